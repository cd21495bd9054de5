r"""Flatness + sliding-mode control on the d-q flat outputs :math:`(\theta, i_d)` (flatstep.model.flat_dq).

The structure of the paper's law (eqs. 12-14, :mod:`flatstep.control.smc`), with :math:`i_d` in place of
:math:`\rho`:

.. math::
    s_1 = i_d - i_d^*,\qquad s_2 = \ddot e + \alpha_2\dot e + \alpha_1 e,\quad e = \theta - \theta^*\\
    \Gamma_1 = \dot i_d^* - W_1\frac{s_1}{|s_1| + \epsilon_1},\qquad
    \Gamma_2 = \theta^{*(3)} - \alpha_2\ddot e - \alpha_1\dot e - W_2\frac{s_2}{|s_2| + \epsilon_2}

and the voltages are the d-q flat inverse (:func:`flatstep.model.flat_dq.dq_voltages`) with
:math:`\dot i_d \to \Gamma_1`, :math:`\theta^{(3)} \to \Gamma_2`, at the measured state and with the rate
:math:`\dot E` of the torques the law knows (:class:`~flatstep.model.torque_model.TorqueModel`). With the exact
model the law gives :math:`\dot s_1 = -W_1 s_1/(|s_1| + \epsilon_1)` and
:math:`\dot s_2 = -W_2 s_2/(|s_2| + \epsilon_2)`. Unlike the paper's pair :math:`(\rho, \theta)` it has no
singularity: no square root, no division by a current, any torque demand is reached through :math:`i_q`.
With :math:`i_d^* = 0` (the default) every ampere makes torque, and the copper loss is that of the torque the
move needs. The gains are :class:`~flatstep.control.smc.SMCGains`, from the same
:func:`~flatstep.loop.design.design_gains` (``W1``, ``eps1`` act on :math:`s_1` in amperes as they do on
:math:`\rho`); the detent hold (``hold_damping``) belongs to the paper's law and is refused here.

Integral action on :math:`s_2` (:class:`DQIntegral`, off by default) adds :math:`-k_i z`, :math:`\dot z = s_2`, to
:math:`\Gamma_2`: inside the boundary layer :math:`\dot s_2 = -\lambda s_2 - k_i z + d`, so a slowly varying
disturbance :math:`d` (the back EMF a wrong :math:`K_m` misses) no longer leaves :math:`s_2 = d/\lambda`.

An online estimate :math:`\hat K_m` of the torque constant (:class:`DQKmAdaptation`, off by default) replaces
:math:`K_m` in the law. With the plant's :math:`K_m` (and :math:`L, J, B` exact) the jerk the law misses is
:math:`J(\theta^{(3)} - \Gamma_2) = (K_m - \hat K_m)\,\phi` along the regressor

.. math::
    \phi = \frac{J\Gamma_2 + B\ddot\theta + \dot E}{\hat K_m} - \frac{\hat K_m\,\omega}{L}

(the q-current rate the law demands less the back EMF's), so
:math:`V = s_2^2/2 + (K_m - \hat K_m)^2/(2\gamma J)` does not grow under
:math:`\dot{\hat K}_m = \gamma\,s_2\,\phi`. The gain is normalized,
:math:`\gamma = r J\lambda/(\phi_0^2 + \phi^2)`, :math:`\lambda = W_2/\epsilon_2`: inside the boundary layer
:math:`s_2 \approx (K_m - \hat K_m)\phi/(J\lambda)`, so the estimate converges at the rate :math:`r` while
:math:`|\phi| \gg \phi_0`. The law evaluates :math:`\phi` along the plan (:math:`\Gamma_2, \ddot\theta, \omega,
\dot E` at :math:`\theta^*` and its derivatives, as a desired-compensation adaptation law does): free of the
measurement's noise, and 0 at rest, where the estimate stops. The demanded rate carries the detent cancellation
:math:`\dot E` at :math:`4N_r\omega`, which keeps :math:`\phi` exciting during the move. With integral action
both take up the back EMF's share at constant speed, where nothing tells them apart, and :math:`\hat K_m` can
drift between them (docs/comparison.md, "The targets").

The angle advance (``advance`` :math:`t_a`, off by default) turns the inverse Park to
:math:`N_r(\theta + \omega t_a)`. A voltage computed at the sample and held over the control period :math:`T_s`
acts on average at the angle the rotor reaches :math:`T_s/2` later; at field-weakening speeds that is a tenth of an
electrical radian (0.22 rad per period at the speed cap of :func:`flatstep.plan.time_optimal_dq.speed_cap`), and
the d-q voltage, dominated there by the back EMF and :math:`N_r\omega L i`, lands partly on the other axis.
:func:`advance_of` gives :math:`T_s/2`, or :math:`3T_s/2` with a period of computation delay.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat_dq import dq_voltages, inverse_park, park
from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.protocol import Plan
from ..validate import check_positive
from .smc import MEASUREMENTS, SMCGains

if TYPE_CHECKING:
    from .build import BuildContext
    from .spec import ControllerSpec

Array = NDArray[np.float64]
#: The paper's gains (Section 3), the default.
PAPER_GAINS = SMCGains()


def _check_period_and_hold(owner: str, control_period: float, v_hold: float) -> None:
    """Raise for a control period or a hold voltage that is not finite and > 0, naming ``owner``'s field."""
    check_positive(f"{owner}.control_period", control_period, unit=" s")
    check_positive(f"{owner}.v_hold", v_hold, unit=" V")


