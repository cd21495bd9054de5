r"""The fastest rest-to-rest move in the d-q flat outputs :math:`(\theta, i_d)`, with field weakening where it pays.

This module is the readable reference; csrc/time_optimal_dq.c runs the same algorithm (``engine="c"``, the
default) and the two agree on the planned durations to rounding (tests/test_time_optimal_dq.py).

**Stages.** :mod:`~flatstep.plan.time_optimal_dq_envelope` gives, at each speed, the largest and the smallest
torque current over the d current within the bus share :math:`\kappa\,v_{use}v_{bus}` and ``i_max`` (closed form:
two discs in the current plane), hence the acceleration envelope :math:`a_\pm(\omega)` and its d currents;
:mod:`~flatstep.plan.time_optimal_dq_profile` smooths the bang-bang move on it and its d current by a box of
width :math:`w` (once or twice), fits both as a table and measures the voltages of the d-q flat inverse on it, the
:math:`L\dot i` terms included.

**Search.** :math:`1 - \kappa` is the bus the inductance needs on top of the steady voltages. For each width
(multiples of the current's rise time :math:`L i_{max}/(v_{use}v_{bus})`, :data:`DEFAULT_WIDTHS`), :math:`\kappa`
is driven to the table's worst margin 0 by the secant, then regula falsi, in at most :data:`SEARCH` tables,
from the bus share the previous width found. With the box once (the jerk jumps; the d-q law takes it), then
twice, the widths are walked from the middle one down while the duration falls, then up unless the way down found
a shorter table; the shortest feasible table wins. A table's duration is known before it is built and falls as
kappa rises: a width whose duration at kappa = 1 is not shorter than the best builds no table, and an infeasible
table no shorter than the best ends its width's search.

**Limits.** The bus :math:`|v| \le v_{use}v_{bus}` (``voltage="phase"``: the inscribed circle of each phase's
:math:`\pm v_{use}v_{bus}`, met once per electrical turn; ``"vector"``: the norm itself), :math:`|i| \le i_{max}`,
the speed cap: the least of ``limits.speed_max`` and the commutation cap :math:`N_r\omega \le 2\pi\,s_e f_c`
(:data:`ELECTRICAL_SHARE` :math:`s_e` of the control rate :math:`f_c`: at least :math:`1/s_e` control periods per
electrical turn, so that a sampled drive still commutates). The torque-angle cap and ``i_hold`` belong to the
paper's :math:`(\rho, \theta)` law and are not used: the d-q law has no singularity.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np

from ..model.motor import MotorParams
from ..validate import InputError, check_choice
from ..validate.limits import MAX_PLAN_SAMPLES
from .arguments import check_angle, check_engine, check_limits, check_motor, check_t0
from .d_current import DCurrentPlan, hermite_cubic
from .envelope import Envelope
from .limits import MotorLimits
from .piecewise import PiecewisePlan, horner_rows
from .segments import hermite_rows
from .smoothing import timing
from .time_optimal_dq_envelope import dq_envelope
from .time_optimal_dq_profile import DQTable, dq_margins, dq_table

__all__ = ["DEFAULT_WIDTHS", "ELECTRICAL_SHARE", "DQCandidate", "DQPlan", "plan_dq_move", "speed_cap",
           "time_optimal_dq"]
#: The largest electrical frequency over the control rate (csrc/time_optimal_dq.h ``TOD_ELECTRICAL_SHARE``).
ELECTRICAL_SHARE = 0.035
#: The smoothing widths tried, in units of the current's rise time L i_max / (v_use v_bus).
DEFAULT_WIDTHS = (0.75, 1.0, 1.5, 2.0, 3.0)
#: Tables tried per width.
SEARCH = 7
#: Of the speed cap, the share the envelope is planned at (the fit may cross it by a little).
CAP_PLAN = 0.995
#: Of i_max, the share the envelope is planned at: the d current, spread wider than the torque current, leaves the
#: current disc by up to a few percent where both are large.
CURRENT_PLAN = 0.97
_S_TOL = 0.003  # a feasible table within 0.3 % of the limit ends a width's search
VOLTAGES = ("phase", "vector")
#: Of i_max, the least floor of the plan's rho channel (DQPlan).
RHO_FLOOR = 0.1
#: The control rate [Hz] the speed cap follows when none is given.
DEFAULT_RATE = 20000.0


class DQCandidate(NamedTuple):
    """A table the search kept: duration [s], bus share kappa, width [s], margins and the table."""

    tf: float
    kappa: float
    width: float
    margins: dict[str, float]
    table: DQTable


def speed_cap(motor: MotorParams, limits: MotorLimits, control_rate: float) -> float:
    """The speed cap [rad/s]: ``limits.speed_max`` and :data:`ELECTRICAL_SHARE` of ``control_rate`` [Hz] (module)."""
    cap = ELECTRICAL_SHARE * 2.0 * math.pi * control_rate / motor.Nr
    return min(cap, limits.speed_max) if limits.speed_max else cap


def _duration(d: float, motor: MotorParams, limits: MotorLimits, cap: float, kappa: float, width: float,
              passes: int) -> float:
    """The duration [s] of the table at ``kappa`` and ``width`` without building it (inf when none is built)."""
    try:
        env = dq_envelope(motor, kappa * limits.v_use * limits.v_bus, CURRENT_PLAN * limits.i_max, CAP_PLAN * cap)
        tm = timing(d, Envelope(env.omega, env.a_plus, env.a_minus), width)
    except ValueError:
        return math.inf
    return (tm.n + passes * (tm.n_box - 1) - 1) * tm.dt


def _try(d: float, motor: MotorParams, limits: MotorLimits, cap: float, kappa: float, width: float,
         passes: int) -> tuple[float, Optional[DQCandidate]]:
    """The measure s of the table at ``kappa`` and ``width`` and the table (inf and None when none is built)."""
    try:
        env = dq_envelope(motor, kappa * limits.v_use * limits.v_bus, CURRENT_PLAN * limits.i_max, CAP_PLAN * cap)
        if timing(d, Envelope(env.omega, env.a_plus, env.a_minus), width).n > MAX_PLAN_SAMPLES:
            return math.inf, None
        table = dq_table(d, env, width, motor, passes)
    except ValueError:
        return math.inf, None
    mg = dq_margins(table, motor, limits.v_use * limits.v_bus, limits.i_max, cap)
    return mg["worst"], DQCandidate(float(table.breaks[-1]), kappa, width, mg, table)


def search_kappa(d: float, motor: MotorParams, limits: MotorLimits, cap: float, width: float,
                 start: float = 1.0, passes: int = 2,
                 shortest: float = math.inf) -> tuple[Optional[DQCandidate], float]:
    """The shortest feasible table at ``width`` shorter than ``shortest`` [s], and the width's least duration.

    The secant on kappa from ``start``, then regula falsi in a bracket. A table's duration is known before it is
    built (:func:`_duration`) and falls as kappa rises: a width whose duration at kappa = 1 is not below
    ``shortest`` builds no table (None and that duration), and an infeasible table not shorter than the best so far
    ends the search (every table below its kappa is longer).
    """
    best: Optional[DQCandidate] = None
    least = _duration(d, motor, limits, cap, 1.0, width, passes)
    if not least < shortest:
        return None, least
    lo, hi, s_lo, s_hi = 0.0, 1.0, math.nan, math.nan
    k, k_prev, s_prev = start, math.nan, math.nan
    for _ in range(SEARCH):
        s, c = _try(d, motor, limits, cap, k, width, passes)
        aim = s + 0.5 * _S_TOL
        if c is not None and s <= 0:
            if best is None or c.tf < best.tf:
                best = c
            shortest = min(shortest, c.tf)
            lo, s_lo = k, aim
            if k >= 1.0 or s > -_S_TOL:
                break
        else:
            hi, s_hi = k, aim
            if shortest < math.inf and (c.tf if c is not None else math.inf) >= shortest:
                break  # no table below this bus share can be shorter than the best
        if not math.isnan(s_lo) and math.isfinite(s_hi):
            k_next = lo + (hi - lo) * s_lo / (s_lo - s_hi)
            k_next = min(max(k_next, lo + 0.02 * (hi - lo)), hi - 0.02 * (hi - lo))
        elif math.isfinite(aim) and math.isfinite(s_prev) and aim != s_prev:
            k_next = k - aim * (k - k_prev) / (aim - s_prev)
            k_next = min(max(k_next, 0.5 * k), 1.5 * k)
        elif math.isfinite(aim):
            k_next = k / (1.0 + aim)
        else:
            k_next = 0.5 * (lo + hi)
        k_prev, s_prev, k = k, aim, min(k_next, 1.0)
        if k < 0.05 or hi - lo < 1e-4:
            break
    return best, least


def plan_dq_move(distance: float, motor: MotorParams, limits: MotorLimits, *, voltage: str = "phase",
                 control_rate: float = DEFAULT_RATE, widths: Optional[tuple[float, ...]] = None,
                 engine: str = "python") -> DQCandidate:
    """The shortest feasible field-weakening table over ``distance`` != 0 [rad] (module docstring).

    Raises
    ------
    InputError
        An argument out of range.
    ValueError
        When no width and bus share give a feasible table.
    """
    d = abs(check_angle(distance, "distance"))
    check_motor(motor)
    check_limits(limits)
    check_choice("voltage", voltage, VOLTAGES)
    if not (isinstance(control_rate, (int, float)) and math.isfinite(control_rate) and control_rate > 0):
        raise InputError("control_rate", control_rate, f"control_rate={control_rate!r}: the drive's control rate "
                         "is a number of Hz > 0")
    if d == 0:
        raise InputError("distance", distance, "distance=0 rad: a move needs a distance; a rest is a dwell")
    check_engine(engine)
    if engine == "c" and widths is None:
        from .time_optimal_dq_c import plan_table

        table, margins, kappa, width = plan_table(d, motor, limits, control_rate)
        return DQCandidate(float(table.breaks[-1]), kappa, width, margins, table)
    cap = speed_cap(motor, limits, control_rate)
    rise = motor.L * limits.i_max / (limits.v_use * limits.v_bus)
    ws = sorted(k * rise for k in (widths or DEFAULT_WIDTHS))
    best: Optional[DQCandidate] = None
    start, passes = 1.0, 1

    def run(i: int) -> float:
        nonlocal best, start
        c, _ = search_kappa(d, motor, limits, cap, ws[i], start, passes, best.tf if best else math.inf)
        if c is None:
            return math.inf
        start = c.kappa  # the next width's search starts at this one's bus share
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

    for boxes in (1, 2):  # the box once (the jerk jumps, the law takes it), then twice
        start, passes, i0 = 1.0, boxes, len(ws) // 2
        f0 = run(i0)
        if not walk(i0 - 1, -1, f0) or f0 == math.inf:  # an infeasible middle width: both ways
            walk(i0 + 1, 1, f0)
    if best is None:
        raise ValueError(f"no feasible field-weakening plan of {distance} rad within {limits}: raise v_bus or i_max")
    return best


class DQPlan(NamedTuple):
    r"""A field-weakening move: the plan of theta (the plan protocol's object) and the planned d current.

    The d-q law tracks both: ``DQSMC(motor, plan, gains, d_current=d_current)``. The plan's rho channel holds
    a bound on the planned current magnitude :math:`\sqrt{i_q^2 + i_d^2 + f^2}`, :math:`f` the larger of
    ``i_hold`` and :data:`RHO_FLOOR` ``i_max`` (so that the paper's flat maps stay defined and the move starts
    from a holding current; the d-q law does not read it).
    """

    plan: PiecewisePlan
    d_current: DCurrentPlan
    found: DQCandidate


def _rho_rows(tb: DQTable, motor: MotorParams, floor: float, samples: int = 16) -> np.ndarray:
    """Rows of the plan's rho channel: at each knot the largest hypot(i_q, i_d, floor) over its two segments.

    Each segment then rises or falls monotonically between its knots (its three derivatives are 0 there), so the
    channel stays above the planned current magnitude sampled at ``samples`` points per segment.
    """
    m = motor
    hs = np.diff(tb.breaks)
    seg = np.repeat(np.arange(hs.size), samples)
    tau = np.tile(np.arange(samples) / (samples - 1.0), hs.size)
    w, acc = (horner_rows(tb.theta, seg, tau, k) / hs[seg] ** k for k in (1, 2))
    i_d, _ = hermite_cubic(tb.breaks[seg] + tau * hs[seg], tb.breaks, tb.i_d, tb.di_d)
    i_q = (m.J * acc + m.B * w) / m.Km
    peak = np.max(np.sqrt(i_q * i_q + i_d * i_d + floor * floor).reshape(hs.size, samples), axis=1)
    rho = np.maximum(np.append(peak, peak[-1]), np.insert(peak, 0, peak[0]))
    state = np.column_stack([rho, 0 * rho, 0 * rho, 0 * rho])
    return hermite_rows(state[:-1], state[1:], hs)


def time_optimal_dq(distance: float, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                    t0: float = 0.0, voltage: str = "phase", control_rate: float = DEFAULT_RATE,
                    widths: Optional[tuple[float, ...]] = None, engine: str = "c") -> DQPlan:
    """The shortest feasible field-weakening move over ``distance`` [rad] from ``theta1`` at ``t0`` (module docstring).

    Raises
    ------
    InputError
        An argument out of range, before any planning.
    ValueError
        When no width and bus share give a feasible table.
    """
    d = check_angle(distance, "distance")
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    c = plan_dq_move(d, motor, limits, voltage=voltage, control_rate=control_rate, widths=widths, engine=engine)
    tb = c.table
    sign = 1.0 if d >= 0 else -1.0
    theta = sign * tb.theta
    theta[:, -1] += theta1
    breaks = tb.breaks + t0
    plan = PiecewisePlan(breaks, theta, _rho_rows(tb, motor, max(limits.i_hold, RHO_FLOOR * limits.i_max)))
    d_current = DCurrentPlan(t0=t0, tf=float(breaks[-1]), knot_t=tuple(breaks), knot_id=tuple(tb.i_d),
                             knot_did=tuple(tb.di_d))
    return DQPlan(plan, d_current, c)
