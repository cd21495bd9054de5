r"""The paper's flatness + sliding-mode law, eqs. (12)-(14), corrected, with the boundary layer of Section 3.

.. math::
    s_1 = \rho - \rho^*,\qquad s_2 = \ddot e + \alpha_2\dot e + \alpha_1 e,\quad e = \theta - \theta^*\\
    \Gamma_1 = \dot\rho^* - W_1\frac{s_1}{|s_1| + \epsilon_1},\qquad
    \Gamma_2 = \theta^{*(3)} - \alpha_2\ddot e - \alpha_1\dot e - W_2\frac{s_2}{|s_2| + \epsilon_2}

and the voltages are the flat inverse (eq. 9) with :math:`\dot\rho \to \Gamma_1`,
:math:`\theta^{(3)} \to \Gamma_2`, evaluated at the measured state (:func:`flatstep.model.flat.flat_voltages`).

**Known torques** (``torques``, a :class:`~flatstep.model.torque_model.TorqueModel`, not in the paper). The
torques :math:`E` it knows beyond eq. (1) (detent, Coulomb friction, a known load) enter the flat inverse as
:math:`A = J\ddot\theta + B\dot\theta + E` and :math:`J\theta^{(3)} + B\ddot\theta \to J\Gamma_2 + B\ddot\theta +
\dot E`, and the ``model`` acceleration as :math:`J\ddot\theta = K_m(i_b\cos N_r\theta - i_a\sin N_r\theta) -
B\dot\theta - E`: the law then cancels them before they show as an error. With no torques (the default) the law is
eqs. (12)-(14) bit for bit.

**Hold** (``SMCGains.hold_damping``, not in the paper). On a quantized encoder the law above, fed by an
observer, hunts across a count edge at rest (docs/drive.md, "Standstill"). With ``hold_damping`` = zeta, from
``plan.tf`` on the law pins the current vector at the electrical angle of the target, the magnetic detent of
:math:`\theta_2` (stiffness :math:`K = K_m\rho_2 N_r`), turned by a damping torque on the measured speed:

.. math::
    \tau = -2\zeta\sqrt{K J}\,\dot\theta,\qquad
    i^* = \rho_2\begin{bmatrix}\cos p\\ \sin p\end{bmatrix},\quad
    p = N_r\theta_2 + \arcsin\!\big(\mathrm{clip}(\tau / K_m\rho_2, \pm 1)\big),

    v = R\,i^* + L\lambda\,(i^* - i) + K_m\dot\theta\begin{bmatrix}-\sin N_r\theta\\ \cos N_r\theta\end{bmatrix},
    \qquad \lambda = W_1/\epsilon_1

(the current loop at the rate of the :math:`s_1` boundary layer, with the back EMF cancelled). The position
error then no longer feeds an integrator, so the quantization cannot drive a limit cycle; a load torque
:math:`\tau_L` costs the static error :math:`\tau_L / K`. With known torques the hold turns the current vector
by their load angle at rest, so that the known part of the load costs nothing:

.. math::
    p = N_r\theta_2 + \arcsin\!\big(\mathrm{clip}(E(t, \theta_2, 0) / K_m\rho_2, \pm 1)\big)
    + \arcsin\!\big(\mathrm{clip}(\tau / K_m\rho_2, \pm 1)\big)

(:math:`E` the known torque on the target at rest: the detent there, the load; Coulomb friction is 0 at rest).
Without torques the first arcsine is 0 and the hold is the one above bit for bit.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat import FlatFlag, flat_voltages, polar
from ..model.motor import MotorParams
from ..model.motor import acceleration as motor_acceleration
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.loss_aware import LossAwareRho
from ..plan.protocol import Plan
from ..validate import InputError, check_finite, check_quantity
from .protocol import check_parts

if TYPE_CHECKING:
    from .build import BuildContext
    from .spec import ControllerSpec

MEASUREMENTS = ("ideal", "model", "observer")
#: The damping ratio of the detent hold (the ``hold`` option) when the run's gains give none: critical
#: damping of the magnetic spring (docs/comparison.md, "At rest on the paper's move").
REST_HOLD_DAMPING = 1.0


@dataclass(frozen=True)
class SMCGains:
    """Design constants of the controller; defaults are the paper's (Section 3)."""

    W1: float = 100.0
    W2: float = 100.0
    eps1: float = 0.005
    eps2: float = 0.005
    xi: float = 0.8
    wn: float = 10.0
    #: damping ratio of the detent hold from ``plan.tf`` on (module docstring); ``None``: track to the end
    hold_damping: Optional[float] = None

    def __post_init__(self) -> None:
        for name in ("W1", "W2", "eps1", "eps2", "wn"):
            object.__setattr__(self, name, check_quantity("gain", getattr(self, name), as_name=name))
        if self.hold_damping is not None:
            object.__setattr__(self, "hold_damping",
                               check_quantity("damping", self.hold_damping, as_name="hold_damping"))
        xi = check_finite("xi", self.xi)
        if xi <= 0:
            raise InputError("xi", xi,
                             f"xi={xi!r} must be > 0 for the error dynamics e'' + 2 xi wn e' + wn^2 e = 0 to be stable")
        object.__setattr__(self, "xi", check_quantity("damping", xi, as_name="xi"))

    @property
    def alpha1(self) -> float:
        r""":math:`\alpha_1 = \omega_n^2`."""
        return self.wn**2

    @property
    def alpha2(self) -> float:
        r""":math:`\alpha_2 = 2\xi\omega_n`."""
        return 2 * self.xi * self.wn

    def as_dict(self) -> dict[str, float]:
        """The design constants by name, for JSON."""
        return asdict(self)


