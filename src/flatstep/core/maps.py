"""The planner, flat maps and controller of the C core over arrays: one C call per array.

The C side is csrc/arrays.h: ``arrays_plan_eval``, ``arrays_plan_flat``, ``arrays_flat_*``,
``arrays_state_to_flat``, ``arrays_smc_step``, ``arrays_controller_step``.
"""
from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..control.smc import FlatnessSMC
from ..model.flat import FlatFlag
from ..model.motor import MotorParams
from ..plan.protocol import Plan
from .structs import (
    RHO_MIN,
    V_LIMIT,
    Array,
    _in,
    _out,
    _rows,
    _shape,
    _u32,
    _vec,
    lib,
    motor_struct,
    plan_struct,
    smc_struct,
)


def plan_flag(plan: Plan, t: ArrayLike) -> FlatFlag:
    """C ``plan_eval`` at times ``t``; the same values as ``plan.flag`` (psi, or the plan's table)."""
    t_arr = np.asarray(t, dtype=np.float64)
    tv = _vec(t_arr)
    out = np.empty((tv.size, 6))
    lib.arrays_plan_eval(plan_struct(plan), _in(tv), tv.size, _out(out))
    return FlatFlag(*_shape(out, t_arr.shape))


def flat_voltages(motor: MotorParams, rho: ArrayLike, drho: ArrayLike, theta: ArrayLike, dtheta: ArrayLike,
                  ddtheta: ArrayLike, dddtheta: ArrayLike, phi: ArrayLike, torque_demand: ArrayLike) -> Array:
    """C ``flat_voltages``; (2, ...) voltages, NaN where the sample is outside the maps' domain."""
    args = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in
                                 (rho, drho, theta, dtheta, ddtheta, dddtheta, phi, torque_demand)))
    rows = np.ascontiguousarray(np.stack([a.ravel() for a in args], axis=1))
    out = np.empty((rows.shape[0], 2))
    lib.arrays_flat_voltages(motor_struct(motor), _in(rows), rows.shape[0], _out(out))
    return _nan_outside(_shape(out, args[0].shape), rows, motor)


def _nan_outside(v: Array, rows: Array, motor: MotorParams) -> Array:
    """Mark samples outside the domain (rho <= 0 or |A| >= Km rho) with NaN instead of the C core's 0 V."""
    rho, A = rows[:, 0], rows[:, 7]
    bad = ~((rho > 0) & (motor.Km**2 * rho**2 - A**2 > 0))
    if np.any(bad):
        v = v.copy()
        v.reshape(2, -1)[:, bad] = np.nan
    return v


def flat_to_state(flag: FlatFlag, motor: MotorParams, load_torque: float = 0.0) -> tuple[Array, Array]:
    """C ``flat_to_state``; raises ValueError (naming the sample) outside the maps' domain."""
    arrays = np.broadcast_arrays(*(np.asarray(f, dtype=np.float64) for f in flag))
    rows = np.ascontiguousarray(np.stack([a.ravel() for a in arrays], axis=1))
    x, v = np.empty((rows.shape[0], 4)), np.empty((rows.shape[0], 2))
    bad = lib.arrays_flat_to_state(motor_struct(motor), _in(rows), rows.shape[0], float(load_torque), _out(x), _out(v))
    if bad:
        raise ValueError(f"{bad} sample(s) of the flat flag are outside the domain of the flat maps "
                         "(rho <= 0 or |J theta'' + B theta' + tau| >= Km rho)")
    return _shape(x, arrays[0].shape), _shape(v, arrays[0].shape)


def state_to_flat(x: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: float = 0.0) -> FlatFlag:
    """C ``state_to_flat``; raises ValueError where ia = ib = 0."""
    x_arr = np.asarray(x, dtype=np.float64)
    xr, vr = _rows(x_arr, 4, "x"), _rows(v, 2, "v")
    if xr.shape[0] != vr.shape[0]:
        raise ValueError(f"x has {xr.shape[0]} samples but v has {vr.shape[0]}")
    out = np.empty((xr.shape[0], 6))
    bad = lib.arrays_state_to_flat(motor_struct(motor), _in(xr), _in(vr), xr.shape[0], float(load_torque), _out(out))
    if bad:
        raise ValueError(f"{bad} sample(s) have ia = ib = 0 (rho = 0): the flat outputs' phase is undefined there")
    return FlatFlag(*_shape(out, x_arr.shape[1:]))


def smc_voltages(controller: FlatnessSMC, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None, *,
                 v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> tuple[Array, NDArray[np.uint32]]:
    """C ``smc_step`` at times ``t`` for states ``x`` (4, n) (and true theta'' in ideal mode).

    Returns the (2, n) voltages and the (n,) status bits (see :data:`STATUS_BITS`).
    """
    xr = _rows(x, 4, "x")
    n = xr.shape[0]
    if controller.measurement != "model" and ddtheta is None:
        raise ValueError(f"measurement={controller.measurement!r} needs the acceleration ddtheta; "
                         "use measurement='model' to compute it from the state")
    acc = np.zeros(n) if ddtheta is None else np.broadcast_to(np.asarray(ddtheta, dtype=np.float64).ravel(), (n,))
    y = np.ascontiguousarray(np.column_stack([xr, acc]))
    tv = np.ascontiguousarray(np.broadcast_to(_vec(t), (n,)))
    v, status = np.empty((n, 2)), np.empty(n, dtype=np.uint32)
    lib.arrays_smc_step(smc_struct(controller, v_limit, rho_min), _in(tv), _in(y), n, _out(v),
                       _u32(status))
    return np.ascontiguousarray(v.T), status


def plan_to_state(plan: Plan, motor: MotorParams, t: ArrayLike, load_torque: float = 0.0) -> tuple[Array, Array]:
    """C ``arrays_plan_flat``: the planned state (4, n) and feedforward voltages (2, n) at the times ``t`` (1-D).

    Plan and flat map run in one C loop; the values are those of ``flat_to_state(plan_flag(plan, t), motor)``.
    """
    tv = _vec(t)
    flag, x, v = np.empty((tv.size, 6)), np.empty((tv.size, 4)), np.empty((tv.size, 2))
    bad = lib.arrays_plan_flat(plan_struct(plan), motor_struct(motor), _in(tv), tv.size, float(load_torque),
                              _out(flag), _out(x), _out(v))
    if bad:
        raise ValueError(f"{bad} sample(s) of the plan are outside the domain of the flat maps "
                         "(|J theta'' + B theta' + tau| >= Km rho): the move is infeasible for this motor")
    return x.T, v.T
