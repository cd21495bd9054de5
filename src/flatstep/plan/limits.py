r"""The motor's limits on a plan, and a plan's worst margins against them through the flat maps.

A plan of the flat outputs fixes, at every instant, the currents and voltages the motor needs
(:func:`flatstep.model.flat.flat_to_state`: R i, L di/dt, the back EMF and the reactance). :func:`plan_margins`
samples a plan and reports how much of each limit it uses:

* ``voltage``: the largest voltage magnitude :math:`\sqrt{v_a^2 + v_b^2}` over the bus voltage: each phase
  voltage reaches it once per electrical turn, so it bounds them at any rotor angle (and does not depend on
  where the samples fall on the turn);
* ``current``: the largest current magnitude :math:`\rho` over ``i_max``;
* ``torque_angle``: the largest :math:`|\cos\delta| = |J\ddot\theta + B\dot\theta| / K_m\rho` over
  :math:`\sin` of ``torque_angle_max`` (the paper's law is singular at :math:`|\cos\delta| = 1`);
* ``speed``, ``acceleration``, ``jerk``: the peaks over the optional caps.

A plan is feasible when every ratio is at most 1.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat import flat_to_state
from ..model.motor import MotorParams
from ..validate import InputError, check_quantity
from .piecewise import PiecewisePlan

Array = NDArray[np.float64]
#: Samples per segment of a margin check.
SAMPLES_PER_SEGMENT = 24


@dataclass(frozen=True)
class MotorLimits:
    r"""The bus, the current and the law's torque-angle margin, and optional speed, acceleration and jerk caps.

    Parameters
    ----------
    v_bus : float
        Bus voltage [V]: each phase voltage must stay within +-v_bus.
    i_max : float
        Largest current-vector magnitude rho [A].
    i_hold : float
        The current across the torque axis at rest, :math:`\rho\sin\delta` [A], > 0 (the holding current).
    i_run : float, optional
        The current across the torque axis at speed [A], in (0, i_hold]; ``None``: i_hold throughout. Less of
        it lowers the reactance voltage :math:`N_r\omega L i_d` (the plan of rho*, :meth:`across`).
    speed_corner : float
        The speed [rad/s] at which the across-axis floor is halfway from i_hold to i_run.
    torque_angle_max : float
        Largest torque angle the plan may ask for, :math:`\pi/2 - \delta` [rad], in (0, pi/2).
    v_use : float
        Fraction of v_bus the plan's feedforward may use, in (0, 1]; the rest is the controller's to correct.
    speed_max, accel_max, jerk_max : float, optional
        Caps [rad/s, rad/s^2, rad/s^3].

    Every field is a number (not a bool, not a string) in its range of :mod:`flatstep.validate.ranges`:
    ``v_bus`` that of ``v_bus``, the currents that of ``current``, ``speed_corner`` and ``speed_max`` that of
    ``speed``, ``accel_max`` ``acceleration``, ``jerk_max`` ``jerk``, ``torque_angle_max`` ``torque_angle`` and
    ``v_use`` ``fraction``; an :class:`~flatstep.validate.InputError` names the field otherwise.
    """

    v_bus: float
    i_max: float
    i_hold: float = 0.3
    i_run: Optional[float] = None
    speed_corner: float = 10.0
    torque_angle_max: float = 1.2
    v_use: float = 0.9
    speed_max: Optional[float] = None
    accel_max: Optional[float] = None
    jerk_max: Optional[float] = None

    def __post_init__(self) -> None:
        # every field in its range of flatstep.validate.ranges (an InputError naming the field otherwise)
        for name, kind in (("v_bus", "v_bus"), ("i_max", "current"), ("i_hold", "current"),
                           ("speed_corner", "speed"), ("torque_angle_max", "torque_angle"), ("v_use", "fraction")):
            object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        for name, kind in (("i_run", "current"), ("speed_max", "speed"), ("accel_max", "acceleration"),
                           ("jerk_max", "jerk")):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        if self.i_hold >= self.i_max:
            raise InputError("i_hold", self.i_hold, f"i_hold={self.i_hold!r} A must be below i_max={self.i_max!r} A, "
                             "or no torque is left")
        if self.i_run is not None and self.i_run > self.i_hold:
            raise InputError("i_run", self.i_run, f"i_run={self.i_run!r} A must be in (0, i_hold={self.i_hold!r} A]")

    def floor(self, omega: ArrayLike) -> Array:
        """The across-axis current without torque: i_hold at rest, towards i_run at speed."""
        w = np.abs(np.asarray(omega, dtype=float))
        run = self.i_hold if self.i_run is None else self.i_run
        return run + (self.i_hold - run) / (1.0 + (w / self.speed_corner) ** 2)

    def across(self, iq: ArrayLike, omega: ArrayLike) -> Array:
        r"""The planned current across the torque axis for the torque current ``iq`` at speed ``omega``.

        .. math:: i_d = \sqrt{f(\omega)^2 + (i_q\cot\alpha_{max})^2}

        smooth in both, and never below :math:`|i_q|\cot\alpha_{max}`: the torque angle stays below
        ``torque_angle_max``.
        """
        return np.hypot(self.floor(omega), np.asarray(iq, dtype=float) / math.tan(self.torque_angle_max))

    def rho(self, iq: ArrayLike, omega: ArrayLike) -> Array:
        """The planned current magnitude rho* = hypot(iq, across(iq, omega))."""
        return np.hypot(np.asarray(iq, dtype=float), self.across(iq, omega))

    def iq_cap(self, omega: ArrayLike) -> Array:
        """The largest torque current within i_max at speed ``omega``."""
        room = np.sqrt(np.maximum(self.i_max**2 - self.floor(omega) ** 2, 0.0))
        return room * math.sin(self.torque_angle_max)

    def as_dict(self) -> dict[str, Optional[float]]:
        """The limits by name, for JSON."""
        return asdict(self)


def plan_margins(plan: PiecewisePlan, motor: MotorParams, limits: MotorLimits,
                 samples_per_segment: int = SAMPLES_PER_SEGMENT) -> dict[str, float]:
    """The plan's worst use of each limit (module docstring): ratios, feasible when all are <= 1.

    The peaks themselves are returned beside them (``v_peak`` [V], ``rho_peak`` [A], ``speed_peak`` ...).
    ``samples_per_segment`` times the plan's segments is at most ``MAX_PLAN_SAMPLES``.
    """
    from .arguments import check_limits, check_motor, check_plan_table, check_samples_per_segment

    plan, motor, limits = check_plan_table(plan), check_motor(motor), check_limits(limits)
    samples_per_segment = check_samples_per_segment(samples_per_segment, plan.n)
    tau = (np.arange(samples_per_segment) + 0.5) / samples_per_segment
    t = np.concatenate([(plan.breaks[:-1, None] + plan.durations[:, None] * tau[None, :]).ravel(), plan.breaks])
    f = plan.flag(np.sort(t))
    torque = motor.J * f.ddtheta + motor.B * f.dtheta
    cos_delta = np.abs(torque) / (motor.Km * f.rho)
    out = dict(rho_peak=float(np.max(f.rho)), speed_peak=float(np.max(np.abs(f.dtheta))),
               accel_peak=float(np.max(np.abs(f.ddtheta))), jerk_peak=float(np.max(np.abs(f.dddtheta))),
               cos_delta_peak=float(np.max(cos_delta)))
    if out["cos_delta_peak"] >= 1:
        out.update(v_peak=math.inf, voltage=math.inf)
    else:
        _, v = flat_to_state(f, motor)
        out["v_peak"] = float(np.max(np.hypot(v[0], v[1])))
        out["voltage"] = out["v_peak"] / limits.v_bus
    out["current"] = out["rho_peak"] / limits.i_max
    out["torque_angle"] = out["cos_delta_peak"] / math.sin(limits.torque_angle_max)
    for key, cap in (("speed", limits.speed_max), ("acceleration", limits.accel_max), ("jerk", limits.jerk_max)):
        out[key] = out[f"{'accel' if key == 'acceleration' else key}_peak"] / cap if cap else 0.0
    out["worst"] = max(out[k] for k in ("voltage", "current", "torque_angle", "speed", "acceleration", "jerk"))
    return out