@dataclass(frozen=True)
class DQIntegral:
    """Integral action on ``s2``: ``Gamma2 -= ki z``, ``z += Ts s2`` after each control period.

    ``z`` holds (anti-windup) while ``|s2| > eps2`` (outside the boundary layer, where the law is not linear) and
    while ``hypot(va, vb) > v_hold`` (the bus). :meth:`designed` takes ``ki`` from the design quantities.

    Parameters
    ----------
    ki : float
        The integral gain [1/s^2], > 0.
    control_period : float
        The period ``Ts`` the integral advances by [s], > 0.
    v_hold : float
        The bus voltage the anti-windup knows [V], > 0.
    """

    ki: float
    control_period: float
    v_hold: float

    def __post_init__(self) -> None:
        check_positive("DQIntegral.ki", self.ki, unit=" 1/s^2")
        _check_period_and_hold("DQIntegral", self.control_period, self.v_hold)

    @classmethod
    def designed(cls, gains: SMCGains, control_period: float, v_hold: float) -> "DQIntegral":
        r"""The integral by the cascade's rule: its pole at :math:`\omega_n/4`, beside the boundary layer's.

        Inside the boundary layer :math:`\dot s_2 = -\lambda s_2 - k_i z`, :math:`\lambda = W_2/\epsilon_2`; with
        :math:`k_i = \lambda\,\omega_n/4` its poles are near :math:`\lambda` and :math:`\omega_n/4`, the pole the
        cascade gives its velocity integral (:mod:`flatstep.control.cascade`). An infinite ``v_hold`` (a drive
        without a bus limit) holds only outside the boundary layer.
        """
        return cls(gains.W2 / gains.eps2 * gains.wn / 4, control_period, v_hold if math.isfinite(v_hold) else 1e300)


@dataclass(frozen=True)
class DQKmAdaptation:
    r"""Online estimate of :math:`K_m` (module docstring), projected into ``motor.Km * (1 +- range)``.

    It advances after each control period and holds where the integral holds (:class:`DQIntegral`).

    Parameters
    ----------
    rate : float
        The convergence rate :math:`r` at full excitation [1/s], > 0.
    phi0 : float
        The regressor :math:`\phi_0` below which the estimate slows down [A/s], > 0.
    range : float
        The projection's relative half-width, in (0, 1).
    control_period : float
        The period ``Ts`` the estimate advances by [s], > 0.
    v_hold : float
        The bus voltage the hold knows [V], > 0.
    """

    rate: float
    phi0: float
    range: float
    control_period: float
    v_hold: float

    def __post_init__(self) -> None:
        check_positive("DQKmAdaptation.rate", self.rate, unit=" 1/s")
        check_positive("DQKmAdaptation.phi0", self.phi0, unit=" A/s")
        if not (check_positive("DQKmAdaptation.range", self.range) < 1.0):
            raise ValueError(f"DQKmAdaptation.range={self.range!r} must be in (0, 1): the estimate's relative "
                             "half-width around the nominal Km (0.3 for +-30 %)")
        _check_period_and_hold("DQKmAdaptation", self.control_period, self.v_hold)

    @classmethod
    def designed(cls, motor: MotorParams, plan: Plan, gains: SMCGains, control_period: float,
                 v_hold: float) -> "DQKmAdaptation":
        r"""The estimate at the error dynamics' rate :math:`\omega_n`, excited above a tenth of the peak back EMF.

        :math:`r = \omega_n` (of :math:`\omega_n/4, \omega_n, 4\omega_n`, the one with the smallest worst error on
        the NEMA 17 move of docs/comparison.md), :math:`\phi_0 = 0.1\,K_m\max|\dot\theta^*|/L` (the back-EMF share
        of the regressor at a tenth of the planned peak speed), projected into +-30 %; an infinite ``v_hold`` holds
        only outside the boundary layer.
        """
        speed = float(np.max(np.abs(plan.flag(np.linspace(plan.t0, plan.tf, 401)).dtheta)))
        phi0 = 0.1 * motor.Km * max(speed, 1e-6) / motor.L
        return cls(gains.wn, phi0, 0.3, control_period, v_hold if math.isfinite(v_hold) else 1e300)


