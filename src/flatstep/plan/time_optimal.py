r"""The fastest rest-to-rest move the motor and its bus can make: a speed-dependent envelope, smoothed and checked.

This module is the readable reference; csrc/time_optimal.c runs the same algorithm (``engine="c"``, the default)
and the two agree on the planned durations to rounding (tests/test_plan_time_optimal_c.py).

**Envelope.** At speed :math:`\omega`, with the current :math:`u = i_q` along the torque axis and the planned
:math:`i_d = \sqrt{f(\omega)^2 + k^2u^2}`, :math:`k = \cot\alpha_{max}` across it
(:meth:`~flatstep.plan.limits.MotorLimits.across`), the steady phase voltage (:math:`di/dt = 0`) is
:math:`v_d = R i_d - e u`, :math:`v_q = R u + e i_d + c` with :math:`e = N_r\omega L`, :math:`c = K_m\omega`, and
its square has the cross terms cancel:

.. math::
    h(u) = v_d^2 + v_q^2 - (\gamma V_{bus})^2
         = (R^2 + e^2)\bigl((1 + k^2)u^2 + f^2\bigr) + 2cRu + 2ce\sqrt{f^2 + k^2u^2} + c^2 - (\gamma V_{bus})^2,

convex in :math:`u`. Newton's method from the current cap ``i_max`` allows (where :math:`h > 0`) therefore falls
monotonically onto the largest :math:`\pm u` within the bus, in a few steps (:func:`iq_bounds`). They bound the
acceleration :math:`a_\pm(\omega) = (K_m u_\pm - B\omega)/J` (back EMF helps braking: :math:`|a_-| > a_+`).

**Bang-bang profile.** Accelerate on :math:`a_+`, cruise at the speed cap if reached, brake on :math:`a_-`:
the distances :math:`\int \omega/a\,d\omega` and times :math:`\int d\omega/a` over a speed grid give the peak
speed where acceleration and braking distances add up to the move. With :math:`\gamma = 1` and no inductance
this is the *bang-bang bound* :func:`bang_bang_time`, the lower bound the planned times are compared with.

**Smoothing.** The speed profile is convolved twice with a box of width :math:`w` (an FIR filter, as
firmwares smooth moves): the jerk becomes continuous, theta''' exists for the law's feedforward, the duration
grows by :math:`2w`, and the end position is kept. A cruise longer than the smoothing needs is not sampled
(:func:`timing`). The result becomes a table of degree-7 segments through the profile's (theta, theta',
theta'', theta''') at its knots (:func:`.segments.hermite_rows`), with :math:`\rho^* = \sqrt{i_q^2 + i_d^2}`
(:meth:`~flatstep.plan.limits.MotorLimits.rho`), both planned at 0.98 of the torque-angle cap
(:func:`planning_limits`).

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
from dataclasses import replace
from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from ..validate import InputError, check_finite
from ..validate.limits import MAX_PLAN_SAMPLES
from .limits import MotorLimits
from .piecewise import NCOEF, PiecewisePlan
from .segments import hermite_rows

Array = NDArray[np.float64]
_GRID = 192          # speed-grid points of the phase plane
_PROBE = 64          # speed-grid points of the probe for the top speed
_TOP_ACCEL = 0.01    # the top speed: where a+ falls to this fraction of a+ at rest
_FINE = 1000         # time samples of the smoothed profile (at least)
_FINE_MAX = 4000     # time samples of the smoothed profile, at most (box tails included; a long cruise is cut)
_PER_PHASE = 16      # time samples over the shortest of speed-up, braking and smoothing width (at least)
_KNOTS = 64          # segments of the table (speed-up and braking halves; 4 more in the cruise)
_CHECK = 8           # samples per segment of the search's margin check (tau = j / 8: the middle included)
_WIDTHS = (0.25, 0.5, 1.0, 2.0, 4.0)  # smoothing widths tried, in units of L / R
#: The smoothing widths tried by default, in units of L / R (csrc/time_optimal.c ``DEFAULT_WIDTHS``).
DEFAULT_WIDTHS = _WIDTHS
_SEARCH = 6          # tables tried per width on gamma, at most
_GAMMA_MIN = 0.05    # the least bus fraction a plan may take
_GAMMA_STEPS = 2.0**16  # gamma is tried on multiples of 1 / _GAMMA_STEPS (csrc/time_optimal.c does the same)
_V_MARGIN = 0.998    # of v_use: the sampled check may miss the peak between its samples by about that much
_ANGLE_PLAN = 0.98   # the torque angle cap planned with, of the true one (planning_limits)
_CAP_PLAN = 0.995    # the speed and acceleration caps planned with, of the true ones (planning_limits)
_S_TOL = 0.003       # a feasible table within 0.3 % of the bus target ends a width's search
_PEAK_OVER_STEADY = 0.994  # a table's peak voltage over the steady one at its move's peak speed (first_gamma)
_NEWTON_TOL = 1e-12  # Newton stops when its step is below this fraction of i_max
#: The most segments of a table the planner writes (csrc/time_optimal.h ``TO_MAX_SEGMENTS``).
MAX_SEGMENTS = _KNOTS + 4


class Envelope(NamedTuple):
    """The speed grid [rad/s] from rest to the top speed and the accelerations a+ > 0, a- < 0 on it [rad/s^2]."""

    omega: Array
    a_plus: Array
    a_minus: Array


def _h(u: Array, omega: Array, motor: MotorParams, limits: MotorLimits, v2: float) -> tuple[Array, Array]:
    """The squared steady voltage less the bus's, h(u), and dh/du at torque current ``u`` (module docstring)."""
    m, k = motor, 1.0 / math.tan(limits.torque_angle_max)
    f, c, e = limits.floor(omega), m.Km * omega, m.Nr * omega * m.L
    z = m.R * m.R + e * e
    root = np.sqrt(f * f + k * k * u * u)
    h = z * ((1.0 + k * k) * u * u + f * f) + 2.0 * c * m.R * u + 2.0 * c * e * root + c * c - v2
    dh = 2.0 * z * (1.0 + k * k) * u + 2.0 * c * m.R + 2.0 * c * e * k * k * u / root
    return h, dh


