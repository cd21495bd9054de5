"""The C field-weakening planner (csrc/time_optimal_dq.h) behind ``time_optimal_dq(..., engine="c")``.

:func:`plan_table` returns the :class:`~flatstep.plan.time_optimal_dq_profile.DQTable` that
:func:`flatstep.plan.time_optimal_dq.plan_dq_move` plans, planned by ``time_optimal_dq_plan`` (the same algorithm).
It reads the compiled core alone (``flatstep._flatstep_core``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .._flatstep_core import ffi, lib
from ..model.motor import MotorParams
from .limits import MotorLimits
from .piecewise import NCOEF
from .smoothing import MAX_SEGMENTS
from .time_optimal_dq_profile import DQTable

#: The workspace time_optimal_dq_plan needs [fs_real].
WORK_LEN = int(lib.time_optimal_dq_work_len())
if lib.TO_MAX_SEGMENTS != MAX_SEGMENTS:
    raise ImportError(f"csrc/time_optimal.h TO_MAX_SEGMENTS={lib.TO_MAX_SEGMENTS} differs from "
                      f"flatstep.plan.smoothing.MAX_SEGMENTS={MAX_SEGMENTS}: rebuild the C core (pip install -e .)")


def _structs(motor: MotorParams, limits: MotorLimits, control_rate: float) -> tuple[Any, Any]:
    """The ``struct motor_params *`` and ``struct tod_limits *`` of the arguments."""
    m = ffi.new("struct motor_params *", dict(R=motor.R, L=motor.L, Km=motor.Km, J=motor.J, B=motor.B, Nr=motor.Nr))
    lim = ffi.new("struct tod_limits *", dict(v_bus=limits.v_bus, v_use=limits.v_use, i_max=limits.i_max,
                                              speed_max=limits.speed_max or 0.0, control_rate=control_rate))
    return m, lim


def plan_raw(distance: float, motor: MotorParams, limits: MotorLimits, control_rate: float,
             work_len: int = WORK_LEN) -> tuple[int, Any]:
    """``time_optimal_dq_plan``'s return code and ``struct tod_result *`` (for tests of the error codes)."""
    m, lim = _structs(motor, limits, control_rate)
    work = np.empty(max(work_len, 1))
    out = ffi.new("struct tod_result *")
    rc = lib.time_optimal_dq_plan(m, lim, float(distance), ffi.from_buffer("double[]", work), work_len, out)
    return int(rc), out


def plan_table(distance: float, motor: MotorParams, limits: MotorLimits,
               control_rate: float) -> tuple[DQTable, dict[str, float], float, float]:
    """The C planner's table over ``|distance|`` from 0 at t = 0, its margins, bus share and width.

    Raises
    ------
    ValueError
        The motor cannot start, or no feasible plan (the arguments are checked by the caller).
    """
    rc, out = plan_raw(abs(distance), motor, limits, control_rate)
    if rc == lib.TOD_ESTART:
        raise ValueError(f"the motor cannot start: at rest {limits.v_use * limits.v_bus:g} V and {limits.i_max:g} A "
                         "give no torque")
    if rc != lib.TOD_OK:
        raise ValueError(f"no feasible field-weakening plan of {distance} rad within {limits}: raise v_bus or i_max"
                         if rc == lib.TOD_ENOPLAN else f"time_optimal_dq_plan refused its arguments (code {rc})")
    n = int(out.n)

    def take(name: str, size: int) -> np.ndarray:
        return np.frombuffer(ffi.buffer(getattr(out, name)), dtype=np.float64)[:size].copy()

    g = out.margins
    margins = dict(voltage=g.voltage, current=g.current, speed=g.speed, i_d_min=g.i_d_min,
                   speed_peak=g.speed_peak, worst=g.worst)
    table = DQTable(take("breaks", n + 1), take("theta", n * NCOEF).reshape(n, NCOEF), take("knot_id", n + 1),
                    take("knot_did", n + 1))
    return table, margins, float(out.kappa), float(out.width)
