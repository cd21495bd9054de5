"""Checks of the planning functions' arguments at entry: types, ranges and sizes, before any work.

Each returns the argument as the planner keeps it, or raises an :class:`~flatstep.validate.InputError` that names
the argument, shows the value and says what is valid.
"""
from __future__ import annotations

from typing import Any

from ..model.motor import MotorParams
from ..validate import InputError, check_choice, check_instance, check_integer, check_quantity
from ..validate.limits import MAX_PLAN_SAMPLES
from .limits import MotorLimits
from .piecewise import PiecewisePlan

#: The engines of the time-optimal planner.
ENGINES = ("c", "python")


def check_motor(motor: Any, name: str = "motor") -> MotorParams:
    """``motor``, or an InputError unless it is a :class:`~flatstep.model.motor.MotorParams`."""
    return check_instance(name, motor, MotorParams, "a MotorParams", "e.g. MotorParams.preset('nema17')")


def check_limits(limits: Any, name: str = "limits") -> MotorLimits:
    """``limits``, or an InputError unless it is a :class:`~flatstep.plan.limits.MotorLimits` (a dict is not)."""
    return check_instance(name, limits, MotorLimits, "a MotorLimits", "e.g. MotorLimits(v_bus=24.0, i_max=1.0)")


def check_plan_table(plan: Any, name: str = "plan") -> PiecewisePlan:
    """``plan``, or an InputError unless it is a :class:`~flatstep.plan.piecewise.PiecewisePlan`."""
    return check_instance(name, plan, PiecewisePlan, "a PiecewisePlan", "a segment table")


def check_t0(t0: Any, name: str = "t0") -> float:
    """``t0`` as float, or an InputError unless it is a time in the range of ``time`` (a run starts at t = 0)."""
    return check_quantity("time", t0, as_name=name)


def check_angle(value: Any, name: str) -> float:
    """``value`` as float, or an InputError unless it is an angle in the range of ``angle``."""
    return check_quantity("angle", value, as_name=name)


def check_engine(engine: Any) -> str:
    """``engine``, or an InputError unless it is one of :data:`ENGINES`."""
    return check_choice("engine", engine, ENGINES)


def check_samples_per_segment(value: Any, segments: int, name: str = "samples_per_segment") -> int:
    """``value`` as int, or an InputError unless it is >= 1 and ``segments`` times it is within MAX_PLAN_SAMPLES."""
    out = check_integer(name, value, low=1, high=MAX_PLAN_SAMPLES, why="samples of each segment")
    if out * segments > MAX_PLAN_SAMPLES:
        raise InputError(name, value, f"{name}={value!r} on {segments} segments is {out * segments:.4g} samples, "
                         f"above the limit of {MAX_PLAN_SAMPLES:.3g} (flatstep.validate.limits.MAX_PLAN_SAMPLES); "
                         f"give at most {max(1, MAX_PLAN_SAMPLES // segments)}")
    return out