def iq_bounds(omega: Array, motor: MotorParams, limits: MotorLimits, gamma: float = 1.0) -> tuple[Array, Array]:
    """The torque currents (lowest, highest) the bus and i_max allow at speeds ``omega`` >= 0 (module docstring).

    Newton from the cap on each side, vectorized over the speeds, until every step is below ``_NEWTON_TOL i_max``;
    0 on both sides where even no torque exceeds the bus.
    """
    omega = np.asarray(omega, dtype=float)
    cap = limits.iq_cap(omega)
    v2 = (gamma * limits.v_bus) ** 2
    reach = _h(np.zeros_like(omega), omega, motor, limits, v2)[0] <= 0
    bounds = []
    for sign in (-1.0, 1.0):
        u = sign * cap
        active = reach & (_h(u, omega, motor, limits, v2)[0] > 0)
        for _ in range(100):  # a loop over Newton steps, vectorized over the speeds; monotone (h is convex)
            if not active.any():
                break
            h, dh = _h(u[active], omega[active], motor, limits, v2)
            step = h / dh
            u[active] -= step
            active[active] = np.abs(step) > _NEWTON_TOL * limits.i_max
        bounds.append(np.where(reach, u, 0.0))
    return bounds[0], bounds[1]


def envelope(motor: MotorParams, limits: MotorLimits, gamma: float) -> Envelope:
    """The speed grid up to the top speed and the accelerations on it, at ``gamma`` of the bus.

    A probe grid up to the lesser of the speed cap and the back-EMF speed finds where a+ first falls to
    ``_TOP_ACCEL`` of its value at rest, interpolated between its points; the grid ends there. (Speeds above it take
    long to reach for little gain; a top that moves continuously with gamma keeps the search's measure smooth.)
    """
    m = motor
    w_emf = gamma * limits.v_bus / m.Km
    w_max = min(limits.speed_max, w_emf) if limits.speed_max else w_emf
    probe = np.linspace(0.0, w_max, _PROBE)
    acc = (m.Km * iq_bounds(probe, m, limits, gamma)[1] - m.B * probe) / m.J
    if not acc[0] > 0:
        raise ValueError(f"the motor cannot start: at rest the bus {limits.v_bus} V (x {gamma:.3g}) and the limits "
                         f"{limits} leave no torque")
    thr = _TOP_ACCEL * acc[0]
    below = np.flatnonzero(~(acc[1:] > thr)) + 1
    top = w_max
    if below.size:  # interpolated between the probe points: the top speed moves continuously with gamma
        j = below[0]
        top = probe[j - 1] + (probe[j] - probe[j - 1]) * ((acc[j - 1] - thr) / (acc[j - 1] - acc[j]))
    omega = np.linspace(0.0, top, _GRID)
    lo, hi = iq_bounds(omega, m, limits, gamma)
    a_plus = (m.Km * hi - m.B * omega) / m.J
    a_minus = (m.Km * lo - m.B * omega) / m.J
    if limits.accel_max:
        a_plus, a_minus = np.minimum(a_plus, limits.accel_max), np.maximum(a_minus, -limits.accel_max)
    a_plus[-1] = max(a_plus[-1], 1e-12 * a_plus[0])  # the top speed is reached in finite time on the grid
    return Envelope(omega, a_plus, a_minus)


