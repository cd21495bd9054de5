r"""Open-loop microstepping, as a current-controlled stepper driver does it: no position feedback.

The driver turns the commanded angle :math:`\theta^*(t)` of the plan into sine/cosine current references at
the run current :math:`\rho^*` (the plan's current norm),

.. math::
    i_a^* = \rho^*\cos N_r\theta^*,\qquad i_b^* = \rho^*\sin N_r\theta^*,

whose stable rest angle is :math:`\theta^*` (the rotor aligns with the current vector, eq. (2) corrected,
docs/paper-notes.md), and tracks them with one PI loop per phase in the stationary a-b frame, tuned by
pole-zero cancellation at the current bandwidth :math:`\omega_c` (:class:`~flatstep.control.loops.PIGains`),
plus the feedforward of its own reference, :math:`v = R i^* + L\,di^*/dt + \mathrm{PI}(i^* - i)`:

.. math:: \frac{di_a^*}{dt} = \dot\rho^*\cos N_r\theta^* - N_r\dot\theta^*\rho^*\sin N_r\theta^*,\qquad
          \frac{di_b^*}{dt} = \dot\rho^*\sin N_r\theta^* + N_r\dot\theta^*\rho^*\cos N_r\theta^*.

A chopper driver regulates its current cycle by cycle, without the lag a linear loop has at the electrical
frequency :math:`N_r\dot\theta^*` (:math:`\arctan(N_r\dot\theta^*/\omega_c)`, i.e. 9.5 electrical degrees,
8.6 counts of a 14-bit encoder, at 20 rad/s on a 50-tooth rotor with :math:`\omega_c = 6000` rad/s); the
feedforward stands in for that, so that the baseline is not crippled by the linear loop
(``feedforward=False`` shows the lag). It reads the two phase currents and nothing else: no encoder, no
speed (the ``back_emf`` option adds the back EMF the plan's speed gives, :math:`K_m\dot\theta^*(-\sin N_r\theta^*,
\cos N_r\theta^*)`, as a driver with back-EMF compensation does from its commanded speed). The rotor
lags :math:`\theta^*` by the load angle :math:`\arcsin(T/(K_m\rho^*))/N_r` for a torque demand :math:`T`, and
rings at the stiffness :math:`\sqrt{K_m N_r\rho^*/J}` with only the motor's own damping. The ``load_angle``
option leads the current vector by the load angle of the torque the plan needs, as a driver with a known
inertia can:

.. math::
    p = N_r\theta^* + \delta,\qquad \sin\delta = \mathrm{clip}\Big(\frac{J\ddot\theta^* + B\dot\theta^*}{K_m\rho^*},
    \pm 1\Big),\qquad \dot\delta = \frac{d}{dt}\sin\delta\,\Big/\cos\delta \text{ (0 where clipped)}.

**Tuning.** :math:`\omega_c = \lambda = 0.3/T_s`, the bandwidth of the sliding controller's current-norm loop
(:func:`flatstep.loop.design.design_gains`); the run current is the plan's, the same current norm the sliding
controller holds. Anti-windup: the integrators hold while the bus limits.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..plan.protocol import Plan
from ..validate import check_positive
from .loops import BaselineController, PIGains, bus_scale, pi_integrate, pi_output

if TYPE_CHECKING:
    from .build import BuildContext
    from .spec import ControllerSpec


@dataclass(frozen=True)
class MicrostepGains:
    r"""Current-loop bandwidth [rad/s] of the microstepping driver (PI gains by pole-zero cancellation).

    ``feedforward`` adds the voltage of the current reference, :math:`R i^* + L\,di^*/dt` (default on);
    ``back_emf`` the back EMF at the plan's angle and speed, ``load_angle`` the lead of the current vector by the
    load angle the plan's torque needs (both default off; module docstring).
    """

    current_bandwidth: float
    feedforward: bool = True
    back_emf: bool = False
    load_angle: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "current_bandwidth",
                           check_positive("current_bandwidth", self.current_bandwidth, unit=" rad/s"))

    def as_dict(self) -> dict[str, float]:
        """The bandwidth and the feedforward switches, for JSON."""
        return {"current_bandwidth": self.current_bandwidth, "feedforward": self.feedforward,
                "back_emf": self.back_emf, "load_angle": self.load_angle}


class Microstepping(BaselineController[MicrostepGains]):
    r"""Open-loop microstepping driver following any plan (:class:`~flatstep.plan.protocol.Plan`).

    Parameters
    ----------
    motor : MotorParams
        The driver's nominal model (only ``R``, ``L`` and ``Nr`` are used).
    plan : Plan
        The move; its :math:`\theta^*(t)` is the commanded angle, its :math:`\rho^*(t)` the run current.
    gains : MicrostepGains
        The current-loop bandwidth and the feedforward switch.
    control_period : float
        Ts [s] of the current loops.
    measurement : str
        Accepted for the drive's bookkeeping (which speed/acceleration the loop computes); the driver reads
        only the currents.
    v_limit : float
        The bus voltage its anti-windup knows [V].
    """

    #: The C twin: csrc/microstep.h.
    c_name = "microstep"
    #: Ts [s] of the current loops: the driver is a sampled law, never continuous (the base class allows ``None``).
    control_period: float

    def __init__(self, motor: MotorParams, plan: Plan, gains: MicrostepGains, *, control_period: float,
                 measurement: str = "model", v_limit: float = math.inf) -> None:
        super().__init__(motor, plan, gains, measurement=measurement, control_period=control_period,
                         v_limit=v_limit)
        self.pi = PIGains.current_loop(motor, gains.current_bandwidth)

    def current_reference(self, t: ArrayLike, order: int = 0) -> NDArray[np.float64]:
        """The current reference ``(ia*, ib*) = rho* (cos p, sin p)``, ``p = N_r theta* [+ delta]``, at times ``t``.

        ``delta`` is the load angle with ``gains.load_angle`` (module docstring). Vectorized; with ``order=1``, its
        time derivative.
        """
        m = self.motor
        ref = self.plan.flag(t)
        p = m.Nr * ref.theta
        c, s = np.cos(p), np.sin(p)
        dp = m.Nr * ref.dtheta
        if self.gains.load_angle:  # sin delta = clip(T / (Km rho*)), delta' = T'/(Km rho*) ... / cos delta
            sd = np.clip((m.J * ref.ddtheta + m.B * ref.dtheta) / (m.Km * ref.rho), -1.0, 1.0)
            cd = np.sqrt(1 - sd * sd)
            rate = ((m.J * ref.dddtheta + m.B * ref.ddtheta) - sd * m.Km * ref.drho) / (m.Km * ref.rho)
            dp = dp + np.where(cd > 0, rate / np.where(cd > 0, cd, 1.0), 0.0)
            s, c = s * cd + c * sd, c * cd - s * sd
        if order == 0:
            return np.array([ref.rho * c, ref.rho * s])
        w = dp * ref.rho
        return np.array([ref.drho * c - w * s, ref.drho * s + w * c])

    def initial_state(self) -> NDArray[np.float64]:
        """The two PI integrals at the start of a run.

        Zero with the feedforward, else the resistive voltage of the start current (a driver at rest).
        """
        if self.gains.feedforward:
            return np.zeros(2)
        return self.motor.R * self.current_reference(self.plan.t0 - 1.0)

    def step(self, state: Optional[ArrayLike], measurement: ArrayLike,
             t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(ia*, ib*) - (ia, ib)`` through the PI loops; ``measurement = (ia, ib, omega, theta, ddtheta)``."""
        integral = self.initial_state() if state is None else np.asarray(state, dtype=float)
        y = np.asarray(measurement, dtype=float)
        i_ref = self.current_reference(t)
        error = i_ref - y[:2]
        v = pi_output(self.pi, error, integral)
        m = self.motor
        if self.gains.feedforward:
            v = v + m.R * i_ref + m.L * self.current_reference(t, 1)
        if self.gains.back_emf:
            ref = self.plan.flag(t)
            p = m.Nr * ref.theta
            v = v + m.Km * ref.dtheta * np.array([-np.sin(p), np.cos(p)])
        hold = bus_scale(v, self.v_limit) < 1.0
        return v, pi_integrate(self.pi, error, integral, self.control_period, hold)

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct microstep_params`` (csrc/microstep.h)."""
        return dict(motor=self.motor.as_dict(), plan=self.plan.c_plan(),
                    gains=dict(current_bandwidth=self.gains.current_bandwidth, feedforward=self.gains.feedforward,
                               back_emf=self.gains.back_emf, load_angle=self.gains.load_angle),
                    Ts=self.control_period, v_limit=self.v_limit)


def from_spec(spec: ControllerSpec, context: BuildContext) -> Microstepping:
    """The microstepping driver (flatstep.control.spec), its current loops at ``lambda`` (flatstep.control.build).

    Any of :class:`MicrostepGains`'s fields given in ``context.law_gains`` replaces the rule's; ``back_emf`` adds the
    back EMF at the plan's speed, ``load_angle`` leads the current vector by the plan's load angle.
    """
    lam, _ = context.bandwidths()
    gains = context.gains(MicrostepGains, dict(current_bandwidth=lam),
                          dict(back_emf=spec.back_emf, load_angle=spec.load_angle))
    return Microstepping(context.motor, context.plan, gains, control_period=context.period,
                         measurement=context.measurement, v_limit=context.v_limit)
