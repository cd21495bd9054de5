"""The exceptions of flatstep's boundary, in one place.

* :class:`~flatstep.validate.checks.InputError` (a ``ValueError``): a refused value, before anything runs;
* :class:`~flatstep.plan.feasibility.InfeasiblePlanError` (a ``ValueError``): a plan the motor cannot follow;
* :class:`RunError` (a ``RuntimeError``): a run that could not go on (its state became non-finite, its
  controller faulted at every trial step, it hit its step or time bound), with the reason and the time.

The command line maps them to exit codes 2 (refused) and 5 (a run that stopped; docs/errors.md).
"""
from __future__ import annotations

from .validate.checks import InputError

__all__ = ["InputError", "RunError"]

#: Reasons a run stops early, with what they mean (the ``reason`` of a :class:`RunError`).
REASONS = {
    "nonfinite": "the plant state became NaN or infinite",
    "fault": "the controller faulted (left its law's domain) at every step the integrator tried",
    "max_steps": "the integrator needed more steps than its bound (Continuous.max_steps)",
    "wall_time": "the run took longer than its bound (Continuous.max_wall_time)",
    "step_size": "the integrator's step size fell below rounding level (a stiff or diverging state)",
    "args": "the C core refused its arguments",
}


class RunError(RuntimeError):
    """A run that stopped before ``t_end``: ``reason`` (a key of :data:`REASONS`) and ``t_fail`` [s]."""

    def __init__(self, reason: str, t_fail: float, message: str) -> None:
        super().__init__(message)
        self.reason = reason
        self.t_fail = t_fail