def advance_of(control_period: float, compute_delay: bool = False) -> float:
    """The angle advance [s] of a voltage held over ``control_period``: its mean delay.

    ``Ts/2``, or ``3 Ts/2`` with a period of computation delay.
    """
    return (1.5 if compute_delay else 0.5) * check_positive("control_period", control_period, unit=" s")


class DQFlatnessSMC:
    """Flatness-based sliding-mode control of (theta, i_d) along a plan (module docstring).

    Parameters
    ----------
    motor : MotorParams
        The controller's model of the motor.
    plan : Plan
        The planned angle (its ``rho`` is not used).
    gains : SMCGains
        The design constants, as for the paper's law; ``hold_damping`` must be ``None``.
    measurement : str
        Where theta'' comes from: ``"ideal"`` and ``"observer"`` read it from the measurement, ``"model"``
        computes it from the measured state, ``J theta'' = Km i_q - B omega - E``.
    d_current : DCurrentPlan
        The planned d current (default 0).
    torques : TorqueModel
        The torques the law knows beyond eq. (1) (default none).
    integral : DQIntegral or None
        Integral action on ``s2`` (default none: a static law).
    adaptation : DQKmAdaptation or None
        The online estimate of ``Km`` (default none: the law uses ``motor.Km``).
    advance : float
        The angle advance :math:`t_a` [s] of the applied voltage, >= 0 (default 0: the voltage at the measured
        angle; module docstring, :func:`advance_of`).
    """

    #: The C twin: csrc/dq_smc.h.
    c_name = "dq_smc"
    #: The C step's bound on hypot(va, vb) [V].
    c_v_limit = 1e3

    def __init__(self, motor: MotorParams, plan: Plan, gains: SMCGains = PAPER_GAINS,
                 measurement: str = "ideal", *, d_current: DCurrentPlan = ZERO_D_CURRENT,
                 torques: TorqueModel = NO_TORQUES, integral: Optional[DQIntegral] = None,
                 adaptation: Optional[DQKmAdaptation] = None, advance: float = 0.0) -> None:
        if measurement not in MEASUREMENTS:
            raise ValueError(f"measurement={measurement!r} is not a measurement mode; valid: {MEASUREMENTS}")
        if gains.hold_damping is not None:
            raise ValueError(f"gains.hold_damping={gains.hold_damping!r}: the detent hold belongs to the paper's "
                             "(rho, theta) law; the d-q law holds the plan's end point by its sliding surfaces "
                             "(give hold_damping=None)")
        for name, value, kind in (("d_current", d_current, DCurrentPlan), ("torques", torques, TorqueModel)):
            if not isinstance(value, kind):
                raise ValueError(f"{name}={value!r} is not a {kind.__name__}")
        if integral is not None and not isinstance(integral, DQIntegral):
            raise ValueError(f"integral={integral!r} is not a DQIntegral (or None for no integral action)")
        if adaptation is not None and not isinstance(adaptation, DQKmAdaptation):
            raise ValueError(f"adaptation={adaptation!r} is not a DQKmAdaptation (or None for the nominal Km)")
        if isinstance(advance, bool) or not (isinstance(advance, (int, float)) and math.isfinite(advance)
                                             and advance >= 0):
            raise ValueError(f"advance={advance!r} s must be finite and >= 0: the time by which the applied voltage "
                             "leads the measured angle (half the control period for a held voltage, 0 for none)")
        self.advance = float(advance)
        self.motor, self.plan, self.gains, self.measurement = motor, plan, gains, measurement
        self.d_current, self.torques, self.integral, self.adaptation = d_current, torques, integral, adaptation

    def dq_currents(self, x: ArrayLike) -> tuple[Array, Array]:
        """The measured ``(i_d, i_q)``: the Park transform by the measured electrical angle."""
        ia, ib, _, theta = np.asarray(x, dtype=float)
        return park(ia, ib, self.motor.Nr * theta)

    def acceleration(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None,
                     km: Optional[float] = None) -> Array:
        """The acceleration theta'' as the law sees it: the given one, or in ``model`` mode the torque model's.

        ``km`` is the torque constant of the model mode (default ``motor.Km``).
        """
        if self.measurement != "model":
            if ddtheta is None:
                raise ValueError(f"measurement={self.measurement!r} needs the acceleration ddtheta; "
                                 "use measurement='model' to compute it from the state")
            return np.asarray(ddtheta, dtype=float)
        m = self.motor
        _, _, omega, theta = np.asarray(x, dtype=float)
        _, i_q = self.dq_currents(x)
        return ((m.Km if km is None else km) * i_q - m.B * omega - self.torques.torque(t, theta, omega, m.Nr)) / m.J

    def sliding_variables(self, t: ArrayLike, x: ArrayLike,
                          ddtheta: Optional[ArrayLike] = None) -> tuple[Array, Array]:
        """Return ``(s1, s2)`` at times ``t`` for states ``x`` (vectorized)."""
        _, _, omega, theta = np.asarray(x, dtype=float)
        ref = self.plan.flag(t)
        i_d, _ = self.dq_currents(x)
        acc = self.acceleration(t, x, ddtheta)
        g = self.gains
        return (i_d - self.d_current.flag(t, ref.dtheta, ref.ddtheta)[0],
                acc - ref.ddtheta + g.alpha2 * (omega - ref.dtheta) + g.alpha1 * (theta - ref.theta))

    def voltages(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> Array:
        """Phase voltages (va, vb) of the law with the integral at 0 and the nominal Km, vectorized over time."""
        return self._law(t, x, ddtheta, 0.0, self.motor.Km)[0]

    def _law(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike], z: float,
             km: float) -> tuple[Array, Array, Array]:
        """Phase voltages (va, vb), ``s2`` and the regressor ``phi`` at the integral ``z`` and the estimate ``km``.

        In the C step's operation order; ``phi`` is 0 without the adaptation.
        """
        _, _, omega, theta = np.asarray(x, dtype=float)
        g = self.gains
        m = self.motor if km == self.motor.Km else self.motor.replace(Km=km)
        ref = self.plan.flag(t)
        id_ref, did_ref = self.d_current.flag(t, ref.dtheta, ref.ddtheta)
        i_d, i_q = self.dq_currents(x)
        acc = self.acceleration(t, x, ddtheta, km)
        e, de, dde = theta - ref.theta, omega - ref.dtheta, acc - ref.ddtheta
        s1 = i_d - id_ref
        s2 = dde + g.alpha2 * de + g.alpha1 * e
        gamma1 = did_ref - g.W1 * s1 / (np.abs(s1) + g.eps1)
        gamma2 = ref.dddtheta - g.alpha2 * dde - g.alpha1 * de - g.W2 * s2 / (np.abs(s2) + g.eps2)
        if self.integral is not None:
            gamma2 = gamma2 - self.integral.ki * z
        dE = self.torques.torque_rate(t, theta, omega, acc, m.Nr)
        v_d, v_q = dq_voltages(m, i_d, i_q, omega, acc, gamma1, gamma2, dE)
        phi = np.zeros_like(s2)
        if self.adaptation is not None:
            dE_plan = self.torques.torque_rate(t, ref.theta, ref.dtheta, ref.ddtheta, m.Nr)
            phi = (m.J * ref.dddtheta + m.B * ref.ddtheta + dE_plan) / km - km * ref.dtheta / m.L
        angle = m.Nr * (theta + omega * self.advance) if self.advance != 0 else m.Nr * theta
        return np.array(inverse_park(v_d, v_q, angle)), s2, phi

    @property
    def observer_torques(self) -> TorqueModel:
        """The torques the drive loop's observer predicts with: the law's own (the observer shares its model)."""
        return self.torques

    def initial_state(self) -> Any:
        """Return ``None`` for the static law, the integral ``z = 0``, or ``(z, Km^) = (0, motor.Km)`` adapting."""
        if self.adaptation is not None:
            return (0.0, self.motor.Km)
        return None if self.integral is None else 0.0

    def _adapted(self, km: float, s2: float, phi: float) -> float:
        """The estimate after one period of its gradient law along ``phi``, projected (C: dq_smc_adapt)."""
        a, m, g = self.adaptation, self.motor, self.gains
        assert a is not None, "only a law with the adaptation advances Km^"
        gain = a.control_period * a.rate * m.J * g.W2 / g.eps2
        km = km + gain * s2 * phi / (a.phi0 * a.phi0 + phi * phi)
        return min(max(km, m.Km * (1 - a.range)), m.Km * (1 + a.range))

    def step(self, state: Any, measurement: ArrayLike, t: float) -> tuple[Array, Any]:
        """Controller step ``(state, measurement, t) -> (voltages, new state)``.

        The state is None (the static law), the integral ``z``, or ``(z, Km^)`` with the adaptation.
        ``measurement`` is ``(ia, ib, omega, theta, ddtheta)``; ``ddtheta`` is not read in ``model`` mode.
        """
        y = np.asarray(measurement, dtype=float)
        if self.adaptation is None:
            z, km = (0.0 if state is None else float(state)), self.motor.Km
        else:
            z, km = float(state[0]), float(state[1])
        v, s2_, phi_ = self._law(t, y[:4], None if self.measurement == "model" else y[4], z, km)
        if self.integral is None and self.adaptation is None:
            return v, None
        s2, phi, vn = float(s2_), float(phi_), float(np.hypot(*v))
        inside = bool(np.all(np.isfinite(v))) and abs(s2) <= self.gains.eps2
        if self.integral is not None and inside and vn <= self.integral.v_hold:
            z = z + self.integral.control_period * s2
        if self.adaptation is None:
            return v, z
        if inside and vn <= self.adaptation.v_hold:
            km = self._adapted(km, s2, phi)
        return v, (z, km)

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct dq_smc_params`` (csrc/dq_smc.h) for this controller."""
        g = self.gains
        return dict(motor=self.motor.as_dict(), plan=self.plan.c_plan(), current=self.d_current.as_dict(),
                    gains=dict(W1=g.W1, W2=g.W2, eps1=g.eps1, eps2=g.eps2, xi=g.xi, wn=g.wn, hold_damping=0.0),
                    torques=self.torques.as_dict(), measurement=1 if self.measurement == "model" else 0,
                    v_limit=self.c_v_limit,
                    integral={} if self.integral is None else dict(ki=self.integral.ki,
                                                                   Ts=self.integral.control_period,
                                                                   v_hold=self.integral.v_hold),
                    adapt={} if self.adaptation is None else dict(rate=self.adaptation.rate,
                                                                  phi0=self.adaptation.phi0,
                                                                  range=self.adaptation.range,
                                                                  Ts=self.adaptation.control_period,
                                                                  v_hold=self.adaptation.v_hold),
                    advance=self.advance)


def from_spec(spec: ControllerSpec, context: BuildContext) -> DQFlatnessSMC:
    """The d-q law as ``spec`` asks (flatstep.control.spec): the run's gains, known torques, planned d current.

    ``integral`` adds :meth:`DQIntegral.designed` (its pole at ``omega_n/4`` as the cascade's velocity integral,
    held while the bus limits) and ``km_estimate`` :meth:`DQKmAdaptation.designed` (at the integral's rate, held as
    the integral is); both advance by the control period. ``advance`` turns the applied voltage by
    :func:`advance_of` the run's control period (and its computation delay).
    """
    g, v = context.sliding_gains(), context.v_limit
    integral = DQIntegral.designed(g, context.period, v) if spec.integral else None
    adaptation = (DQKmAdaptation.designed(context.motor, context.plan, g, context.period, v)
                  if spec.km_estimate else None)
    advance = advance_of(context.period, context.compute_delay) if spec.advance else 0.0
    return DQFlatnessSMC(context.motor, context.plan, g, context.measurement, torques=context.torques,
                         d_current=context.d_current, integral=integral, adaptation=adaptation, advance=advance)
