"""The C trajectory evaluator (csrc/trajectory.h) over arrays: ``traj_flag_n`` and ``traj_theta``.

The same values as :meth:`flatstep.plan.piecewise.PiecewisePlan.flag` and
:meth:`~flatstep.plan.piecewise.PiecewisePlan.theta_deriv`, computed by the C core.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..model.flat import FlatFlag
from ..plan.piecewise import MAX_ORDER, PiecewisePlan
from .structs import Array, _in, _out, _shape, _vec, lib


def traj_flag(plan: PiecewisePlan, t: ArrayLike) -> FlatFlag:
    """C ``traj_flag`` at times ``t`` (one C call over the array)."""
    t_arr = np.asarray(t, dtype=np.float64)
    tv = _vec(t_arr)
    out = np.empty((tv.size, 6))
    lib.traj_flag_n(plan.c_struct(), _in(tv), tv.size, _out(out))
    return FlatFlag(*_shape(out, t_arr.shape))


def traj_theta(plan: PiecewisePlan, t: ArrayLike, order: int) -> Array:
    """C ``traj_theta``: the ``order``-th derivative (0..4) of theta at times ``t`` (a C call per sample)."""
    if not 0 <= order <= MAX_ORDER:
        raise ValueError(f"order={order!r} is out of range; the table gives theta's derivatives 0..{MAX_ORDER}")
    t_arr = np.asarray(t, dtype=np.float64)
    tr = plan.c_struct()
    return np.array([lib.traj_theta(tr, float(s), order) for s in t_arr.ravel()]).reshape(t_arr.shape)


def traj_valid(plan: PiecewisePlan) -> bool:
    """C ``traj_valid`` on the plan's table."""
    return bool(lib.traj_valid(plan.c_struct()))
