"""Plan files (TOML): a motor, its limits and a list of waypoints -> one piecewise plan and its moves.

::

    name = "ten waypoints"
    [motor]
    preset = "nema17"          # or R, L, Km, J, B, Nr, or datasheet keys (docs/motors.md)
    [limits]                   # flatstep.plan.limits.MotorLimits
    v_bus = 24.0
    i_max = 1.0
    [plan]
    planner = "time_optimal"   # or a segment family: "psi", "hermite", "spline", "scurve"
    t0 = 0.005                 # when the sequence starts [s]
    rho = 0.4                  # the families' constant current magnitude [A]
    caps = {v_max = 100.0, a_max = 2e4, j_max = 1e7}   # the families' speed, acceleration and jerk caps
    durations = [0.05, 0.05]   # or each move's duration (psi, hermite, spline)
    through = false            # time_optimal: true passes a waypoint at speed where the motion keeps its direction
    waypoints = [0.0, {theta = 2.0, dwell = 0.02}, {theta = 5.0, velocity = 10.0}]

The time_optimal planner rests at every waypoint unless ``through = true``: then a run of waypoints in one
direction without a dwell is one move, the fastest over the run, which passes the waypoints inside it at the
speed it has there (on one axis the fastest path through them; :func:`runs`). It still rests where the motion
reverses, where a dwell is asked and at the end.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..model.datasheet import motor_from_table, uses_datasheet
from ..model.motor import MotorParams
from ..validate import InputError, check_quantity
from ..validate.limits import MAX_OPTIMAL_MOVES
from .limits import MotorLimits
from .piecewise import PiecewisePlan
from .time_optimal import time_optimal
from .waypoints import FAMILIES, Caps, Waypoint, plan_waypoints

#: The shortest move between two waypoints [rad] (well below an encoder count; a shorter one is a dwell).
MIN_MOVE = 1e-6

PLANNERS = ("time_optimal",) + FAMILIES
_KEYS = {"": ("name", "description", "motor", "limits", "plan", "simulate"),
         "plan": ("planner", "t0", "rho", "caps", "durations", "through", "waypoints"),
         "simulate": ("control_rate", "t_after")}


@dataclass(frozen=True)
class PlanFile:
    """What a plan file holds, planned: the table, its moves and dwells, the motor and its limits."""

    name: str
    motor: MotorParams
    limits: Optional[MotorLimits]
    plan: PiecewisePlan
    #: (label, start [s], duration [s]) of each move and dwell, in order
    steps: list[tuple[str, float, float]]
    #: the [simulate] settings: control_rate [Hz], t_after [s]
    simulate: dict[str, float]


def _check(where: str, table: dict[str, Any], section: str) -> dict[str, Any]:
    """The section's keys, or a ValueError naming an unknown one."""
    if not isinstance(table, dict):
        raise ValueError(f"{where}: [{section}] must be a table")
    if section in _KEYS:
        unknown = set(table) - set(_KEYS[section])
        if unknown:
            raise ValueError(f"{where}: unknown key(s) {sorted(unknown)} in [{section or 'top level'}]; "
                             f"valid: {list(_KEYS[section])}")
    return table


def _motor(where: str, table: dict[str, Any]) -> MotorParams:
    """The [motor] section: a preset, parameters, or a preset with some parameters changed."""
    if uses_datasheet(table):
        return motor_from_table(table, where).params
    table = dict(table)
    base = MotorParams.preset(str(table.pop("preset", "nema17")))
    try:
        return base.replace(**table) if table else base
    except InputError as exc:
        raise exc.at(f"{where}:motor.{exc.name}") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: [motor]: {exc}") from None


def _limits(where: str, table: dict[str, Any]) -> Optional[MotorLimits]:
    """The [limits] section (:class:`MotorLimits`), or None when the file has none."""
    try:
        return MotorLimits(**table) if table else None
    except InputError as exc:
        raise exc.at(f"{where}:limits.{exc.name}") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: [limits]: {exc}") from None


def _simulate_settings(where: str, table: dict[str, Any]) -> dict[str, float]:
    """The [simulate] section: the drive's control rate [Hz] and the time simulated after the move [s]."""
    out = {"control_rate": 20000.0, "t_after": 0.02}
    for key, kind in (("control_rate", "rate"), ("t_after", "time")):
        if key in table:
            try:
                out[key] = check_quantity(kind, table[key], as_name=key)
            except InputError as exc:
                raise exc.at(f"{where}:simulate.{key}") from None
    return out