def _cumtrapz(y: Array, x: Array) -> Array:
    """The running trapezoidal integral of ``y`` over ``x``, from 0."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(x))])


class BangBang(NamedTuple):
    """The bang-bang move on an envelope: speed-up time [s], cruise time [s], braking time [s], peak speed [rad/s]."""

    t1: float
    cruise: float
    t2: float
    w_peak: float
    t_acc: Array
    t_dec: Array


def bang_bang(distance: float, env: Envelope) -> BangBang:
    """The bang-bang move over ``distance`` > 0 on ``env`` (module docstring)."""
    omega, a_plus, a_minus = env
    t_acc = _cumtrapz(1.0 / a_plus, omega)
    t_dec = _cumtrapz(1.0 / -a_minus, omega)
    d_both = _cumtrapz(omega / a_plus + omega / -a_minus, omega)
    if distance >= d_both[-1]:
        w_peak, cruise = float(omega[-1]), (distance - float(d_both[-1])) / float(omega[-1])
    else:
        w_peak, cruise = float(np.interp(distance, d_both, omega)), 0.0
    return BangBang(float(np.interp(w_peak, omega, t_acc)), cruise, float(np.interp(w_peak, omega, t_dec)), w_peak,
                    t_acc, t_dec)


def bang_bang_time(distance: float, motor: MotorParams, limits: MotorLimits) -> float:
    """The lower bound: the bang-bang move on the full bus ignoring inductance and jerk (module docstring)."""
    d = abs(check_finite("distance", distance))
    b = bang_bang(d, envelope(motor, limits, 1.0))
    return b.t1 + b.cruise + b.t2


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


def smoothed_table(distance: float, env: Envelope, width: float, motor: MotorParams, limits: MotorLimits) -> Table:
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
    speed = _box(_box(speed, n_box), n_box)
    inc = 0.5 * (speed[1:] + speed[:-1]) * dt  # the trapezoids of the angle
    r = min(r, speed.size - 1)  # no cut (k = 0): r only has to index the profile
    cruise = speed[r] if k else 0.0
    scale = distance / (np.sum(inc) + k * dt * cruise)
    # the cruise's knots 4 samples inside it, where the jerk's central differences see only the constant cruise (at
    # its ends the jerk jumps, and a long cruise segment would bulge to meet half of that jump)
    knots = _knots(speed.size - 1 + k, (b.t1 + 2 * width) / dt + 4, (b.t1 + b.cruise) / dt - 4, b.cruise > 0)
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

    The same ratios as :func:`~flatstep.plan.limits.plan_margins`, the voltage magnitude from the polar-frame
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
    out["worst"] = max(out["voltage"] / (_V_MARGIN * limits.v_use), out["current"], out["torque_angle"],
                       out["speed"], out["acceleration"], out["jerk"]) - 1.0
    return out


class Candidate(NamedTuple):
    """A table the search tried: its duration [s], the bus fraction, the width [s], its margins and the table."""

    tf: float
    gamma: float
    width: float
    margins: dict[str, float]
    table: Table


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


def check_samples(distance: float, tm: Timing) -> None:
    """Raise an InputError naming ``distance`` when its move would be sampled more than ``MAX_PLAN_SAMPLES`` times."""
    if tm.n > MAX_PLAN_SAMPLES:
        total = tm.move.t1 + tm.move.cruise + tm.move.t2
        raise InputError("distance", distance, f"the move of {distance:g} rad takes {total:.4g} s at this motor's "
                         f"speed limit, which the time-optimal planner would sample {tm.n:.3g} times (every "
                         f"{tm.dt:.3g} s), above the limit of {MAX_PLAN_SAMPLES:.3g} (flatstep.validate.limits."
                         "MAX_PLAN_SAMPLES); split it into shorter moves with waypoints, or plan it with a spline")


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
        v2 = max(v2, float(_h(np.array([u]), np.array([w]), m, limits, 0.0)[0][0]))
    s = _PEAK_OVER_STEADY * math.sqrt(v2) / (_V_MARGIN * limits.v_use * limits.v_bus) - 1.0
    return min(1.0, 1.0 / (1.0 + s + 0.5 * _S_TOL))


def plan_move(distance: float, motor: MotorParams, limits: MotorLimits,
              widths: Optional[tuple[float, ...]] = None) -> Candidate:
    """The shortest feasible candidate over ``distance`` != 0 (module docstring); a ValueError when there is none.

    The widths, sorted, are searched from the middle one outwards: down while the duration falls, then up while
    it falls unless the way down found a shorter table (the duration first falls, then rises with the width);
    infeasible widths do not stop a walk before a feasible one is found, and an infeasible middle width sends the
    search both ways. Each width's search starts at the gamma the previous feasible width found.
    """
    d = abs(distance)
    ws = sorted(widths or tuple(k * (motor.L / motor.R) for k in _WIDTHS))
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


def time_optimal(distance: float, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                 t0: float = 0.0, widths: Optional[tuple[float, ...]] = None, engine: str = "c") -> PiecewisePlan:
    """The shortest feasible smoothed envelope move over ``distance`` [rad] (module docstring).

    ``engine="c"`` plans with csrc/time_optimal.c, ``"python"`` with this module (the same algorithm); the plan
    starts at ``theta1`` [rad] at time ``t0`` [s].

    Raises
    ------
    ValueError
        For a zero distance, an unknown engine, or when no smoothing width and headroom give a feasible table.
    """
    d = check_finite("distance", distance)
    theta1, t0 = check_finite("theta1", theta1), check_finite("t0", t0)
    if d == 0:
        raise ValueError("distance=0.0 rad: a move needs a distance; a rest is a dwell")
    if engine == "c":
        from .._core_time_optimal import plan_table

        return _plan(plan_table(d, motor, limits, widths), d, theta1, t0, from_c=True)
    if engine != "python":
        raise ValueError(f"engine={engine!r} is not a planner engine; valid: 'c', 'python'")
    return _plan(plan_move(d, motor, limits, widths).table, d, theta1, t0)


def time_optimal_sequence(waypoints: list[tuple[float, float]], motor: MotorParams, limits: MotorLimits, *,
                          t0: float = 0.0, engine: str = "c") -> PiecewisePlan:
    """Time-optimal rest-to-rest moves through ``waypoints`` ``[(theta, dwell), ...]``, each followed by its dwell.

    The first waypoint is the start; a dwell of the first holds the start before the first move. The tables are
    joined into one plan (one validation of the whole table).
    """
    if len(waypoints) < 2:
        raise ValueError(f"{len(waypoints)} waypoint(s): a sequence needs at least 2")
    theta = [check_finite(f"waypoint {i} theta", w[0]) for i, w in enumerate(waypoints)]
    dwell = [check_finite(f"waypoint {i} dwell", w[1]) for i, w in enumerate(waypoints)]
    t0 = check_finite("t0", t0)
    if min(dwell) < 0:
        raise ValueError(f"dwells {dwell} s must be >= 0")
    for i in range(len(theta) - 1):
        if theta[i + 1] == theta[i]:
            raise ValueError(f"waypoints {i} and {i + 1} sit at {theta[i]} rad: give the rest as a dwell")
    if engine not in ("c", "python"):
        raise ValueError(f"engine={engine!r} is not a planner engine; valid: 'c', 'python'")
    if engine == "c":
        from .._core_time_optimal import plan_table

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
