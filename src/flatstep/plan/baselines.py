r"""What firmwares and general planners do, at their best on the same motor: a trapezoid and a Ruckig S-curve.

Both take constant caps. :func:`best_baseline` searches the caps whose whole move keeps the same limits as
:func:`~flatstep.plan.time_optimal.time_optimal` (the bus within ``v_use``, the current, the torque angle,
checked by :func:`~flatstep.plan.margins.plan_margins` through the flat maps), so that each baseline is at its
best. The current follows the same rule as the time-optimal plan's, :math:`\rho = \sqrt{i_q^2 + i_{hold}^2}`
with :math:`i_q = (J\ddot\theta + B\dot\theta)/K_m`, so only the shape of :math:`\theta(t)` differs.

* ``trapezoid``: acceleration in {+a, 0, -a}. Its acceleration steps would need infinite voltage
  (:math:`L\,di/dt`); its margins are taken inside the segments, which favours it.
* ``ruckig``: the time-optimal jerk-limited profile of the ``ruckig`` package (PyPI, the ``bench`` extra); its
  duration is Ruckig's, and its table is the seven-phase S-curve of :func:`.segments.scurve_rows`, whose
  duration matches Ruckig's (``tests/test_plan_baselines.py``).

Both hold the paper's law's current across the torque axis (``i_hold``) throughout, and the acceleration cap is
found by bisection at each speed cap and jerk time: baselines for the (rho, theta) law, not the fastest a drive
can do with the same profiles. A field-oriented drive's own, Ruckig with ``i_d = 0`` and a trapezoid with field
weakening, each with its caps searched on a full grid, are :mod:`flatstep.bench.fair_baselines`
(docs/planning.md, section 6).
"""
from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray
from scipy.special import comb

from ..model.motor import MotorParams
from ..validate import InputError, check_choice, check_quantity
from .arguments import check_angle, check_limits, check_motor, check_t0
from .limits import MotorLimits
from .margins import plan_margins
from .piecewise import NCOEF, PiecewisePlan, horner
from .segments import hermite_rows, scurve_rows

Array = NDArray[np.float64]
KINDS = ("trapezoid", "ruckig")
_SPLIT = 6  # sub-segments per phase, for the current's table


def _check_distance(distance: Any) -> float:
    """``distance`` as float, or an InputError unless it is a non-zero angle in the range of ``angle``."""
    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    return d


def _check_caps(v_max: Any, a_max: Any, j_max: Any) -> tuple[float, float, Optional[float]]:
    """The caps as floats (``j_max`` may be None), or an InputError naming the one out of its range."""
    return (check_quantity("speed", v_max, as_name="v_max"), check_quantity("acceleration", a_max, as_name="a_max"),
            None if j_max is None else check_quantity("jerk", j_max, as_name="j_max"))


def ruckig_duration(distance: float, v_max: float, a_max: float, j_max: float) -> float:
    """Ruckig's time-optimal rest-to-rest duration over ``distance`` under the caps [s]."""
    distance = check_angle(distance, "distance")
    v_max, a_max, _ = _check_caps(v_max, a_max, None)
    j_max = check_quantity("jerk", j_max, as_name="j_max")
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [float(distance)], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v_max], [a_max], [j_max]
    traj = Trajectory(1)
    result = Ruckig(1).calculate(inp, traj)
    if result != Result.Working:
        raise ValueError(f"ruckig refused the move {distance} rad under v={v_max}, a={a_max}, j={j_max}: {result}")
    return float(traj.duration)


def trapezoid_rows(distance: float, v_max: float, a_max: float) -> tuple[Array, Array]:
    """The trapezoid (or triangle) from 0 over ``distance`` > 0: rows (k, 11) and durations (k,)."""
    distance = _check_distance(distance)
    v_max, a_max, _ = _check_caps(v_max, a_max, None)
    ta = v_max / a_max
    if a_max * ta * ta >= distance:  # the speed cap is not reached: a triangle
        ta, cruise = math.sqrt(distance / a_max), 0.0
    else:
        cruise = (distance - a_max * ta * ta) / v_max
    vp = a_max * ta
    rows, durations, p = [], [], 0.0
    for h, v0, acc in ((ta, 0.0, a_max), (cruise, vp, 0.0), (ta, vp, -a_max)):
        if h > 0:
            row = np.zeros(NCOEF)
            row[-3:] = [acc * h * h / 2, v0 * h, p]
            rows.append(row)
            durations.append(h)
            p += v0 * h + acc * h * h / 2
    return np.array(rows), np.array(durations)


def _split(rows: Array, h: Array, k: int) -> tuple[Array, Array]:
    """Each row split into ``k`` rows over equal parts of its segment (exact re-expansion in the local time).

    On part i, tau = (i + s) / k: the ascending coefficients of p(a + b s) are c @ M with
    M[j, m] = C(j, m) a^(j - m) b^m, one matrix per part.
    """
    j = np.arange(NCOEF)
    low = j[:, None] >= j[None, :]
    power = np.where(low, j[:, None] - j[None, :], 0)
    mats = np.array([np.where(low, comb(j[:, None], j[None, :]) * (i / k) ** power * (1.0 / k) ** j[None, :], 0.0)
                     for i in range(k)])
    parts = np.einsum("nj,kjm->nkm", rows[:, ::-1], mats)
    return parts[:, :, ::-1].reshape(-1, NCOEF), np.repeat(h / k, k)