def is_plan_file(path: Union[str, Path]) -> bool:
    """Whether ``path`` reads as a plan file, not a scenario file: it has [limits] or waypoints in [plan].

    A file that cannot be read or parsed is not one (the scenario reader then says why).
    """
    try:
        doc = tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
    plan = doc.get("plan")
    return "limits" in doc or (isinstance(plan, dict) and ("waypoints" in plan or "planner" in plan))


def _waypoint(where: str, i: int, w: Union[float, dict[str, Any]]) -> Waypoint:
    """One waypoint of the list: a number or a table with theta, velocity, dwell."""
    try:
        return Waypoint(**w) if isinstance(w, dict) else Waypoint(float(w))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: [plan] waypoints[{i}]={w!r}: {exc}") from None


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


def _optimal_sequence(points: list[Waypoint], motor: MotorParams, limits: MotorLimits, t0: float,
                      through: bool = False) -> tuple[PiecewisePlan, list[tuple[str, float, float]]]:
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


def _family_steps(plan: PiecewisePlan, points: list[Waypoint], family: str) -> list[tuple[str, float, float]]:
    """Moves and dwells of a family's plan.

    A dwell is a segment of constant theta; a move ends at the first break at its waypoint, at rest there if the
    family rests there.
    """
    dwell = np.all(plan.theta[:, :-1] == 0, axis=1)
    at, speed = plan.theta_deriv(plan.breaks[1:], 0), plan.theta_deriv(plan.breaks[1:] - 1e-12 * plan.tf, 1)
    steps: list[tuple[str, float, float]] = []
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


def load_plan_file(path: Union[str, Path]) -> PlanFile:
    """Read and plan a plan file (module docstring); ValueErrors name the file and the faulty key."""
    path = Path(path)
    where = str(path)
    try:
        doc = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise ValueError(f"{where}: no such plan file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML: {exc}") from None
    _check(where, doc, "")
    motor = _motor(where, _check(where, doc.get("motor", {}), "motor"))
    limits = _limits(where, _check(where, doc.get("limits", {}), "limits"))
    settings = _simulate_settings(where, _check(where, doc.get("simulate", {}), "simulate"))
    sec = _check(where, doc.get("plan", {}), "plan")
    planner = sec.get("planner", "time_optimal")
    if planner not in PLANNERS:
        raise ValueError(f"{where}: [plan] planner={planner!r}; valid: {PLANNERS}")
    raw = sec.get("waypoints")
    if not isinstance(raw, list):
        raise ValueError(f"{where}: [plan] waypoints must be a list of angles or tables {{theta, velocity, dwell}}")
    points = [_waypoint(where, i, w) for i, w in enumerate(raw)]
    try:
        t0 = check_quantity("time", sec.get("t0", 0.0), as_name="t0")
    except ValueError as exc:
        raise ValueError(f"{where}:plan.t0: {exc}") from None
    through = sec.get("through", False)
    if not isinstance(through, bool):
        raise ValueError(f"{where}: [plan] through={through!r} must be true or false")
    if through and planner != "time_optimal":
        raise ValueError(f"{where}: [plan] through = true is for the time_optimal planner; the {planner!r} family "
                         "passes a waypoint at the velocity it gives (or its own choice)")
    try:
        if planner == "time_optimal":
            if limits is None:
                raise ValueError("the time_optimal planner needs a [limits] section (v_bus, i_max)")
            if len(points) < 2:
                raise ValueError(f"{len(points)} waypoint(s): a move needs at least 2")
            if len(points) - 1 > MAX_OPTIMAL_MOVES:
                raise ValueError(f"{len(points)} waypoints are {len(points) - 1} time-optimal moves, above the limit "
                                 f"of {MAX_OPTIMAL_MOVES} (flatstep.validate.limits.MAX_OPTIMAL_MOVES, under 1 ms "
                                 "of planning each); split the sequence into several files, or use a spline planner")
            plan, steps = _optimal_sequence(points, motor, limits, t0, through)
        else:
            caps = Caps(**sec["caps"]) if "caps" in sec else None
            plan = plan_waypoints(points, family=planner, rho=float(sec.get("rho", 0.5)), t0=t0,
                                  durations=sec.get("durations"), caps=caps)
            steps = _family_steps(plan, points, planner)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: [plan]: {exc}") from None
    return PlanFile(str(doc.get("name", path.stem)), motor, limits, plan, steps, settings)