class FlatnessSMC:
    """Flatness-based sliding-mode controller tracking any plan (:class:`~flatstep.plan.protocol.Plan`).

    Parameters
    ----------
    motor : MotorParams
        The controller's model of the motor (may differ from the plant's).
    plan : Plan
        The planned flat-output trajectory, any :class:`~flatstep.plan.protocol.Plan` (the hold targets its
        end points).
    gains : SMCGains
        The design constants (default: the paper's).
    measurement : str
        Where theta'' comes from. ``"ideal"``: the true acceleration, passed by the simulator (the paper's
        assumption); ``"model"``: computed from the measured state by the zero-load model,
        ``J theta'' = Km (ib cos Nr theta - ia sin Nr theta) - B omega``; ``"observer"``: the estimate of a
        :class:`~flatstep.loop.observers.Observer`, passed by the simulator like the ideal one.
    torques : TorqueModel
        The torques the law knows beyond eq. (1) (module docstring; default none).
    loss_aware : LossAwareRho, optional
        Track the loss-aware ``rho*(t)`` (:mod:`flatstep.plan.loss_aware`) instead of the plan's ``rho``.
    """

    #: The C twin: csrc/smc.h (``struct smc``, ``smc_init``, ``smc_controller``).
    c_name = "smc"
    #: The C step's guards: bound on hypot(va, vb) [V] and smallest current norm acted on [A].
    c_v_limit, c_rho_min = 1e3, 1e-6

    def __init__(self, motor: MotorParams, plan: Plan, gains: SMCGains = SMCGains(),
                 measurement: str = "ideal", *, torques: TorqueModel = NO_TORQUES,
                 loss_aware: Optional[LossAwareRho] = None) -> None:
        if measurement not in MEASUREMENTS:
            raise ValueError(f"measurement={measurement!r} is not a measurement mode; valid: {MEASUREMENTS}")
        check_parts(motor, plan, gains, SMCGains)
        if not isinstance(torques, TorqueModel):
            raise ValueError(f"torques={torques!r} is not a TorqueModel")
        self.motor, self.plan, self.gains, self.measurement = motor, plan, gains, measurement
        if loss_aware is not None and not isinstance(loss_aware, LossAwareRho):
            raise ValueError(f"loss_aware={loss_aware!r} is not a LossAwareRho (or None)")
        self.torques, self.loss_aware = torques, loss_aware

    def reference(self, t: ArrayLike) -> FlatFlag:
        """The flat flag the law tracks at times ``t``: the plan's, with the loss-aware ``rho*`` if chosen."""
        ref = self.plan.flag(t)
        if self.loss_aware is None:
            return ref
        rho, drho = self.loss_aware.reference(ref, t, self.motor, self.torques)
        return ref._replace(rho=rho, drho=drho)

    def acceleration(self, x: ArrayLike, ddtheta: Optional[ArrayLike] = None,
                     t: ArrayLike = 0.0) -> NDArray[np.float64]:
        """The acceleration theta'' as the controller sees it.

        The given ``ddtheta`` in ``ideal`` and ``observer`` mode; in ``model`` mode the model of the measured state
        under the known torques at time ``t``, :func:`flatstep.model.motor.acceleration` with load ``E``.
        """
        if self.measurement != "model":
            if ddtheta is None:
                raise ValueError(f"measurement={self.measurement!r} needs the acceleration ddtheta; "
                                 "use measurement='model' to compute it from the state")
            return np.asarray(ddtheta, dtype=float)
        _, _, omega, theta = np.asarray(x, dtype=float)
        return motor_acceleration(x, self.motor, self.torques.torque(t, theta, omega, self.motor.Nr))

    def sliding_variables(self, t: ArrayLike, x: ArrayLike,
                          ddtheta: Optional[ArrayLike] = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Return ``(s1, s2)`` of eq. (12) at times ``t`` for states ``x`` (vectorized)."""
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        ref = self.reference(t)
        acc = self.acceleration(x, ddtheta, t)
        g = self.gains
        return (np.hypot(ia, ib) - ref.rho,
                acc - ref.ddtheta + g.alpha2 * (omega - ref.dtheta) + g.alpha1 * (theta - ref.theta))

    def voltages(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """Phase voltages (va, vb) of eqs. (13)-(14), vectorized over time."""
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        m, g = self.motor, self.gains
        ref = self.reference(t)
        rho, phi = polar(ia, ib)
        acc = self.acceleration(x, ddtheta, t)
        e, de, dde = theta - ref.theta, omega - ref.dtheta, acc - ref.ddtheta
        s1 = rho - ref.rho
        s2 = dde + g.alpha2 * de + g.alpha1 * e
        gamma1 = ref.drho - g.W1 * s1 / (np.abs(s1) + g.eps1)
        gamma2 = ref.dddtheta - g.alpha2 * dde - g.alpha1 * de - g.W2 * s2 / (np.abs(s2) + g.eps2)
        E, dE = self.torques.torque(t, theta, omega, m.Nr), self.torques.torque_rate(t, theta, omega, acc, m.Nr)
        v = flat_voltages(m, rho, gamma1, theta, omega, acc, gamma2 + dE / m.J, phi, m.J * acc + m.B * omega + E)
        if g.hold_damping is None:
            return v
        return np.where(np.asarray(t) >= self.plan.tf, self.hold_voltages(ia, ib, omega, theta, t), v)

    def hold_currents(self, omega: ArrayLike, t: ArrayLike = 0.0) -> NDArray[np.float64]:
        """The detent hold's current vector ``(ia*, ib*)`` at the measured speed and time ``t`` (vectorized).

        The module docstring gives the law; ``t`` matters only for known torques that change in time.
        """
        m, rho2, Nr, zeta = self.motor, self.plan.rho2, self.motor.Nr, self.gains.hold_damping
        assert zeta is not None, "hold_currents needs gains.hold_damping (the hold is off without it)"
        # sin p = s, cos p by the angle additions on N_r theta2 and the load angle, as csrc/smc.c computes them
        s = np.clip(-2.0 * zeta * np.sqrt(m.J * Nr / (m.Km * rho2)) * np.asarray(omega), -1.0, 1.0)
        c = np.sqrt(1.0 - s * s)
        s2, c2 = np.sin(Nr * self.plan.theta2), np.cos(Nr * self.plan.theta2)
        if self.torques != NO_TORQUES:  # the load angle of the known torque on theta2 at rest (no Coulomb term)
            sl = np.clip(self.torques.torque(t, self.plan.theta2, 0.0, Nr) / (m.Km * rho2), -1.0, 1.0)
            cl = np.sqrt(1.0 - sl * sl)
            s2, c2 = s2 * cl + c2 * sl, c2 * cl - s2 * sl
        return rho2 * np.array([c2 * c - s2 * s, s2 * c + c2 * s])

    def hold_voltages(self, ia: ArrayLike, ib: ArrayLike, omega: ArrayLike, theta: ArrayLike,
                      t: ArrayLike = 0.0) -> NDArray[np.float64]:
        """The detent hold's voltages (module docstring) for measured currents, speed, angle, time (vectorized)."""
        m, g = self.motor, self.gains
        ia_ref, ib_ref = self.hold_currents(omega, t)
        lam, emf, Nr_theta = g.W1 / g.eps1, m.Km * np.asarray(omega), m.Nr * np.asarray(theta)
        return np.array([m.R * ia_ref + m.L * lam * (ia_ref - ia) - emf * np.sin(Nr_theta),
                         m.R * ib_ref + m.L * lam * (ib_ref - ib) + emf * np.cos(Nr_theta)])

    @property
    def observer_torques(self) -> TorqueModel:
        """The torques the drive loop's observer predicts with: the law's own (the observer shares its model)."""
        return self.torques

    def initial_state(self) -> None:
        """Return ``None``: the law is static, no state between steps."""
        return None

    def step(self, state: None, measurement: ArrayLike, t: float) -> tuple[NDArray[np.float64], None]:
        """Controller step ``(state, measurement, t) -> (voltages, new state)``; this law is static.

        ``measurement`` is ``(ia, ib, omega, theta, ddtheta)``; ``ddtheta`` is not read in ``model`` mode.
        """
        y = np.asarray(measurement, dtype=float)
        return self.voltages(t, y[:4], None if self.measurement == "model" else y[4]), state

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct smc_params`` (csrc/smc.h) for this controller."""
        g = self.gains
        return dict(motor=self.motor.as_dict(), plan=self.plan.c_plan(),
                    gains=dict(W1=g.W1, W2=g.W2, eps1=g.eps1, eps2=g.eps2, xi=g.xi, wn=g.wn,
                               hold_damping=g.hold_damping or 0.0),
                    # "ideal" and "observer" both read theta'' from y[4]; only "model" computes it from the state
                    measurement=1 if self.measurement == "model" else 0, torques=self.torques.as_dict(),
                    loss_aware=self.loss_aware.as_dict() if self.loss_aware else dict(margin=0.0, rho_hold=0.0),
                    v_limit=self.c_v_limit, rho_min=self.c_rho_min)


def from_spec(spec: ControllerSpec, context: BuildContext) -> FlatnessSMC:
    """The paper's law as ``spec`` asks (flatstep.control.spec): the run's gains, known torques, rho plan, hold.

    ``hold`` pins the detent from tf on with ``smc_gains.hold_damping`` (or :data:`REST_HOLD_DAMPING`), turned by
    the known torques' load angle on the target; ``rho_plan="loss_aware"`` tracks the loss-aware rho*(t)
    (``context.loss_aware``, default ``LossAwareRho.for_plan(plan)``).
    """
    gains = context.sliding_gains()
    if spec.hold and gains.hold_damping is None:
        gains = replace(gains, hold_damping=REST_HOLD_DAMPING)
    loss_aware = None
    if spec.rho_plan == "loss_aware":
        loss_aware = context.loss_aware or LossAwareRho.for_plan(context.plan)
    return FlatnessSMC(context.motor, context.plan, gains, context.measurement, torques=context.torques,
                       loss_aware=loss_aware)
