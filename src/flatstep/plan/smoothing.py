r"""The smoothed move of the time-optimal planner: the bang-bang profile filtered, fitted as a table, and checked.

The second stage of :mod:`flatstep.plan.time_optimal`, after :mod:`flatstep.plan.envelope` (csrc/time_optimal.c
runs the same).

**Smoothing.** The speed profile is convolved twice with a box of width :math:`w` (an FIR filter, as
firmwares smooth moves): the jerk becomes continuous, theta''' exists for the law's feedforward, the duration
grows by :math:`2w`, and the end position is kept. A cruise longer than the smoothing needs is not sampled
(:func:`timing`). The result becomes a table of degree-7 segments through the profile's (theta, theta',
theta'', theta''') at its knots (:func:`.segments.hermite_rows`), with :math:`\rho^* = \sqrt{i_q^2 + i_d^2}`
(:meth:`~flatstep.plan.limits.MotorLimits.rho`), both planned at 0.98 of the torque-angle cap
(:func:`planning_limits`).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from ..validate import InputError
from ..validate.limits import MAX_PLAN_SAMPLES
from .envelope import BangBang, Envelope, bang_bang, envelope
from .limits import MotorLimits
from .piecewise import NCOEF
from .segments import hermite_rows

Array = NDArray[np.float64]
_FINE = 1000         # time samples of the smoothed profile (at least)
_FINE_MAX = 4000     # time samples of the smoothed profile, at most (box tails included; a long cruise is cut)
_PER_PHASE = 16      # time samples over the shortest of speed-up, braking and smoothing width (at least)
_KNOTS = 64          # segments of the table (speed-up and braking halves; 4 more in the cruise)
_CHECK = 8           # samples per segment of the search's margin check (tau = j / 8: the middle included)
#: Of v_use, the voltage a table may reach: the sampled check may miss the peak between its samples by about that much.
V_MARGIN = 0.998
#: The most segments of a table the planner writes (csrc/time_optimal.h ``TO_MAX_SEGMENTS``).
MAX_SEGMENTS = _KNOTS + 4


def _box(x: Array, n: int) -> Array:
    """``x`` convolved with a unit-area box of ``n`` samples (the output is ``n - 1`` samples longer)."""
    c = np.concatenate([[0.0], np.cumsum(np.concatenate([np.zeros(n - 1), x, np.zeros(n - 1)]))])
    return (c[n:] - c[:-n]) * (1.0 / n)  # times the box's height, as csrc/time_optimal.c rounds it


class Timing(NamedTuple):
    """The sampling of a smoothed move: the bang-bang move, the sample step [s], box and profile samples, the cut.

    ``k`` samples of the cruise from sample ``r`` on are not sampled (the smoothed speed is constant there).
    """

    move: BangBang
    dt: float
    n_box: int
    n: int
    r: int
    k: int


def timing(distance: float, env: Envelope, width: float) -> Timing:
    """The sampling of the move over ``distance`` > 0 smoothed by ``width`` [s] (module docstring).

    Fine enough for the shortest of speed-up, braking and smoothing and for the move less its long cruise, coarse
    enough for at most about ``_FINE_MAX`` samples; the full profile lasts ``(n + 2 (n_box - 1) - 1) dt``. A
    cruise longer than the smoothing needs is cut: only ``2 n_box + 4`` samples of it are kept at each end.
    """
    b = bang_bang(distance, env)
    total = b.t1 + b.cruise + b.t2
    core = b.t1 + b.t2 + min(b.cruise, 4 * width) + 2 * width
    dt = max(min(core / _FINE, min(b.t1, b.t2, width) / _PER_PHASE), core / _FINE_MAX)
    n_box = max(1, int(round(width / dt)))
    keep = 2 * n_box + 4
    first, last = math.ceil(b.t1 / dt) + 1, math.floor((b.t1 + b.cruise) / dt) - 1  # inside the raw cruise
    r = first + keep
    return Timing(b, dt, n_box, int(math.ceil(total / dt)) + 1, r, max(0, last - keep - r))


def smoothed_duration(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float, width: float) -> float:
    """The duration [s] of :func:`smoothed_plan`'s table, without building it."""
    tm = timing(abs(distance), envelope(motor, limits, gamma), width)
    return (tm.n + 2 * (tm.n_box - 1) - 1) * tm.dt