def with_torque_current(rows: Array, h: Array, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                        t0: float = 0.0, sign: float = 1.0) -> PiecewisePlan:
    r"""A table of theta rows (from 0, positive) with :math:`\rho = \sqrt{i_q^2 + i_{hold}^2}` (module docstring).

    Each segment's current is a degree-7 segment through its own one-sided :math:`(\rho, \dot\rho)` at both ends.
    """
    check_motor(motor)
    check_limits(limits)
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    rows, h = _split(rows, h, _SPLIT)
    ends = []
    for tau in (0.0, 1.0):
        t = np.full(rows.shape[0], tau)
        d = [horner(rows, t, k) / h**k for k in (1, 2, 3)]
        iq = (motor.J * d[1] + motor.B * d[0]) / motor.Km
        diq = (motor.J * d[2] + motor.B * d[1]) / motor.Km
        rho = limits.rho(iq, d[0])
        # d rho / dt by the chain rule through iq and omega, from a central difference of limits.rho
        step = 1e-7 * (1.0 + np.abs(iq))
        drho_diq = (limits.rho(iq + step, d[0]) - limits.rho(iq - step, d[0])) / (2 * step)
        wstep = 1e-6 * (1.0 + np.abs(d[0]))
        drho_dw = (limits.rho(iq, d[0] + wstep) - limits.rho(iq, d[0] - wstep)) / (2 * wstep)
        zeros = np.zeros_like(rho)
        ends.append(np.column_stack([rho, drho_diq * diq + drho_dw * d[1], zeros, zeros]))
    theta = sign * rows
    theta[:, -1] += theta1
    return PiecewisePlan(t0 + np.concatenate([[0.0], np.cumsum(h)]), theta, hermite_rows(ends[0], ends[1], h))


def baseline_plan(kind: str, distance: float, motor: MotorParams, limits: MotorLimits, v_max: float,
                  a_max: float, j_max: Optional[float] = None, *, theta1: float = 0.0,
                  t0: float = 0.0) -> PiecewisePlan:
    """The ``kind`` baseline over ``distance`` [rad] under the caps, as a table with the torque current."""
    kind = check_choice("kind", kind, KINDS)
    distance, d = _check_distance(distance), abs(distance)
    check_motor(motor)
    check_limits(limits)
    v_max, a_max, j_max = _check_caps(v_max, a_max, j_max)
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    if kind == "trapezoid":
        rows, h = trapezoid_rows(d, v_max, a_max)
    elif kind == "ruckig":
        if j_max is None:
            raise InputError("j_max", j_max, "j_max=None: a ruckig profile needs j_max")
        rows, h = scurve_rows(0.0, d, v_max, a_max, j_max)
    return with_torque_current(rows, h, motor, limits, theta1=theta1, t0=t0,
                               sign=1.0 if distance >= 0 else -1.0)


def _ok(plan: PiecewisePlan, motor: MotorParams, limits: MotorLimits) -> bool:
    """The time-optimal planner's feasibility test, for a baseline."""
    m = plan_margins(plan, motor, limits)
    return m["voltage"] <= limits.v_use and max(m["current"], m["torque_angle"]) <= 1.0


def _largest_accel(kind: str, distance: float, motor: MotorParams, limits: MotorLimits, v: float,
                   tj: Optional[float], a_top: float) -> Optional[tuple[PiecewisePlan, dict[str, float]]]:
    """At speed cap ``v`` and jerk time ``tj``, the plan with the largest feasible acceleration cap (bisection)."""
    lo, hi, found = 0.0, a_top, None
    for _ in range(10):
        a = 0.5 * (lo + hi)
        caps = dict(v_max=float(v), a_max=float(a), j_max=float(a / tj) if tj else math.inf)
        plan = baseline_plan(kind, distance, motor, limits, caps["v_max"], caps["a_max"],
                             caps["j_max"] if tj else None)
        if _ok(plan, motor, limits):
            lo, found = a, (plan, caps)
        else:
            hi = a
    return found


def best_baseline(kind: str, distance: float, motor: MotorParams,
                  limits: MotorLimits) -> tuple[PiecewisePlan, dict[str, float]]:
    """The fastest ``kind`` baseline whose whole move keeps the limits: a search over its constant caps.

    Speed caps on a grid up to the bus's top speed, then a finer grid around the best one; for each (and each
    jerk time, for ruckig), the largest feasible acceleration cap by bisection. Returns the plan and its caps.
    """
    kind, distance = check_choice("kind", kind, KINDS), _check_distance(distance)
    check_motor(motor)
    check_limits(limits)
    a_top = motor.Km * float(limits.iq_cap(0.0)) / motor.J
    w_top = limits.v_use * limits.v_bus / motor.Km
    tau_e = motor.L / motor.R
    jerk_times = (None,) if kind == "trapezoid" else tuple(k * tau_e for k in (0.25, 0.5, 1.0, 2.0))
    best: Optional[tuple[PiecewisePlan, dict[str, float]]] = None
    coarse = w_top * np.linspace(0.2, 1.0, 13)
    step = coarse[1] - coarse[0]
    for speeds in (coarse, None):
        if speeds is None:  # refine: 16 speeds across one coarse step either side of the best
            if best is None:
                break
            speeds = best[1]["v_max"] + step * np.linspace(-1.0, 1.0, 17)
            speeds = speeds[(speeds > 0) & (speeds <= w_top)]
        for v in speeds:
            for tj in jerk_times:
                found = _largest_accel(kind, distance, motor, limits, float(v), tj, a_top)
                if found is not None and (best is None or found[0].tf < best[0].tf):
                    best = found
    if best is None:
        raise ValueError(f"no {kind} over {distance} rad keeps the limits {limits}")
    return best
