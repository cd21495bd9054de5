"""A scenario file's ``[plan]`` and ``[limits]``: the planner, its keys and waypoints -> one plan and its steps.

The planners and the keys each takes are :data:`flatstep.studies.scenario_keys.PLANNER_KEYS`; every value is
checked before any planning, and a refusal names ``file:plan.key`` (or ``plan.waypoints[i]``), the value, why and
what is valid.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Union

from ..model.motor import MotorParams
from ..plan.d_current import DCurrentPlan
from ..plan.limits import MotorLimits
from ..plan.piecewise import PiecewisePlan
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from ..plan.sequence import PLANNERS, Step, family_steps, optimal_sequence
from ..plan.time_optimal_dq import DEFAULT_RATE, VOLTAGES, time_optimal_dq
from ..plan.waypoints import Caps, Waypoint, plan_waypoints
from ..validate import InputError, check_bool, check_choice, check_finite, check_positive, check_quantity
from ..validate.checks import is_real
from ..validate.limits import MAX_OPTIMAL_MOVES
from .file_values import wrap
from .scenario_keys import CAPS, OLD_CAPS, PLANNER_KEYS

_WAYPOINT_KEYS = ("theta", "velocity", "dwell")


@dataclass(frozen=True)
class PlannedMove:
    """A file's plan: the planner, the plan, its moves and dwells, and the limits it was planned under."""

    planner: str
    plan: Union[RestToRest, PiecewisePlan]
    steps: list[Step]
    limits: Optional[MotorLimits]
    d_current: Optional[DCurrentPlan] = None  # the planned d current of a field-weakening plan


def _planner(where: str, table: dict[str, Any]) -> str:
    """The planner of ``[plan]``: given, or rest_to_rest when no waypoints are."""
    if "planner" not in table:
        if "waypoints" in table:
            raise InputError("planner", None, f"{where}:plan.planner: waypoints need a planner: give planner = one "
                                              f"of {list(PLANNERS[1:])} (plan files planned \"time_optimal\" when "
                                              "none was given)")
        return "rest_to_rest"
    try:
        return check_choice("planner", table["planner"], PLANNERS)
    except InputError as exc:
        raise exc.at(f"{where}:plan.planner") from None


def _check_planner_keys(where: str, planner: str, table: dict[str, Any]) -> None:
    """Refuse a key of ``[plan]`` that ``planner`` does not take, naming the planner and the keys it takes."""
    takes = PLANNER_KEYS[planner]
    for key in table:
        if key not in takes:
            raise InputError(key, table[key], f"{where}:plan.{key}: the {planner} planner does not take {key} "
                                              f"(given {table[key]!r}); it takes {list(takes)}")


def _number(where: str, name: str, value: Any, kind: Optional[str] = None) -> float:
    """A finite number (a bool or a string is refused), in the range ``kind`` if given, named ``file:name``."""
    try:
        return check_quantity(kind, value, as_name=name.rsplit(".", 1)[-1]) if kind else check_finite(name, value)
    except InputError as exc:
        raise exc.at(f"{where}:{name}") from None


def _waypoint(where: str, i: int, w: Any) -> Waypoint:
    """Waypoint ``i``: an angle [rad] or a table {theta, velocity, dwell}; a string or a bool is refused."""
    name = f"plan.waypoints[{i}]"
    if isinstance(w, dict):
        unknown = sorted(set(w) - set(_WAYPOINT_KEYS))
        if unknown or "theta" not in w:
            raise InputError(name, w, f"{where}:{name}: {w!r} must be an angle or a table with theta and optionally "
                                      f"velocity, dwell; {'unknown ' + str(unknown) if unknown else 'no theta'}")
        values = {k: _number(where, f"{name}.{k}", v) for k, v in w.items()}
    elif is_real(w) and not isinstance(w, bool):
        values = {"theta": w}
    else:
        raise InputError(name, w, f"{where}:{name}: {w!r} is not a number or a table; give an angle [rad] or "
                                  "{theta, velocity, dwell}")
    try:
        return Waypoint(**values)
    except InputError as exc:
        raise exc.at(f"{where}:{name}") from None


