"""A plan's worst use of each limit (:class:`~flatstep.plan.limits.MotorLimits`), through the flat maps.

The checks of :mod:`flatstep.plan.limits`' module docstring, on a segment table sampled ``samples_per_segment``
times per segment and at its breaks.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.flat import flat_to_state
from ..model.motor import MotorParams
from .arguments import check_limits, check_motor, check_plan_table, check_samples_per_segment
from .limits import SAMPLES_PER_SEGMENT, MotorLimits
from .piecewise import PiecewisePlan


def plan_margins(plan: PiecewisePlan, motor: MotorParams, limits: MotorLimits,
                 samples_per_segment: int = SAMPLES_PER_SEGMENT) -> dict[str, float]:
    """The plan's worst use of each limit (module docstring): ratios, feasible when all are <= 1.

    The peaks themselves are returned beside them (``v_peak`` [V], ``rho_peak`` [A], ``speed_peak`` ...).
    ``samples_per_segment`` times the plan's segments is at most ``MAX_PLAN_SAMPLES``.
    """
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
