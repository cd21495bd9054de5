r"""The fastest rest-to-rest move the motor and its bus can make: a speed-dependent envelope, smoothed and checked.

This module is the readable reference; csrc/time_optimal.c runs the same algorithm (``engine="c"``, the default)
and the two agree on the planned durations to rounding (tests/test_plan_time_optimal_c.py).

**Stages.** :mod:`flatstep.plan.envelope` gives the speed-dependent acceleration envelope at a fraction
:math:`\gamma` of the bus and the bang-bang move on it (with :math:`\gamma = 1` and no inductance, the lower bound
:func:`bang_bang_time`); :mod:`flatstep.plan.smoothing` smooths that move twice by a box, fits it as a table of
degree-7 segments with :math:`\rho^*`, and measures the table's margins.

**Search.** The inductance needs voltage headroom, which the envelope's :math:`\gamma < 1` leaves. The table's
worst margin :math:`s(\gamma)` (:func:`table_margins`: the voltage over ``0.998 v_use``, every other ratio over
1, less 1) is driven to 0 by :func:`search_width`: the proportional guess :math:`\gamma/(1 + s)`, the secant,
then regula falsi (Illinois) once a bracket is measured, in at most ``_SEARCH`` tables, from a first gamma
predicted by the steady voltage at a cruising move's peak speed (:func:`first_gamma`). :func:`plan_move` walks
the smoothing widths (multiples of :math:`L/R`) from the middle one towards shorter plans; the shortest feasible
table wins.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from ..validate import InputError, check_quantity, check_sequence, short_repr
from ..validate import limits as limits_mod
from ..validate.checks import is_real
from ..validate.limits import MAX_OPTIMAL_MOVES, MAX_PLAN_SAMPLES
from .arguments import check_angle, check_engine, check_limits, check_motor, check_t0
from .envelope import Envelope, bang_bang, bang_bang_time, envelope, iq_bounds, voltage_excess
from .limits import MotorLimits
from .piecewise import NCOEF, PiecewisePlan
from .smoothing import (
    DEFAULT_WIDTHS,
    MAX_SEGMENTS,
    V_MARGIN,
    Table,
    check_samples,
    planning_limits,
    smoothed_duration,
    smoothed_table,
    table_margins,
    timing,
)

Array = NDArray[np.float64]
__all__ = ["DEFAULT_WIDTHS", "MAX_SEGMENTS", "Candidate", "bang_bang_time", "iq_bounds", "plan_move",
           "smoothed_duration", "smoothed_plan", "time_optimal", "time_optimal_sequence"]
_SEARCH = 6          # tables tried per width on gamma, at most
_GAMMA_MIN = 0.05    # the least bus fraction a plan may take
_GAMMA_STEPS = 2.0**16  # gamma is tried on multiples of 1 / _GAMMA_STEPS (csrc/time_optimal.c does the same)
_S_TOL = 0.003       # a feasible table within 0.3 % of the bus target ends a width's search
_PEAK_OVER_STEADY = 0.994  # a table's peak voltage over the steady one at its move's peak speed (first_gamma)


class Candidate(NamedTuple):
    """A table the search tried: its duration [s], the bus fraction, the width [s], its margins and the table."""

    tf: float
    gamma: float
    width: float
    margins: dict[str, float]
    table: Table


def _try(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float,
         width: float) -> Optional[Candidate]:
    """The table at ``gamma`` and ``width`` (planned within :func:`planning_limits`) and its margins.

    None when the move would take more than ``MAX_PLAN_SAMPLES`` samples.
    """
    plan = planning_limits(limits)
    env = envelope(motor, plan, gamma)
    if timing(distance, env, width).n > MAX_PLAN_SAMPLES:
        return None
    table = smoothed_table(distance, env, width, motor, plan)
    return Candidate(float(table.breaks[-1]), gamma, width, table_margins(table, motor, limits), table)


def _duration(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float, width: float) -> float:
    """The duration [s] of the table at ``gamma`` and ``width`` from its timing alone, before the table is built.

    0 when the table would not be built (the motor cannot start, or the move has too many samples): the search
    then tries it and measures the failure as before.
    """
    try:
        tm = timing(distance, envelope(motor, planning_limits(limits), gamma), width)
    except ValueError:
        return 0.0
    return 0.0 if tm.n > MAX_PLAN_SAMPLES else (tm.n + 2 * (tm.n_box - 1) - 1) * tm.dt


def search_width(distance: float, motor: MotorParams, limits: MotorLimits, width: float,
                 start: float = 1.0, bound: float = math.inf) -> Optional[Candidate]:
    """The regula falsi on gamma at ``width`` from ``start`` (module docstring): its shortest feasible table or None.

    Until both a feasible and an infeasible gamma are known, the next guess is the secant through the last two
    tables, or scales gamma by ``1 / (1 + s)`` after one (the voltage about proportional to gamma); then regula
    falsi (Illinois) inside the bracket; every guess aims at ``s = -_S_TOL / 2``, inside the accepted band. It
    stops at a feasible table within ``_S_TOL`` of the bus target, at a feasible gamma of 1, after ``_SEARCH``
    tables, at an infeasible table not shorter than ``bound`` [s] (every feasible gamma lies below it, and is
    slower still), or, after an infeasible table, at a guess whose duration (:func:`_duration`, known before its
    table) is not shorter than the best: the guess estimates the feasible gamma, and a table slower than the best
    cannot win (a heuristic: a feasible gamma well above the guess would be missed).
    """
    best: Optional[Candidate] = None
    lo, hi, s_lo, s_hi = 0.0, 1.0, math.nan, math.nan  # nan: not measured
    side, g, g_last, s_last = 0, start, math.nan, math.nan
    g_prev, s_prev = math.nan, math.nan  # the point before the last, for the secant
    for _ in range(_SEARCH):
        g = float(np.rint(g * _GAMMA_STEPS)) / _GAMMA_STEPS  # on a grid: the C planner tries the same gamma
        if g < _GAMMA_MIN:
            break
        if side == 1 and _duration(distance, motor, limits, g, width) >= min(bound, best.tf if best else math.inf):
            break  # below an infeasible gamma, the guess of the bus target is no faster than the best: no table
        try:
            c: Optional[Candidate] = _try(distance, motor, limits, g, width)
            s = c.margins["worst"] if c is not None else math.inf
        except ValueError:  # the motor cannot start at this gamma
            c, s = None, math.inf
        aim = s + 0.5 * _S_TOL  # the guesses aim at the middle of the accepted band (-_S_TOL, 0]
        g_last, s_last, g_prev, s_prev = g, aim, g_last, s_last
        if c is not None and s <= 0:
            if best is None or c.tf < best.tf:
                best = c
            lo, s_lo = g, aim
            if g >= 1.0 or s > -_S_TOL:
                break
            if side == -1 and not math.isnan(s_hi):
                s_hi *= 0.5  # Illinois: the end kept twice in a row counts half
            side = -1
        else:
            if c is not None and c.tf >= min(bound, best.tf if best is not None else math.inf):
                break
            hi, s_hi = g, aim
            if side == 1 and not math.isnan(s_lo):
                s_lo *= 0.5
            side = 1
        if hi - lo < 1e-4:
            break
        if not math.isnan(s_lo) and math.isfinite(s_hi):  # a bracket: regula falsi
            g = lo + (hi - lo) * s_lo / (s_lo - s_hi)
        elif math.isfinite(s_last) and math.isfinite(s_prev) and s_last != s_prev:  # one side: the secant
            g = g_last - s_last * (g_last - g_prev) / (s_last - s_prev)
            g = min(max(g, 0.5 * g_last), 1.5 * g_last)
        elif math.isfinite(s_last):  # one point: the voltage about proportional to gamma
            g = g_last / (1.0 + s_last)
        else:  # an infinite measure: halve the bracket
            g = 0.5 * (lo + hi)
        if not math.isnan(s_hi):  # inside a measured bracket
            g = min(max(g, lo + 0.02 * (hi - lo)), hi - 0.02 * (hi - lo))
        g = min(g, 1.0)
    return best


def smoothed_plan(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float, width: float, *,
                  theta1: float = 0.0, t0: float = 0.0) -> PiecewisePlan:
    """The bang-bang move on the envelope at ``gamma``, smoothed twice by a box of ``width`` [s], as a plan."""
    distance, theta1, t0 = check_angle(distance, "distance"), check_angle(theta1, "theta1"), check_t0(t0)
    check_motor(motor)
    check_limits(limits)
    gamma = check_quantity("fraction", gamma, as_name="gamma")
    lo, hi = limits_mod.MIN_SMOOTHING_WIDTH, limits_mod.MAX_SMOOTHING_WIDTH
    if not (is_real(width) and math.isfinite(width) and lo <= width <= hi):
        raise InputError("width", width, f"width={width!r}: a smoothing width is a number of seconds in "
                         f"[{lo:g}, {hi:g}] (flatstep.validate.limits.MIN_SMOOTHING_WIDTH, MAX_SMOOTHING_WIDTH)")
    if abs(distance) < limits_mod.MIN_MOVE_DISTANCE:
        raise InputError("distance", distance, f"distance={distance!r} rad: a move needs at least "
                         f"{limits_mod.MIN_MOVE_DISTANCE:g} rad (flatstep.validate.limits.MIN_MOVE_DISTANCE)")
    table = smoothed_table(abs(distance), envelope(motor, limits, gamma), width, motor, limits)
    return _plan(table, distance, theta1, t0)


def _plan(table: Table, distance: float, theta1: float, t0: float, from_c: bool = False) -> PiecewisePlan:
    """The plan of a table planned over ``|distance|`` from 0 at t = 0: mirrored for a negative distance, shifted.

    ``from_c``: the table is csrc/time_optimal.c's own, whose search checked rho > 0 (PiecewisePlan._of_checked_table).
    """
    theta = (1.0 if distance >= 0 else -1.0) * table.theta
    theta[:, -1] += theta1
    if from_c:
        return PiecewisePlan._of_checked_table(table.breaks + t0, theta, table.rho)
    return PiecewisePlan(table.breaks + t0, theta, table.rho)


def first_gamma(distance: float, motor: MotorParams, limits: MotorLimits, full: Envelope) -> float:
    """The first bus fraction the search tries: predicted from the steady voltage at the full-bus move's peak speed.

    The full-bus bang-bang move over ``distance`` on ``full`` (the envelope at gamma = 1 within the planning
    ``limits``) peaks at the speed ``w_peak``; the steady voltage there, on the envelope's torque current of
    either side, times ``_PEAK_OVER_STEADY``, predicts the table's peak voltage at gamma = 1. Its measure ``s``
    predicted so, the guess ``1 / (1 + s + _S_TOL / 2)`` aims at the middle of the accepted band (at most 1).
    Only a move that cruises holds its peak speed long enough for this; any other starts on the full bus (the
    smoothing lowers a short move's peak, and the inductance rather than the steady voltage sets its margin).
    A poor guess costs a table, never feasibility: the search measures every table.
    """
    m, b = motor, bang_bang(distance, full)
    if not b.cruise > 0:
        return 1.0
    w = b.w_peak
    v2 = 0.0
    for a in (np.interp(w, full.omega, full.a_plus), np.interp(w, full.omega, full.a_minus)):
        u = (m.J * float(a) + m.B * w) / m.Km
        v2 = max(v2, float(voltage_excess(np.array([u]), np.array([w]), m, limits, 0.0)[0][0]))
    s = _PEAK_OVER_STEADY * math.sqrt(v2) / (V_MARGIN * limits.v_use * limits.v_bus) - 1.0
    return min(1.0, 1.0 / (1.0 + s + 0.5 * _S_TOL))


def plan_move(distance: float, motor: MotorParams, limits: MotorLimits,
              widths: Optional[tuple[float, ...]] = None) -> Candidate:
    """The shortest feasible candidate over ``distance`` != 0 (module docstring); a ValueError when there is none.

    The widths, sorted, are searched from the middle one outwards: down while the duration falls, then up while
    it falls unless the way down found a shorter table (the duration first falls, then rises with the width);
    infeasible widths do not stop a walk before a feasible one is found, and an infeasible middle width sends the
    search both ways. Each width's search starts at the gamma the previous feasible width found.
    """
    d = abs(check_angle(distance, "distance"))
    check_motor(motor)
    check_limits(limits)
    _check_widths(widths)
    ws = sorted(widths or tuple(k * (motor.L / motor.R) for k in DEFAULT_WIDTHS))
    full = envelope(motor, planning_limits(limits), 1.0)
    best: Optional[Candidate] = None

    for w in ws:
        check_samples(distance, timing(d, full, w))
    start = first_gamma(d, motor, planning_limits(limits), full)

    def run(i: int) -> float:
        nonlocal best, start
        tm = timing(d, full, ws[i])
        # the duration falls as gamma rises: a width whose full-bus move is not shorter than the best cannot win
        if best is not None and (tm.n + 2 * (tm.n_box - 1) - 1) * tm.dt >= best.tf:
            return math.inf
        c = search_width(d, motor, limits, ws[i], start, best.tf if best is not None else math.inf)
        if c is None:
            return math.inf
        start = c.gamma
        if best is None or c.tf < best.tf:
            best = c
        return c.tf

    def walk(i: int, step: int, f: float) -> bool:
        """Whether a width beyond ws[i - step] was shorter; walks while the duration falls."""
        better = False
        while 0 <= i < len(ws):
            fi = run(i)
            if fi < f:
                better, f = True, fi
            elif f < math.inf:
                break
            i += step
        return better

    i0 = len(ws) // 2
    f0 = run(i0)
    if not walk(i0 - 1, -1, f0) or f0 == math.inf:  # an infeasible middle width: both ways
        walk(i0 + 1, 1, f0)
    if best is None:
        raise ValueError(f"no feasible plan of {distance} rad within {limits}: raise v_bus or i_max, lower i_hold or "
                         "i_run, or split the move with waypoints")
    return best


def _check_widths(widths: Optional[tuple[float, ...]]) -> None:
    """Raises an InputError unless ``widths`` is None or 1 to 8 finite smoothing widths within the documented range."""
    if widths is None:
        return
    top = limits_mod.MAX_SMOOTHING_WIDTHS
    if not isinstance(widths, (tuple, list, np.ndarray)) or not 1 <= len(widths) <= top:
        raise InputError("widths", widths, f"widths={short_repr(widths)}: give a tuple of 1 to {top} smoothing "
                         "widths [s] (flatstep.validate.limits.MAX_SMOOTHING_WIDTHS)")
    lo, hi = limits_mod.MIN_SMOOTHING_WIDTH, limits_mod.MAX_SMOOTHING_WIDTH
    for w in widths:
        if not (is_real(w) and math.isfinite(w) and lo <= w <= hi):
            raise InputError("widths", widths, f"widths={widths!r}: every smoothing width must be a number of seconds "
                             f"in [{lo:g}, {hi:g}] (flatstep.validate.limits.MIN_SMOOTHING_WIDTH, MAX_SMOOTHING_WIDTH)")


def time_optimal(distance: float, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                 t0: float = 0.0, widths: Optional[tuple[float, ...]] = None, engine: str = "c") -> PiecewisePlan:
    """The shortest feasible smoothed envelope move over ``distance`` [rad] (module docstring).

    ``engine="c"`` plans with csrc/time_optimal.c, ``"python"`` with this module (the same algorithm); the plan
    starts at ``theta1`` [rad] at time ``t0`` [s].

    Raises
    ------
    InputError
        A ValueError naming the argument, for one of a wrong type or out of its range (angles within +-1e6 rad,
        ``t0 >= 0``, ``motor`` a MotorParams, ``limits`` a MotorLimits), a move shorter than ``MIN_MOVE_DISTANCE``
        or an unknown engine, checked before any planning.
    ValueError
        When no smoothing width and headroom give a feasible table.
    """
    d = check_angle(distance, "distance")
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    check_motor(motor)
    check_limits(limits)
    check_engine(engine)
    if abs(d) < limits_mod.MIN_MOVE_DISTANCE:
        raise InputError("distance", distance, f"distance={distance!r} rad: a move needs at least "
                         f"{limits_mod.MIN_MOVE_DISTANCE:g} rad (flatstep.validate.limits.MIN_MOVE_DISTANCE); a "
                         "shorter one is a hold (a dwell)")
    _check_widths(widths)
    if engine == "c":
        from .time_optimal_c import plan_table

        return _plan(plan_table(d, motor, limits, widths), d, theta1, t0, from_c=True)
    return _plan(plan_move(d, motor, limits, widths).table, d, theta1, t0)


def _check_sequence(waypoints: Any) -> tuple[list[float], list[float]]:
    """The angles and dwells of ``[(theta, dwell), ...]``, or an InputError naming the waypoint (before any work)."""
    check_sequence("waypoints", waypoints, low=2, high=MAX_OPTIMAL_MOVES + 1, what="waypoints (theta, dwell)",
                   limit="MAX_OPTIMAL_MOVES, plus the start")
    theta, dwell = [], []
    for i, w in enumerate(waypoints):
        if not (isinstance(w, (tuple, list, np.ndarray)) and len(w) == 2):
            raise InputError(f"waypoints[{i}]", w, f"waypoints[{i}]={short_repr(w)} is not a pair (theta [rad], "
                             "dwell [s]); give each waypoint as (theta, dwell)")
        theta.append(check_angle(w[0], f"waypoints[{i}] theta"))
        dwell.append(check_quantity("time", w[1], as_name=f"waypoints[{i}] dwell"))
    for i in range(len(theta) - 1):
        if theta[i + 1] == theta[i]:
            raise InputError(f"waypoints[{i + 1}]", waypoints[i + 1], f"waypoints {i} and {i + 1} sit at "
                             f"{theta[i]} rad: give the rest as a dwell")
    return theta, dwell


def time_optimal_sequence(waypoints: list[tuple[float, float]], motor: MotorParams, limits: MotorLimits, *,
                          t0: float = 0.0, engine: str = "c") -> PiecewisePlan:
    """Time-optimal rest-to-rest moves through ``waypoints`` ``[(theta, dwell), ...]``, each followed by its dwell.

    The first waypoint is the start; a dwell of the first holds the start before the first move. The tables are
    joined into one plan (one validation of the whole table). At most ``MAX_OPTIMAL_MOVES`` moves, checked with
    every waypoint's type and range before any planning.
    """
    theta, dwell = _check_sequence(waypoints)
    check_motor(motor)
    check_limits(limits)
    check_engine(engine)
    t0 = check_t0(t0)
    if engine == "c":
        from .time_optimal_c import plan_table

    breaks, rows, rho_rows = [np.array([t0])], [], []
    t = t0
    for i in range(len(theta)):
        if dwell[i] > 0:
            row = np.zeros((1, NCOEF))
            row[0, -1] = theta[i]
            rho = np.zeros((1, NCOEF))
            rho[0, -1] = limits.i_hold
            t += dwell[i]
            breaks.append(np.array([t]))
            rows.append(row)
            rho_rows.append(rho)
        if i + 1 < len(theta):
            d = theta[i + 1] - theta[i]
            table = plan_table(d, motor, limits, None) if engine == "c" else plan_move(d, motor, limits).table
            move = (1.0 if d >= 0 else -1.0) * table.theta
            move[:, -1] += theta[i]
            breaks.append(t + table.breaks[1:])
            rows.append(move)
            rho_rows.append(table.rho)
            t = float(breaks[-1][-1])
    if engine == "c":  # the C planner's checked tables and dwells at i_hold > 0
        return PiecewisePlan._of_checked_table(np.concatenate(breaks), np.vstack(rows), np.vstack(rho_rows))
    return PiecewisePlan(np.concatenate(breaks), np.vstack(rows), np.vstack(rho_rows))