def _waypoints(where: str, raw: Any) -> list[Waypoint]:
    """The waypoint list: 2 to MAX_OPTIMAL_MOVES + 1 of them, counted before any is read."""
    if not isinstance(raw, list):
        raise InputError("waypoints", raw, f"{where}:plan.waypoints: waypoints={raw!r} must be a list of angles or "
                                           "tables {theta, velocity, dwell}")
    if not 2 <= len(raw) <= MAX_OPTIMAL_MOVES + 1:
        raise InputError("waypoints", len(raw), f"{where}:plan.waypoints: {len(raw)} waypoint(s) are "
                         f"{max(len(raw) - 1, 0)} moves; a sequence has 1 to {MAX_OPTIMAL_MOVES} moves "
                         "(flatstep.validate.limits.MAX_OPTIMAL_MOVES): split a longer one into several files")
    return [_waypoint(where, i, w) for i, w in enumerate(raw)]


def _caps(where: str, raw: Any) -> Caps:
    """``[plan] caps``: speed_max, accel_max and jerk_max."""
    if not isinstance(raw, dict):
        raise InputError("caps", raw, f"{where}:plan.caps: caps={raw!r} must be a table {{speed_max, accel_max, "
                                      "jerk_max}")
    for key in raw:
        if key in OLD_CAPS:
            raise InputError(key, raw[key], f"{where}:plan.caps.{key}: caps.{key} is an old name: rename it "
                                            f"caps.{OLD_CAPS[key]}")
    if set(raw) != set(CAPS):
        raise InputError("caps", raw, f"{where}:plan.caps: caps={raw!r} must give exactly {list(CAPS)}")
    v = {}
    for key in CAPS:
        try:
            v[key] = check_positive(key, raw[key])
        except InputError as exc:
            raise exc.at(f"{where}:plan.caps.{key}") from None
    return Caps(v_max=v["speed_max"], a_max=v["accel_max"], j_max=v["jerk_max"])


def _durations(where: str, raw: Any, moves: int) -> list[float]:
    """``[plan] durations``: one duration > 0 [s] per move."""
    if not isinstance(raw, list) or len(raw) != moves:
        raise InputError("durations", raw, f"{where}:plan.durations: durations={raw!r} must be a list of {moves} "
                                           f"durations [s], one per move between the {moves + 1} waypoints")
    out = []
    for i, d in enumerate(raw):
        try:
            out.append(check_positive(f"durations[{i}]", d, unit=" s"))
        except InputError as exc:
            raise exc.at(f"{where}:plan.durations[{i}]") from None
    return out


def read_limits(where: str, table: dict[str, Any], v_bus: Optional[float]) -> Optional[MotorLimits]:
    """``[limits]`` as :class:`MotorLimits` on the bus ``v_bus`` (``[drive] v_bus``); ``None`` without it."""
    if not table:
        return None
    if "i_max" not in table:
        raise InputError("i_max", None, f"{where}:limits.i_max: [limits] needs i_max, the largest current-vector "
                                        "magnitude [A] a plan may ask")
    if v_bus is None:
        raise InputError("v_bus", None, f"{where}:drive.v_bus: [limits] plans against the bus: give [drive] v_bus "
                                        "(and [drive] control_rate)")
    for key, value in table.items():
        if not (is_real(value) and not isinstance(value, bool)):
            raise InputError(key, value, f"{where}:limits.{key}: {key}={value!r} is not a number; give a finite "
                                         "real value")
    return wrap(where, "limits", MotorLimits, v_bus=v_bus, **table)


