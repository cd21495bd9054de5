"""Waypoint sequences: the moves and dwells of a time-optimal sequence or a segment family's plan.

:func:`optimal_sequence` plans time-optimal moves through waypoints; it rests at every waypoint unless
``through``: then a run of waypoints in one direction without a dwell is one move, the fastest over the run, which
passes the waypoints inside it at the speed it has there (on one axis the fastest path through them; :func:`runs`).
It still rests where the motion reverses, where a dwell is asked and at the end. :func:`family_steps` finds the
moves and dwells of a segment family's plan (:func:`flatstep.plan.waypoints.plan_waypoints`). A scenario file's
``[plan]`` (docs/scenario-reference.md) chooses among :data:`PLANNERS`.
"""
from __future__ import annotations

import numpy as np

from ..model.motor import MotorParams
from .limits import MotorLimits
from .piecewise import PiecewisePlan
from .time_optimal import time_optimal
from .waypoints import FAMILIES, Waypoint

#: The shortest move between two waypoints [rad] (well below an encoder count; a shorter one is a dwell).
MIN_MOVE = 1e-6

#: The planners of a scenario file's [plan]: the paper's move, the time-optimal sequence, the segment families.
PLANNERS = ("rest_to_rest", "time_optimal") + FAMILIES
#: One move and dwell of a sequence: (label, start [s], duration [s]).
Step = tuple[str, float, float]


def _label(i: int) -> str:
    """The label of the move from waypoint i to i + 1."""
    return f"move {i} -> {i + 1}"


def runs(points: list[Waypoint]) -> list[tuple[int, int]]:
    """The moves ``(i, j)`` of a time-optimal sequence through ``points`` that rests only where it must.

    A move from waypoint ``i`` goes on through the next waypoints while the motion keeps its direction and no
    dwell is asked there; it ends at ``j``, where it reverses, dwells, or the list ends.
    """
    moves, i = [], 0
    while i + 1 < len(points):
        sign, j = np.sign(points[i + 1].theta - points[i].theta), i + 1
        while (j + 1 < len(points) and points[j].dwell == 0
               and np.sign(points[j + 1].theta - points[j].theta) == sign):
            j += 1
        moves.append((i, j))
        i = j
    return moves


def optimal_sequence(points: list[Waypoint], motor: MotorParams, limits: MotorLimits, t0: float,
                      through: bool = False) -> tuple[PiecewisePlan, list[Step]]:
    """Time-optimal moves through the waypoints, with their dwells (velocities: rests).

    From rest to rest at every waypoint, or with ``through`` only at the ends of :func:`runs`.
    """
    for i, p in enumerate(points):
        if p.velocity not in (None, 0.0):
            raise ValueError(f"waypoint {i}: velocity={p.velocity!r} rad/s; the time_optimal planner chooses the "
                             "speed at a waypoint (0, or what it has there with through = true): give 0 or None")
        if i + 1 < len(points) and abs(points[i + 1].theta - p.theta) < MIN_MOVE:
            raise ValueError(f"waypoints {i} and {i + 1} sit at {p.theta} and {points[i + 1].theta} rad, less "
                             f"than {MIN_MOVE:g} rad apart: give a rest as a dwell, or merge them")
    moves = runs(points) if through else [(i, i + 1) for i in range(len(points) - 1)]
    parts: list[tuple[str, PiecewisePlan]] = []
    t = t0
    if points[0].dwell > 0:
        parts.append(("dwell at 0", PiecewisePlan.hold(points[0].theta, limits.i_hold, t, t + points[0].dwell)))
        t = parts[-1][1].tf
    for i, j in moves:
        label = f"move {i} -> {j}" + (f" (through {', '.join(str(k) for k in range(i + 1, j))})" if j > i + 1 else "")
        parts.append((label, time_optimal(points[j].theta - points[i].theta, motor, limits, theta1=points[i].theta,
                                          t0=t)))
        t = parts[-1][1].tf
        if points[j].dwell > 0:
            parts.append((f"dwell at {j}", PiecewisePlan.hold(points[j].theta, limits.i_hold, t, t + points[j].dwell)))
            t = parts[-1][1].tf
    steps = [(label, part.t0, part.tf - part.t0) for label, part in parts]
    return PiecewisePlan.concatenate([part for _, part in parts]), steps


def family_steps(plan: PiecewisePlan, points: list[Waypoint], family: str) -> list[Step]:
    """Moves and dwells of a family's plan.

    A dwell is a segment of constant theta; a move ends at the first break at its waypoint, at rest there if the
    family rests there.
    """
    dwell = np.all(plan.theta[:, :-1] == 0, axis=1)
    at, speed = plan.theta_deriv(plan.breaks[1:], 0), plan.theta_deriv(plan.breaks[1:] - 1e-12 * plan.tf, 1)
    steps: list[Step] = []
    k, start = 0, plan.t0
    for i in range(plan.n):
        if dwell[i]:
            steps.append((f"dwell at {k}", float(plan.breaks[i]), float(plan.durations[i])))
            start = plan.breaks[i + 1]
            continue
        nxt = k + 1
        rest = nxt == len(points) - 1 or points[min(nxt, len(points) - 1)].dwell > 0 or family in ("psi", "scurve")
        if nxt < len(points) and abs(at[i] - points[nxt].theta) < 1e-9 and (not rest or abs(speed[i]) < 1e-6):
            steps.append((_label(k), float(start), float(plan.breaks[i + 1] - start)))
            k, start = nxt, plan.breaks[i + 1]
    return steps