def _knots(last: int, up: float, down: float, cruise: bool) -> NDArray[np.intp]:
    """Sample indices of the table's knots: dense in speed-up and braking (smoothing included), few in a cruise."""
    a, b = min(max(up, 0.0), last), min(max(down, 0.0), last)
    if cruise and b > a:
        pieces = [np.linspace(0.0, a, _KNOTS // 2 + 1), np.linspace(a, b, 5)[1:],
                  np.linspace(b, last, _KNOTS // 2 + 1)[1:]]
    else:
        pieces = [np.linspace(0.0, last / 2, _KNOTS // 2 + 1), np.linspace(last / 2, last, _KNOTS // 2 + 1)[1:]]
    k = np.rint(np.concatenate(pieces)).astype(np.intp)
    return k[np.concatenate([[True], k[1:] != k[:-1]])]


def _gradient(x: Array, dt: float) -> Array:
    """Central differences inside, one-sided at the ends (numpy.gradient's first-order edges)."""
    g = np.empty_like(x)
    g[1:-1] = (x[2:] - x[:-2]) / (2.0 * dt)
    g[0], g[-1] = (x[1] - x[0]) / dt, (x[-1] - x[-2]) / dt
    return g


class Table(NamedTuple):
    """A segment table (breaks [s], theta and rho rows as :class:`~flatstep.plan.piecewise.PiecewisePlan` takes)."""

    breaks: Array
    theta: Array
    rho: Array


def smoothed_table(distance: float, env: Envelope, width: float, motor: MotorParams, limits: MotorLimits,
                   passes: int = 2) -> Table:
    """The bang-bang move on ``env`` over ``distance`` > 0, smoothed twice by a box of ``width`` [s], as a table.

    The profile is sampled without the cut of :func:`timing` (sample ``i >= r`` at ``(i + k) dt``); a knot in the
    cut reads the constant cruise at sample ``r``, a knot after it the sample ``k`` earlier. The angle between
    knots sums the profile's trapezoids between them and the cut's cruise they span.
    """
    b, dt, n_box, n, r, k = timing(distance, env, width)
    total = b.t1 + b.cruise + b.t2
    i = np.arange(n - k)
    t = np.where(i < r, i, i + k) * dt
    speed = np.where(t <= b.t1, np.interp(t, b.t_acc, env.omega),
                     np.where(t < b.t1 + b.cruise, b.w_peak, np.interp(total - t, b.t_dec, env.omega)))
    speed[-1] = 0.0
    for _ in range(passes):  # twice (a box once: the jerk jumps, as the field-weakening planner may take)
        speed = _box(speed, n_box)
    inc = 0.5 * (speed[1:] + speed[:-1]) * dt  # the trapezoids of the angle
    r = min(r, speed.size - 1)  # no cut (k = 0): r only has to index the profile
    cruise = speed[r] if k else 0.0
    covered = float(np.sum(inc) + k * dt * cruise)
    if not (covered > 0 and math.isfinite(covered)):  # csrc/time_optimal_table.c builds no table either
        raise ValueError(f"the smoothed profile of {distance:g} rad at width {width:g} s covers no angle")
    scale = distance / covered
    # the cruise's knots 4 samples inside it, where the jerk's central differences see only the constant cruise (at
    # its ends the jerk jumps, and a long cruise segment would bulge to meet half of that jump)
    knots = _knots(speed.size - 1 + k, (b.t1 + passes * width) / dt + 4, (b.t1 + b.cruise) / dt - 4, b.cruise > 0)
    at = np.where(knots < r, knots, np.where(knots >= r + k, knots - k, r))  # the sample each knot reads
    # the angle from knot to knot: the trapezoids between their samples and the cut's samples between them
    sums = np.where(at[1:] > at[:-1], np.add.reduceat(inc, np.minimum(at[:-1], inc.size - 1)), 0.0)
    cut = np.clip(knots[1:], r, r + k) - np.clip(knots[:-1], r, r + k)
    step = (sums + cut * dt * cruise) * scale
    angle = np.concatenate([[0.0], np.cumsum(step)])
    step[-1] = distance - angle[-2]  # the move ends at the distance
    speed = speed * scale
    acc = _gradient(speed, dt)
    jerk = _gradient(acc, dt)
    state = np.column_stack([angle, speed[at], acc[at], jerk[at]])
    state[0, 1:] = state[-1, 1:] = 0.0
    h = np.diff(knots) * dt
    rho = limits.rho((motor.J * acc + motor.B * speed) / motor.Km, speed)
    # rho and rho' at the knots (the law reads rho' only); rho'' and rho''' set to 0 keep each segment monotone
    rho_state = np.column_stack([rho, _gradient(rho, dt), 0 * rho, 0 * rho])[at]
    # each segment from 0 to its step, its start angle added after: rounding of the angle [rad] divided by h^3
    # would otherwise show in the jerk at the breaks
    start, end = state[:-1].copy(), state[1:].copy()
    start[:, 0], end[:, 0] = 0.0, step
    rows = hermite_rows(start, end, h)
    rows[:, -1] += angle[:-1]
    return Table(np.concatenate([[0.0], np.cumsum(h)]), rows, hermite_rows(rho_state[:-1], rho_state[1:], h))


def table_margins(table: Table, motor: MotorParams, limits: MotorLimits, samples: int = _CHECK) -> dict[str, float]:
    r"""The table's worst use of each limit at ``samples`` points per segment (``tau = j / samples``) and its end.

    The same ratios as :func:`~flatstep.plan.margins.plan_margins`, the voltage magnitude from the polar-frame
    voltages (the input map is a rotation, so :math:`|v| = \sqrt{X^2 + Y^2}`, no angle needed); ``inf`` where
    rho <= 0 or the torque angle reaches 90 degrees. ``worst`` is the search's :math:`s`: the voltage over
    ``0.998 v_use``, every other ratio over 1, the largest less 1.
    """
    m = motor
    h = np.diff(table.breaks)
    tau = np.arange(samples) / samples  # from each segment's start; an even count has its middle, where fits bulge
    seg = np.repeat(np.arange(h.size), tau.size)
    tt = np.tile(tau, h.size)
    seg, tt = np.append(seg, h.size - 1), np.append(tt, 1.0)

    def deriv(rows: Array, k: int) -> Array:
        powers = np.arange(NCOEF - 1, -1, -1)
        fall = np.array([math.perm(int(p), k) for p in powers], dtype=float)
        d = rows * fall
        out = np.zeros(seg.size)
        for j in range(NCOEF - k):  # a loop over the degree, vectorized over the samples
            out = out * tt + d[seg, j]
        return out / h[seg] ** k

    w, acc, jerk = (deriv(table.theta, k) for k in (1, 2, 3))
    rho, drho = deriv(table.rho, 0), deriv(table.rho, 1)
    out = dict(current=float(np.max(rho)) / limits.i_max, speed=0.0, acceleration=0.0, jerk=0.0)
    for key, cap, x in (("speed", limits.speed_max, w), ("acceleration", limits.accel_max, acc),
                        ("jerk", limits.jerk_max, jerk)):
        if cap:
            out[key] = float(np.max(np.abs(x))) / cap
    a = m.J * acc + m.B * w
    kr = m.Km * rho
    if not (np.min(rho) > 0 and np.max(np.abs(a) - kr) < 0):
        out.update(voltage=math.inf, torque_angle=math.inf, worst=math.inf)
        return out
    s = np.sqrt(kr * kr - a * a)
    out["torque_angle"] = float(np.max(np.abs(a) / kr)) / math.sin(limits.torque_angle_max)
    dphi = -((m.J * jerk + m.B * acc) * rho - a * drho) / (rho * s) - m.Nr * w
    x = m.L * drho + m.R * rho + m.Km * w * (a / kr)
    y = m.L * rho * dphi - m.Km * w * (s / kr)
    out["voltage"] = float(np.max(np.hypot(x, y))) / limits.v_bus
    out["worst"] = max(out["voltage"] / (V_MARGIN * limits.v_use), out["current"], out["torque_angle"],
                       out["speed"], out["acceleration"], out["jerk"]) - 1.0
    return out


#: The smoothing widths tried by default, in units of L / R (csrc/time_optimal.c ``DEFAULT_WIDTHS``).
DEFAULT_WIDTHS = (0.25, 0.5, 1.0, 2.0, 4.0)
_ANGLE_PLAN = 0.98   # the torque angle cap planned with, of the true one (planning_limits)
_CAP_PLAN = 0.995    # the speed and acceleration caps planned with, of the true ones (planning_limits)


def planning_limits(limits: MotorLimits) -> MotorLimits:
    """The limits the envelope and rho* are planned with, a little inside the true ones.

    The torque angle cap is ``_ANGLE_PLAN`` times the true one, the speed and acceleration caps ``_CAP_PLAN``
    times theirs: rho* keeps the torque angle at its cap where the torque current is large, and the envelope
    keeps a capped speed or acceleration at its cap; the table's fit would otherwise cross them by a little, a
    margin no bus fraction could buy back.
    """
    return replace(limits, torque_angle_max=limits.torque_angle_max * _ANGLE_PLAN,
                   speed_max=limits.speed_max * _CAP_PLAN if limits.speed_max else None,
                   accel_max=limits.accel_max * _CAP_PLAN if limits.accel_max else None)


def check_samples(distance: float, tm: Timing) -> None:
    """Raise an InputError naming ``distance`` when its move would be sampled more than ``MAX_PLAN_SAMPLES`` times."""
    if tm.n > MAX_PLAN_SAMPLES:
        total = tm.move.t1 + tm.move.cruise + tm.move.t2
        raise InputError("distance", distance, f"the move of {distance:g} rad takes {total:.4g} s at this motor's "
                         f"speed limit, which the time-optimal planner would sample {tm.n:.3g} times (every "
                         f"{tm.dt:.3g} s), above the limit of {MAX_PLAN_SAMPLES:.3g} (flatstep.validate.limits."
                         "MAX_PLAN_SAMPLES); split it into shorter moves with waypoints, or plan it with a spline")