def _field_weakening(where: str, given: dict[str, Any], points: list[Waypoint], motor: MotorParams,
                     limits: MotorLimits, t0: float, control_rate: Optional[float]) -> PlannedMove:
    """One field-weakening move between two waypoints (:func:`flatstep.plan.time_optimal_dq.time_optimal_dq`)."""
    try:
        voltage = check_choice("voltage", given.get("voltage", "phase"), VOLTAGES)
    except InputError as exc:
        raise exc.at(f"{where}:plan.voltage") from None
    if given.get("through", False) is not False:
        raise InputError("through", given["through"], f"{where}:plan.through: field_weakening plans one move from "
                                                      "rest to rest; leave through out")
    if len(points) != 2 or any(p.velocity is not None or p.dwell for p in points):
        raise InputError("waypoints", given["waypoints"], f"{where}:plan.waypoints: field_weakening plans one move: "
                         "give two waypoints (start and end angles), without velocity or dwell")
    theta1, theta2 = points[0].theta, points[1].theta
    try:
        fw = time_optimal_dq(theta2 - theta1, motor, limits, theta1=theta1, t0=t0, voltage=voltage,
                             control_rate=DEFAULT_RATE if control_rate is None else control_rate)
    except InputError as exc:
        raise exc.at(f"{where}:plan.waypoints") from None
    except ValueError as exc:
        raise ValueError(f"{where}:plan: {exc}") from None
    # limits None: the (rho, theta) margins of flatstep.plan.margins do not apply; the planner measured the d-q ones
    return PlannedMove("time_optimal", fw.plan, [(f"move {theta1:g} -> {theta2:g}", t0, fw.plan.tf - t0)], None,
                       fw.d_current)


def read_plan(where: str, table: dict[str, Any], motor: MotorParams, limits: Optional[MotorLimits],
              has_motor: bool, control_rate: Optional[float] = None) -> PlannedMove:
    """``[plan]`` planned (module docstring); ``has_motor``: the file gives ``[motor]``.

    ``control_rate`` [Hz] is the drive's, which caps a field-weakening plan's speed (default: time_optimal_dq's).
    """
    planner = _planner(where, table)
    _check_planner_keys(where, planner, table)
    given = {k: v for k, v in table.items() if k != "planner"}
    if planner == "rest_to_rest":
        plan = wrap(where, "plan", RestToRest, **{**PAPER_PLAN.as_dict(), **given})
        return PlannedMove(planner, plan, [(f"move {plan.theta1:g} -> {plan.theta2:g}", plan.t0, plan.tf - plan.t0)],
                           limits)
    if not has_motor:
        raise InputError("motor", None, f"{where}:motor: a waypoint plan names its motor: give [motor] (preset or "
                                        "R, L, Km, J, B, Nr; plan files ran on \"nema17\" when none was given)")
    if "waypoints" not in given:
        raise InputError("waypoints", None, f"{where}:plan.waypoints: the {planner} planner needs waypoints")
    points = _waypoints(where, given["waypoints"])
    t0 = _number(where, "plan.t0", given.get("t0", 0.0), "time")
    if planner == "time_optimal":
        try:
            through = check_bool("through", given.get("through", False))
        except InputError as exc:
            raise exc.at(f"{where}:plan.through") from None
        if limits is None:
            raise InputError("limits", None, f"{where}:limits: the time_optimal planner plans against the motor's "
                                             "limits: give [limits] i_max (and [drive] v_bus)")
        try:
            weakening = check_bool("field_weakening", given.get("field_weakening", False))
        except InputError as exc:
            raise exc.at(f"{where}:plan.field_weakening") from None
        if weakening:
            return _field_weakening(where, given, points, motor, limits, t0, control_rate)
        if "voltage" in given:
            raise InputError("voltage", given["voltage"], f"{where}:plan.voltage: the bus limit is chosen for a "
                                                          "field-weakening plan: give field_weakening = true")
    else:
        rho = _number(where, "plan.rho", given.get("rho", 0.5), "current")
        caps = _caps(where, given["caps"]) if "caps" in given else None
        durations = _durations(where, given["durations"], len(points) - 1) if "durations" in given else None
    try:  # the planners' own refusals: waypoints too close, a speed where a rest is due, neither durations nor caps
        if planner == "time_optimal":
            assert limits is not None
            segments, steps = optimal_sequence(points, motor, limits, t0, through)
        else:
            segments = plan_waypoints(points, family=planner, rho=rho, t0=t0, durations=durations, caps=caps)
            steps = family_steps(segments, points, planner)
    except InputError as exc:
        raise exc.at(f"{where}:plan.waypoints") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}:plan: {exc}") from None
    return PlannedMove(planner, segments, steps, limits)
