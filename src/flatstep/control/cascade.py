r"""Cascaded field-oriented control: PI current loops in d-q, a position-velocity loop with feedforward.

The structure of the common open-source servo firmwares: a proportional position loop gives a velocity
command, a PI velocity loop a torque (q-current) command, and PI loops regulate :math:`i_d \to 0` and
:math:`i_q \to i_q^*` in the rotor frame (Park transform by :math:`N_r\hat\theta`,
:mod:`flatstep.control.loops`); the plan supplies velocity and acceleration feedforward:

.. math::
    \omega_c = \dot\theta^* + k_\theta(\theta^* - \hat\theta),\qquad
    i_q^* = \frac{J\ddot\theta^* + B\dot\theta^*}{K_m} + \frac{J}{K_m}\Big(k_\omega(\omega_c - \hat\omega)
            + k_{i\omega}\int(\omega_c - \hat\omega)\,dt\Big),\qquad i_d^* = 0,

    v_d = \mathrm{PI}(i_d^* - i_d) - L N_r\hat\omega i_q,\qquad
    v_q = \mathrm{PI}(i_q^* - i_q) + L N_r\hat\omega i_d + K_m\hat\omega

(the last terms decouple the axes and cancel the back-emf, as the firmwares' optional feedforwards do).

**Tuning.** Current PIs by pole-zero cancellation at :math:`\omega_c = \lambda = 0.3/T_s`, the sliding
controller's inner bandwidth. With an ideal current loop the mechanical error obeys
:math:`s^3 + k_\omega s^2 + (k_\omega k_\theta + k_{i\omega})s + k_{i\omega}k_\theta`; a P-PI cascade can place
its three poles only where :math:`(k_\omega k_\theta + k_{i\omega})^2 \ge 4k_\omega k_{i\omega}k_\theta`, and the
fastest such set with a double pole at :math:`w` is :math:`\{w, w, w/4\}` (the integrator's pole, a quarter
of the bandwidth, the usual rule): :math:`k_\omega = 2.25w`, :math:`k_\theta = w/3`,
:math:`k_{i\omega} = 0.75w^2`, with :math:`w = \omega_n = \lambda/4`, the sliding controller's error
bandwidth. Anti-windup: every integrator holds while the bus limits.

**In the plan's frame** (``plan_frame``): the current loops regulate :math:`i_d, i_q` in the frame of the plan's
angle, Park by :math:`N_r\theta^*` rather than :math:`N_r\hat\theta`, with :math:`i_d^* = h\rho^*(t)`, a share
:math:`h` (``d_hold``, default 1) of the plan's current held on the d axis, as the paper's law holds it. The torque
is then :math:`K_m(i_q\cos N_r\delta + i_d\sin N_r\delta)` with :math:`\delta = \theta^* - \theta`: the held
current answers an angle error at once, a spring of stiffness :math:`K_m h\rho^* N_r` that needs neither the
measurement nor the loops (no sampling or computation delay in it), while the P-PI loop and the q current do what
they do without it. The decoupling uses the frame's speed :math:`N_r\dot\theta^*`, the back EMF
:math:`K_m\hat\omega(-\sin N_r(\hat\theta - \theta^*), \cos N_r(\hat\theta - \theta^*))` in that frame, and the
voltage feedforward adds :math:`R i_d^* + L\,di_d^*/dt` on d. The price is the held current's copper.

**Anti-cogging** (``torques``, a :class:`~flatstep.model.torque_model.TorqueModel`, as servo firmwares calibrate
it): the known torques :math:`E(t, \hat\theta, \hat\omega)` (detent, friction, load) join the q-current command,
:math:`i_q^* \mathrel{+}= E/K_m`, tracked through the current loop; none by default. As in firmware the drive's
observer does not know them; ``model_observer=True`` gives them to the observer too, as the flatness laws do.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import DCurrentPlan
from ..plan.protocol import Plan
from ..validate import InputError, check_finite, check_positive
from .feedforward import reference
from .loops import BaselineController, PIGains, bus_scale, inverse_park, park, pi_integrate, pi_output

if TYPE_CHECKING:
    from .build import BuildContext
    from .spec import ControllerSpec

#: The rule of the cascade in the plan's frame (:func:`plan_frame_rule`): the current loops' speed
#: :math:`\lambda T_s`, the outer bandwidth's cap :math:`w T_s`, the position and integral gains over that bandwidth
#: (:math:`k_\theta/w`, :math:`k_{i\omega}/w^2`), the velocity gain's two bounds (:math:`k_\omega T_s`, and the
#: current one count per period of speed error may ask, in shares of :math:`\rho^*`), the share of
#: :math:`\rho^*` held on d, the least sampling cap ratio :math:`r` the loops' take-over follows, the powers of
#: :math:`1/r` by which the current loops' speed and the position gain rise and of :math:`r` by which the velocity
#: integral falls there, and the current loops' fastest :math:`\lambda T_s`.
PLAN_FRAME_RULE = dict(lambda_ts=0.895, w_ts=0.0871, k_omega_ts=0.5, k_omega_count=2.0, k_theta=1.28, ki_omega=1.60,
                       d_hold=0.535, r_min=0.5, follow_current=2.0, follow_position=1.5, integral_fall=6.0,
                       lambda_ts_max=1.79)
#: The share of the bus the plan-frame rule's feedforward may take with its held current (:func:`plan_frame_rule`).
HOLD_VOLTAGE_SHARE = 0.75


@dataclass(frozen=True)
class CascadeGains:
    r"""Gains of the cascade: the current loops' bandwidth and the P-PI loop's gains.

    By default the P-PI loop's gains follow the rule of the module docstring from its bandwidth
    ``position_bandwidth`` :math:`w` (poles :math:`w, w, w/4`); any of ``k_theta``, ``k_omega``, ``ki_omega``
    given replaces its rule's value, so that the three poles are free.

    Parameters
    ----------
    current_bandwidth : float
        :math:`\omega_c` [rad/s] of the d-q current PIs (pole-zero cancellation), > 0.
    position_bandwidth : float
        :math:`w` [rad/s] of the rule, > 0.
    decoupling : bool
        Cancel the axes' coupling and the back EMF at the measured speed (default on).
    k_theta, k_omega, ki_omega : float, optional
        Position gain [1/s] (> 0; rule :math:`w/3`), velocity gain [1/s] (> 0; rule :math:`2.25w`), velocity
        integral gain [1/s^2] (>= 0; rule :math:`0.75w^2`).
    voltage_feedforward : bool
        Add the voltage of the q current the plan needs, :math:`R i_q^{ff} + L\,di_q^{ff}/dt` (module docstring;
        default off).
    plan_frame : bool
        Regulate the currents in the plan's frame with :math:`i_d^* = h\rho^*` (module docstring; default off).
    d_hold : float
        :math:`h`, the share of the plan's :math:`\rho^*` held on d with ``plan_frame`` (>= 0, default 1).
    """

    current_bandwidth: float
    position_bandwidth: float
    decoupling: bool = True
    k_theta: Optional[float] = None
    k_omega: Optional[float] = None
    ki_omega: Optional[float] = None
    voltage_feedforward: bool = False
    plan_frame: bool = False
    d_hold: float = 1.0

    def __post_init__(self) -> None:
        for name in ("current_bandwidth", "position_bandwidth"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name), unit=" rad/s"))
        w = self.position_bandwidth
        for name, rule, unit in (("k_theta", w / 3.0, " 1/s"), ("k_omega", 2.25 * w, " 1/s")):
            value = getattr(self, name)
            object.__setattr__(self, name, rule if value is None else check_positive(name, value, unit=unit))
        ki = 0.75 * w**2 if self.ki_omega is None else check_finite("ki_omega", self.ki_omega)
        if ki < 0:
            raise InputError("ki_omega", ki, f"ki_omega={ki!r} 1/s^2 must be >= 0 (0: no velocity integral)")
        object.__setattr__(self, "ki_omega", ki)
        hold = check_finite("d_hold", self.d_hold)
        if hold < 0:
            raise InputError("d_hold", hold, f"d_hold={hold!r} must be >= 0 (the share of the plan's rho* held on d)")
        object.__setattr__(self, "d_hold", hold)
        for name in ("decoupling", "voltage_feedforward", "plan_frame"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(name, getattr(self, name), f"{name}={getattr(self, name)!r} is not true or false")

    def loop_gains(self) -> tuple[float, float, float]:
        """``(k_theta, k_omega, ki_omega)`` of the P-PI loop."""
        return float(self.k_theta or 0.0), float(self.k_omega or 0.0), float(self.ki_omega or 0.0)

    def as_dict(self) -> dict[str, Any]:
        """The bandwidths, the switches and the loop gains, for JSON."""
        return asdict(self)


class CascadeFOC(BaselineController[CascadeGains]):
    """Cascaded P-PI position-velocity loop over d-q PI current loops, with feedforward from the plan.

    Parameters
    ----------
    motor : MotorParams
        The controller's nominal model.
    plan : Plan
        The move.
    gains : CascadeGains
        The bandwidths of the loops.
    control_period : float
        Ts [s].
    measurement : str
        Where speed and angle come from (``"observer"``, ``"model"``: encoder and its difference,
        ``"ideal"``), as for :class:`~flatstep.control.smc.FlatnessSMC`; the acceleration is not used.
    v_limit : float
        The bus voltage its anti-windup knows [V].
    torques : TorqueModel
        The anti-cogging: the known torques that join the q-current command (default none).
    model_observer : bool
        Give ``torques`` to the drive loop's observer as well (default: no, as firmware does).
    """

    #: The C twin: csrc/cascade.h.
    c_name = "cascade"
    #: Ts [s]: the cascade is a sampled law, never continuous (the base class allows ``None``).
    control_period: float

    def __init__(self, motor: MotorParams, plan: Plan, gains: CascadeGains, *, control_period: float,
                 measurement: str = "observer", v_limit: float = math.inf, torques: TorqueModel = NO_TORQUES,
                 model_observer: bool = False) -> None:
        super().__init__(motor, plan, gains, measurement=measurement, control_period=control_period,
                         v_limit=v_limit)
        if not isinstance(torques, TorqueModel):
            raise ValueError(f"torques={torques!r} is not a TorqueModel")
        self.torques, self.model_observer = torques, bool(model_observer)
        self.pi = PIGains.current_loop(motor, gains.current_bandwidth)
        self.k_theta, k_omega, ki_omega = gains.loop_gains()
        self.pi_omega = PIGains(k_omega, ki_omega)

    @property
    def observer_torques(self) -> Optional[TorqueModel]:
        """The torques the drive loop's observer predicts with: ``torques`` with ``model_observer``, else none."""
        return self.torques if self.model_observer else None

    def initial_state(self) -> NDArray[np.float64]:
        """Integrals (velocity loop [rad/s^2], d and q current loops [V]), all zero.

        The loops start from the plan's start equilibrium and bring its d current to 0.
        """
        return np.zeros(3)

    def step(self, state: Optional[ArrayLike], measurement: ArrayLike,
             t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One period of the cascade; ``measurement = (ia, ib, omega, theta, ddtheta)``."""
        m, g, Ts = self.motor, self.gains, self.control_period
        integral = self.initial_state() if state is None else np.asarray(state, dtype=float)
        ia, ib, omega, theta = np.asarray(measurement, dtype=float)[:4]
        ref = self.plan.flag(t)
        e_omega = float(ref.dtheta + self.k_theta * (ref.theta - theta) - omega)
        accel = pi_output(self.pi_omega, e_omega, integral[0])
        known = float(self.torques.torque(t, theta, omega, m.Nr))  # the anti-cogging (and friction, load) torque
        iq_ref = (m.J * ref.ddtheta + m.B * ref.dtheta + m.J * accel + known) / m.Km
        id_ref, w_frame, sd, cd = 0.0, omega, 0.0, 1.0
        p = m.Nr * (ref.theta if g.plan_frame else theta)
        if g.plan_frame:  # the plan's frame: d holds a share of rho*, the back EMF at the angle error
            id_ref, w_frame = g.d_hold * float(ref.rho), float(ref.dtheta)
            sd, cd = math.sin(m.Nr * (theta - ref.theta)), math.cos(m.Nr * (theta - ref.theta))
        i_d, i_q = park(ia, ib, p)
        e_i = np.array([id_ref - i_d, iq_ref - i_q], dtype=float)
        v_dq = pi_output(self.pi, e_i, integral[1:])
        if g.decoupling:
            v_dq = v_dq + np.array([-m.L * m.Nr * w_frame * i_q - m.Km * omega * sd,
                                    m.L * m.Nr * w_frame * i_d + m.Km * omega * cd])
        if g.voltage_feedforward:
            v_dq = v_dq + np.array([g.d_hold * (m.R * float(ref.rho) + m.L * float(ref.drho)) if g.plan_frame
                                    else 0.0, self.reference_voltage(t)])
        v = np.array(inverse_park(v_dq[0], v_dq[1], p))
        hold = bus_scale(v, self.v_limit) < 1.0
        new = np.concatenate([[pi_integrate(self.pi_omega, e_omega, integral[0], Ts, hold)],
                              pi_integrate(self.pi, e_i, integral[1:], Ts, hold)])
        return v, new

    def reference_voltage(self, t: float) -> float:
        r"""The voltage of the q current the plan needs, :math:`R i_q^{ff} + L\,di_q^{ff}/dt` [V] at time ``t``.

        :math:`i_q^{ff} = (J\ddot\theta^* + B\dot\theta^* + E^*)/K_m` with the known torques along the plan
        (:func:`flatstep.control.feedforward.reference` in d-q).
        """
        ref = reference(self.plan, self.motor, t, torques=self.torques, frame="dq")
        return float(self.motor.R * ref.currents[1] + self.motor.L * ref.current_rates[1])

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct cascade_params`` (csrc/cascade.h)."""
        g = self.gains
        k_theta, k_omega, ki_omega = g.loop_gains()
        return dict(motor=self.motor.as_dict(), plan=self.plan.c_plan(),
                    gains=dict(current_bandwidth=g.current_bandwidth, k_theta=k_theta, k_omega=k_omega,
                               ki_omega=ki_omega, decoupling=g.decoupling,
                               voltage_feedforward=g.voltage_feedforward, plan_frame=g.plan_frame,
                               d_hold=g.d_hold), torques=self.torques.as_dict(),
                    Ts=self.control_period, v_limit=self.v_limit)


def plan_frame_rule(context: BuildContext) -> dict[str, float]:
    r"""The rule gains of the cascade in the plan's frame, from the control period, the plan and the model.

    The current loops at :math:`\lambda = 0.895/T_s` (``lambda_ts`` replaces 0.895; a computation delay doubles
    :math:`T_s` here, in every bound below), a share :math:`h = 0.535` of the plan's largest :math:`\rho^*` held on
    d (less where the bus is short: :func:`held_share`), and the P-PI loop over the bandwidth

    .. math:: w = \min\left(\frac{0.0871}{T_s},\ \omega_s\right),\qquad
              \omega_s = \sqrt{\frac{K_m h \rho^*_{max} N_r}{J}},

    the held current's spring frequency (its stiffness over the inertia) capped by what the sampling allows:
    :math:`k_\theta = 1.28w`, :math:`k_{i\omega} = 1.60w^2`. Where the sampling caps the loop below the spring,
    :math:`r = 0.0871/(T_s\omega_s) < 1` (else :math:`r = 1`), the spring takes over what the loop loses: the held
    share rises to :math:`h/r^2` (at most 1: the spring's frequency rises by :math:`1/r`), the velocity
    integral falls to :math:`k_{i\omega} = 1.60\,w^2 \bar r^6` with :math:`\bar r = \max(r, 0.5)` (the floor
    ``r_min``), and the loops that act through the spring follow it, the current loops' speed (``lambda_ts``'s too)
    rising by :math:`1/\bar r^2` and the position gain by :math:`1/\bar r^{1.5}`:
    :math:`\lambda = \min(0.895/\bar r^2,\ 1.79)/T_s` (1.79: the current loop's discrete pole, about
    :math:`1 - \lambda T_s`, kept inside the unit circle) and :math:`k_\theta = 1.28\,w/\bar r^{1.5}`.
    The velocity gain has its own bounds,

    .. math:: k_\omega = \min\left(\frac{0.5}{T_s},\ 2\,\frac{K_m\rho^*_{max}}{J}\,\frac{T_s}{q}\right),

    half the sampling rate, or less where a speed error of one encoder count :math:`q` per period would ask more
    than twice the plan's current of the q loop (:math:`J k_\omega q / (K_m T_s) \le 2\rho^*`; ``angle_step``
    of the context, without which only the first bound holds). Every figure is :data:`PLAN_FRAME_RULE`;
    docs/comparison.md ("The default controller") says where they come from and what they give on scenarios they
    were and were not chosen on. ``bandwidth_scale`` multiplies every gain's bandwidth.
    """
    r, m, Ts = PLAN_FRAME_RULE, context.motor, context.period * (2.0 if context.compute_delay else 1.0)
    scale = context.bandwidth_scale
    rho = float(np.max(np.abs(context.plan.flag(np.array([context.plan.t0, context.plan.tf])).rho)))
    spring = math.sqrt(m.Km * r["d_hold"] * max(rho, 1e-12) * m.Nr / m.J)
    short = min(1.0, r["w_ts"] / Ts / spring)  # < 1 where the sampling caps the loop below the spring
    capped = max(short, r["r_min"])  # the current loops and the position gain follow the spring, the integral falls
    lam_ts = context.lambda_ts if context.lambda_ts is not None else r["lambda_ts"]
    lam = min(lam_ts / capped ** r["follow_current"], max(lam_ts, r["lambda_ts_max"])) / Ts
    hold = held_share(context, rho, min(1.0, r["d_hold"] / short**2))
    w = scale * min(r["w_ts"] / Ts, spring)
    k_omega = r["k_omega_ts"] / Ts
    if context.angle_step > 0.0:  # one count per period of speed error asks at most k_omega_count rho* of current
        k_omega = min(k_omega, r["k_omega_count"] * m.Km * max(rho, 1e-12) * Ts / (m.J * context.angle_step))
    return dict(current_bandwidth=scale * lam, position_bandwidth=w, k_omega=scale * k_omega,
                k_theta=r["k_theta"] * w / capped ** r["follow_position"],
                ki_omega=r["ki_omega"] * w ** 2 * capped ** r["integral_fall"], d_hold=hold)


def held_share(context: BuildContext, rho: float, h0: Optional[float] = None) -> float:
    r"""The share of ``rho`` [A] the plan-frame rule holds on d: ``h0``, less where the bus is short.

    The largest of :math:`h_0, 0.9h_0, \ldots, 0` (:math:`h_0` default the rule's ``d_hold``) whose feedforward phase
    voltages along the move (:func:`~flatstep.control.feedforward.reference` with :math:`i_d^* = h\rho`, the known
    torques) stay within :data:`HOLD_VOLTAGE_SHARE` of the bus: the held current may not take the voltage the
    move needs. Without a bus limit, :math:`h_0`.
    """
    h0 = PLAN_FRAME_RULE["d_hold"] if h0 is None else h0
    limit = HOLD_VOLTAGE_SHARE * context.v_limit
    if not math.isfinite(limit):
        return h0
    plan = context.plan
    t = np.linspace(plan.t0, plan.tf, 401)
    for h in h0 * np.linspace(1.0, 0.0, 11):
        d = DCurrentPlan(h * rho, h * rho, plan.t0, plan.tf)
        ref = reference(plan, context.motor, t, torques=context.torques, frame="ab", d_current=d)
        if float(np.max(np.abs(ref.voltages))) <= limit:
            return float(h)
    return 0.0


def from_spec(spec: ControllerSpec, context: BuildContext) -> CascadeFOC:
    """The cascade as ``spec`` asks (flatstep.control.spec), tuned by rule (:mod:`flatstep.control.build`).

    Current loops at ``lambda``, the P-PI loop by the rule at ``w = omega_n``, any of :class:`CascadeGains`'s fields
    given in ``context.law_gains`` over them; ``feedforward`` is the anti-cogging (the known torques in the q-current
    command), ``observer_torques`` gives them to the observer too, ``voltage_feedforward`` adds the voltage of the
    planned q current (with those torques along the plan), ``plan_frame`` runs the current loops in the plan's frame
    with a share ``d_hold`` of rho* held on d, and then its gains follow :func:`plan_frame_rule`.
    """
    if spec.plan_frame:
        rule = plan_frame_rule(context)
    else:
        lam, wn = context.bandwidths()
        rule = dict(current_bandwidth=lam, position_bandwidth=wn)
    gains = context.gains(CascadeGains, rule,
                          dict(voltage_feedforward=spec.voltage_feedforward, plan_frame=spec.plan_frame))
    return CascadeFOC(context.motor, context.plan, gains, control_period=context.period,
                      measurement=context.measurement, v_limit=context.v_limit, torques=context.torques,
                      model_observer=spec.observer_torques)
