"""The C time-optimal planner (csrc/time_optimal.h) behind ``time_optimal(..., engine="c")``.

:func:`plan_table` returns the table :func:`flatstep.plan.time_optimal.plan_move` plans, planned by
``time_optimal_plan`` (the same algorithm, csrc/time_optimal.c). It calls the compiled core directly, with the
motor's own C fields (:meth:`~flatstep.model.motor.MotorParams.c_params`): the plan layer does not import the
binding (:mod:`flatstep.core`), which sits above it.
"""
from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .._flatstep_core import ffi, lib
from ..model.motor import MotorParams
from ..validate import InputError
from ..validate.limits import MAX_PLAN_SAMPLES
from .envelope import envelope
from .limits import MotorLimits
from .piecewise import NCOEF
from .smoothing import DEFAULT_WIDTHS, MAX_SEGMENTS, Table, check_samples, planning_limits, timing

#: The workspace time_optimal_plan needs [fs_real].
WORK_LEN = int(lib.time_optimal_work_len())
if lib.TO_MAX_SAMPLES != MAX_PLAN_SAMPLES:
    raise ImportError(f"csrc/time_optimal.h TO_MAX_SAMPLES={lib.TO_MAX_SAMPLES} differs from "
                      f"flatstep.validate.limits.MAX_PLAN_SAMPLES={MAX_PLAN_SAMPLES}: keep them equal")
if lib.TO_MAX_SEGMENTS != MAX_SEGMENTS:  # the reference and the C core share their sizes
    raise ImportError(f"csrc/time_optimal.h TO_MAX_SEGMENTS={lib.TO_MAX_SEGMENTS} differs from "
                      f"flatstep.plan.time_optimal.MAX_SEGMENTS={MAX_SEGMENTS}: rebuild the C core (pip install -e .)")


def limits_struct(limits: MotorLimits) -> Any:
    """A ``struct to_limits *`` holding ``limits`` (a cap of None is 0; i_run of None is i_hold)."""
    return ffi.new("struct to_limits *", dict(
        v_bus=limits.v_bus, i_max=limits.i_max, i_hold=limits.i_hold,
        i_run=limits.i_hold if limits.i_run is None else limits.i_run, speed_corner=limits.speed_corner,
        torque_angle_max=limits.torque_angle_max, v_use=limits.v_use, speed_max=limits.speed_max or 0.0,
        accel_max=limits.accel_max or 0.0, jerk_max=limits.jerk_max or 0.0))


def plan_raw(distance: float, motor: MotorParams, limits: MotorLimits,
             widths: Optional[tuple[float, ...]] = None, work_len: int = WORK_LEN) -> tuple[int, Any]:
    """``time_optimal_plan``'s return code and ``struct to_result *`` (for tests of the error codes)."""
    work = np.empty(max(work_len, 1))
    w = np.ascontiguousarray(widths if widths else [], dtype=np.float64)
    out = ffi.new("struct to_result *")
    m = ffi.new("struct motor_params *", motor.c_params())
    rc = lib.time_optimal_plan(m, limits_struct(limits), float(distance),
                               ffi.from_buffer("double[]", w) if w.size else ffi.NULL, w.size,
                               ffi.from_buffer("double[]", work), work_len, out)
    return int(rc), out


def plan_table(distance: float, motor: MotorParams, limits: MotorLimits,
               widths: Optional[tuple[float, ...]] = None) -> Table:
    """The C planner's table over ``distance`` (either sign, mirrored as the reference mirrors), from 0 at t = 0.

    Raises
    ------
    ValueError
        With the reference's messages: the motor cannot start, no feasible plan, or an argument out of range.
    """
    if widths is not None and not 1 <= len(widths) <= lib.TO_MAX_WIDTHS:
        raise ValueError(f"widths={widths!r}: give 1 to {lib.TO_MAX_WIDTHS} smoothing widths [s]")
    if widths is not None and not all(math.isfinite(w) and w > 0 for w in widths):
        raise ValueError(f"widths={widths!r}: every smoothing width must be a finite time > 0 [s]")
    rc, out = plan_raw(distance, motor, limits, widths)
    if rc == lib.TO_ESTART:
        raise ValueError(f"the motor cannot start: at rest the bus {limits.v_bus} V and the limits {limits} leave no "
                         "torque")
    if rc == lib.TO_ELONG:  # the reference's message, from its own timing of the full-bus move
        full = envelope(motor, planning_limits(limits), 1.0)
        for w in widths or tuple(k * (motor.L / motor.R) for k in DEFAULT_WIDTHS):
            check_samples(distance, timing(abs(distance), full, w))
        raise InputError("distance", distance, f"the move of {distance:g} rad would take more than "
                         f"{MAX_PLAN_SAMPLES:.3g} samples (flatstep.validate.limits.MAX_PLAN_SAMPLES): split it "
                         "into shorter moves with waypoints")
    if rc == lib.TO_ENOPLAN:
        raise ValueError(f"no feasible plan of {distance} rad within {limits}: raise v_bus or i_max, lower i_hold or "
                         "i_run, or split the move with waypoints")
    if rc != lib.TO_OK:
        raise ValueError(f"time_optimal_plan refused distance={distance!r} rad with {motor} and {limits} "
                         f"(code {rc}): the motor parameters, limits and distance must be finite and in range")
    n = int(out.n)
    breaks = np.frombuffer(ffi.buffer(out.breaks), dtype=np.float64)[: n + 1].copy()
    rows = np.frombuffer(ffi.buffer(out.theta), dtype=np.float64)[: n * NCOEF].reshape(n, NCOEF)
    rho = np.frombuffer(ffi.buffer(out.rho), dtype=np.float64)[: n * NCOEF].reshape(n, NCOEF)
    # C mirrors a negative move itself; the reference's Table is of |distance|: undo it so that both mirror once
    sign = 1.0 if distance >= 0 else -1.0
    return Table(breaks, sign * rows, rho.copy())
