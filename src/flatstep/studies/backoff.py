"""Plan, check on the drive, back off the binding limit, plan again: the planner's side of the check.

:func:`plan_for_drive` plans within some limits, checks the plan (:mod:`flatstep.studies.verify`), and where a case
is lost or faults tightens the limit that binds (:data:`BACK_OFF`) and plans again, at most :data:`ROUNDS` times;
then it refuses, naming the limit and what to change. :func:`check_on_drive` does it for a scenario file: each plan
is checked as ``flatstep simulate`` would run it, with the file's own controller on the file's drive.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable, Optional

import numpy as np

from ..control.protocol import Controller
from ..loop.reference import DriveLoop
from ..model.motor import MotorParams
from ..plan.limits import MotorLimits
from ..plan.piecewise import PiecewisePlan
from .scenario import Scenario
from .verify import Verdict, verify_plan, verify_scenario

#: Back-off rounds of :func:`plan_for_drive` before it refuses.
ROUNDS = 3
#: How each binding limit is tightened in a round: (the :class:`MotorLimits` field, its factor).
BACK_OFF = {"commutation rate": ("speed_max", 0.8), "voltage at speed": ("v_use", 0.85),
            "torque angle": ("torque_angle_max", 0.85), "current": ("torque_angle_max", 0.85),
            "tracking on the drive": ("speed_max", 0.8)}


def back_off(limits: MotorLimits, binds: str, plan: PiecewisePlan) -> MotorLimits:
    """The limits with the binding one tightened by its :data:`BACK_OFF` factor.

    A speed cap is taken from the plan's peak speed where that is lower (a cap above it would change nothing).
    """
    name, factor = BACK_OFF[binds]
    value = getattr(limits, name)
    if name == "speed_max":
        t = np.linspace(plan.t0, plan.tf, 4001)
        peak = float(np.max(np.abs(plan.flag(t).dtheta)))
        value = peak if value is None else min(value, peak)
    return replace(limits, **{name: value * factor})


def tighter(limits: MotorLimits, other: MotorLimits) -> MotorLimits:
    """``limits`` with the torque angle, bus fraction and speed cap of ``other`` where those are tighter."""
    caps = [c for c in (limits.speed_max, other.speed_max) if c is not None]
    return replace(limits, torque_angle_max=min(limits.torque_angle_max, other.torque_angle_max),
                   v_use=min(limits.v_use, other.v_use), speed_max=min(caps) if caps else None)


def plan_for_drive(replan: Callable[[MotorLimits], PiecewisePlan], motor: MotorParams, limits: MotorLimits,
                   loop: Optional[DriveLoop], uncertainty: float = 0.1, rounds: int = ROUNDS,
                   controller: Optional[Callable[[PiecewisePlan], Controller]] = None,
                   derived: Optional[MotorLimits] = None,
                   check: Optional[Callable[[PiecewisePlan, MotorLimits], Verdict]] = None,
                   ) -> tuple[Optional[PiecewisePlan], MotorLimits, Verdict]:
    """Plan with ``limits``, verify on the drive, back off the binding limit and re-plan, ``rounds`` times at most.

    Parameters
    ----------
    replan : callable
        ``replan(limits) -> PiecewisePlan``: the planner (e.g. ``lambda lim: time_optimal(d, motor, lim)``); a
        ValueError means no plan within those limits.
    motor : MotorParams
        The nominal motor.
    limits : MotorLimits
        The first limits (e.g. :meth:`MotorLimits.for_drive`).
    loop : DriveLoop, optional
        The drive (only without ``check``).
    uncertainty : float
        The relative error of R, L, Km and J.
    rounds : int
        Back-off rounds after the first plan.
    controller : callable, optional
        ``controller(plan) -> Controller``; default :func:`drive_controller` (only without ``check``).
    derived : MotorLimits, optional
        The limits derived for this drive (:meth:`MotorLimits.for_drive`): when the first plan fails, the second
        is made within the :func:`tighter` of both, before the binding limit is backed off.
    check : callable, optional
        ``check(plan, limits) -> Verdict``: how a plan is checked (a scenario's: :func:`verify_scenario` on the
        scenario with that plan); default :func:`verify_plan` on ``loop``.

    Returns
    -------
    plan, limits, verdict
        The verified plan and its limits, or ``None``, the last limits and the last verdict (what binds).
    """
    if check is None:
        if loop is None:
            raise ValueError("plan_for_drive needs a loop (the drive) or a check")
        drive = loop

        def check(plan: PiecewisePlan, lim: MotorLimits) -> Verdict:
            return verify_plan(plan, motor, drive, None if controller is None else controller(plan), uncertainty, lim)

    history: list[dict[str, Any]] = []
    plan: Optional[PiecewisePlan] = None
    verdict = Verdict(False, [], 0.0, uncertainty=uncertainty)
    for k in range(rounds + 1):
        try:
            plan = replan(limits)
        except ValueError as exc:
            history.append(dict(round=k, refused=str(exc)))
            return None, limits, replace(verdict, rounds=history)
        verdict = check(plan, limits)
        history.append(dict(round=k, duration=plan.tf - plan.t0, status=verdict.status, binds=verdict.binds,
                            worst_error=verdict.worst_error, seconds=verdict.seconds))
        if verdict.verified:
            return plan, limits, replace(verdict, rounds=history)
        if k < rounds:
            assert verdict.binds is not None  # an unverified verdict names what binds
            both = tighter(limits, derived) if derived is not None else limits
            limits = both if k == 0 and both != limits else back_off(limits, verdict.binds, plan)
    return None, limits, replace(verdict, rounds=history)


def replan_steps(plan: PiecewisePlan, steps: list[tuple[str, float, float]], motor: MotorParams,
                 ) -> Callable[[MotorLimits], tuple[PiecewisePlan, list[tuple[str, float, float]]]]:
    """A planner that makes a time-optimal sequence's moves and dwells again under other limits.

    ``steps`` are a plan file's (label, start, duration): a ``dwell`` holds its angle as long; any other step is a
    move from the plan's angle at its start to its angle at its end (a move through via points included: the
    time-optimal planner makes it one move).
    """
    from ..plan.time_optimal import time_optimal

    ends = plan.theta_deriv(np.array([[s, s + d] for _, s, d in steps]).ravel(), 0).reshape(-1, 2)

    def make(limits: MotorLimits) -> tuple[PiecewisePlan, list[tuple[str, float, float]]]:
        parts, out, t = [], [], plan.t0
        for (label, _, duration), (a, b) in zip(steps, ends, strict=True):
            if label.startswith("dwell"):
                part = PiecewisePlan.hold(float(a), limits.i_hold, t, t + duration)
            else:
                part = time_optimal(float(b - a), motor, limits, theta1=float(a), t0=t)
            parts.append(part)
            out.append((label, t, part.tf - part.t0))
            t = part.tf
        return PiecewisePlan.concatenate(parts), out

    return make


def with_plan(scenario: Scenario, plan: Any, old_tf: float) -> Scenario:
    """``scenario`` running ``plan`` instead, its horizon moved with the plan's end (the same time after it).

    The controller is built again for the plan by :meth:`Scenario.controller` (the file's type, gains and
    measurement), as ``flatstep simulate`` builds it.
    """
    if plan is scenario.plan:
        return scenario
    return replace(scenario, plan=plan, t_end=max(scenario.t_end, plan.tf + (scenario.t_end - old_tf)))


def check_on_drive(pf: Any, planner: str, uncertainty: Optional[float] = None) -> tuple[Any, dict[str, Any]]:
    """A plan file's plan checked as ``flatstep simulate`` runs it, backed off when it is a time-optimal sequence.

    The check is :func:`verify_scenario` on the file's scenario: its ``[controller]``, ``[drive]``, ``[sensors]``,
    ``[observer]``, ``[plant]`` (effects), ``[load]`` and ``[feedforward]``, on its plant and the corners of
    ``uncertainty`` (default: ``[limits] uncertainty``, 0.1). The first plan is the file's; the second is made within
    the file's limits tightened to those derived for the drive (:meth:`MotorLimits.for_drive`, ``derived`` of
    :func:`plan_for_drive`), then the binding limit is backed off; each plan is checked with the file's law built
    for it. Returns the plan file with the verified plan (or the file's own, unverified) and plan.json's ``verify``
    entry.
    """
    assert pf.limits is not None, "the check runs a plan planned within [limits]"
    delta = pf.limits.uncertainty if uncertainty is None else uncertainty
    scenario = pf.scenario
    if planner != "time_optimal":
        verdict = verify_scenario(scenario, delta, pf.limits)
        return pf, dict(verdict.as_dict(), backed_off=False)
    made: dict[str, Any] = {}
    make = replan_steps(pf.plan, pf.steps, pf.motor)
    first = scenario.plan

    def replan(limits: MotorLimits) -> PiecewisePlan:
        made["plan"], made["steps"] = make(limits) if limits is not pf.limits else (first, pf.steps)
        return made["plan"]

    def check(plan: PiecewisePlan, limits: MotorLimits) -> Verdict:
        return verify_scenario(with_plan(scenario, plan, first.tf), delta, limits)

    loop = scenario.loop
    counts = loop.sensors.encoder_counts if loop is not None and loop.sensors is not None else None
    rate = 1.0 / loop.control_period if loop is not None else DEFAULT_CONTROL_RATE
    derived = MotorLimits.for_drive(pf.motor, v_bus=pf.limits.v_bus, i_max=pf.limits.i_max, control_rate=rate,
                                    encoder_counts=counts, uncertainty=delta)
    plan, limits, verdict = plan_for_drive(replan, pf.motor, pf.limits, loop, delta, derived=derived, check=check)
    info = dict(verdict.as_dict(), backed_off=len(verdict.rounds) > 1)
    if plan is None:
        info["suggested_limits"] = derived.as_dict()
        return pf, info
    info["limits"] = limits.as_dict()
    if plan is first:
        return pf, info
    return replace(pf, scenario=with_plan(scenario, plan, first.tf), limits=limits, steps=made["steps"]), info


#: The control rate [Hz] the limits are derived for when a file runs in continuous time.
DEFAULT_CONTROL_RATE = 20e3
