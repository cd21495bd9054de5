r"""A plan as a machine runs it: step timestamps for a step/dir driver, and a setpoint stream for a servo drive.

**Step timestamps.** A step/dir driver at ``microsteps`` per full step moves the rotor in increments
:math:`\Delta = \pi / (2 N_r m)`. After :math:`n` net steps it commands :math:`\theta_1 + n\Delta`. The export
keeps :math:`n(t) = \lfloor(\theta(t) - \theta_1)/\Delta + 1/2\rfloor`, the microstep nearest the plan: a step is
due wherever :math:`\theta(t)` crosses a level :math:`\theta_1 + (k - 1/2)\Delta`, upward (direction +1) or
downward (-1). Each segment of the plan's table is split where :math:`\dot\theta` changes sign (the roots of the
derivative polynomial), so that :math:`\theta` is monotone on every piece; on each piece all its crossings are
found at once: bracketed on a grid, refined by Newton's method inside the bracket, and each one's error bound
checked by the sign change around it (a bisection where the check fails).
Between two steps the commanded position is within :math:`\Delta/2` of the plan; a timer of ``timer_rate`` Hz
rounds each timestamp to its tick, which adds at most :math:`|\dot\theta|_{max}/(2 f_{timer})`:
:attr:`StepTrain.position_bound` is that sum.

**Setpoint stream.** Samples at ``rate`` Hz from ``t_start`` (the plan's start) through its end: the angle,
speed and acceleration of the plan, the torque the move needs (:math:`J\ddot\theta + B\dot\theta` plus the
constant load), and the d and q currents of the plan's state through the flat maps (the paper's
:math:`(\rho, \theta)` plans: the current vector the plan itself sets; or the d current of a
:class:`~flatstep.plan.d_current.DCurrentPlan` with :math:`i_q` = torque / :math:`K_m`). It is what a
field-oriented drive that accepts feedforward terms takes. As CSV (header ``t,...``), or as a C header holding
a ``static const float`` table that the C core's ``setpoint_at`` (csrc/setpoints.h) replays: row :math:`k` at
:math:`t_0 + k/f`, held or linearly interpolated between rows.
"""
from __future__ import annotations

import io
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

import numpy as np
from numpy.typing import NDArray

from ..model.flat import flat_to_state
from ..model.flat_dq import park
from ..model.motor import MotorParams
from ..validate import InputError, check_count, check_finite, check_quantity
from .d_current import DCurrentPlan
from .piecewise import FALL, NCOEF, PiecewisePlan, horner
from .protocol import Plan, check_plan

Array = NDArray[np.float64]
#: Samples per monotone piece that bracket each crossing before Newton's method.
GRID = 64
#: Newton steps per crossing (quadratic convergence from a bracket of 1/63 of the piece).
NEWTON_STEPS = 6
#: Largest half-width of a crossing's bracket in the local time that Newton's result may keep.
TAU_TOLERANCE = 1e-9
#: Halvings of the local time for a crossing Newton did not settle: 2^-52 of a segment.
BISECTION_STEPS = 52
#: Most step events one export may hold (a 20-rad move at 256 microsteps on a 50-tooth rotor is 163,000).
MAX_STEPS = 20_000_000
#: Most rows of one setpoint stream.
MAX_ROWS = 20_000_000
#: Columns of a setpoint stream after ``t``, in the order of ``enum setpoint_column`` (csrc/setpoints.h).
SETPOINT_COLUMNS = ("theta", "omega", "alpha", "torque", "i_d", "i_q")
#: Their units.
SETPOINT_UNITS = ("rad", "rad/s", "rad/s^2", "N m", "A", "A")


@dataclass(frozen=True)
class StepTrain:
    """Step events of a step/dir driver: when each step is due and its direction.

    Attributes
    ----------
    t : ndarray
        The step times [s], nondecreasing.
    direction : ndarray
        +1 or -1 per step (int8).
    increment : float
        The rotor angle of one microstep [rad].
    theta1 : float
        The angle the count starts from [rad] (the plan's start).
    timing_error : float
        The largest difference between a step's timestamp and its exact crossing [s].
    position_bound : float
        The most the commanded position differs from the plan at any time [rad].
    """

    t: Array
    direction: NDArray[np.int8]
    increment: float
    theta1: float
    timing_error: float
    position_bound: float

    @property
    def positions(self) -> Array:
        """The commanded angle after each step [rad]."""
        return self.theta1 + np.cumsum(self.direction.astype(float)) * self.increment

    def commanded(self, t: Array) -> Array:
        """The commanded angle at times ``t`` [rad]: after every step due at or before t."""
        count = np.concatenate([[0.0], np.cumsum(self.direction.astype(float))])
        return self.theta1 + count[np.searchsorted(self.t, np.asarray(t, dtype=float), side="right")] * self.increment


def _pieces(table: PiecewisePlan) -> tuple[NDArray[np.intp], Array, Array]:
    """The monotone pieces of theta: segment index and local-time bounds (tau_a, tau_b) of each."""
    segs, lo, hi = [], [], []
    for i, row in enumerate(table.theta):  # a loop over segments (tens), not over samples
        derivative = np.polyder(np.trim_zeros(row, "f")) if np.any(row[:-1]) else np.zeros(1)
        cuts = [0.0, 1.0]
        if derivative.size > 1:
            roots = np.roots(derivative)
            real = roots[np.abs(roots.imag) < 1e-9].real
            cuts += [float(r) for r in real if 0.0 < r < 1.0]
        cuts = sorted(set(cuts))
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            segs.append(i)
            lo.append(a)
            hi.append(b)
    return np.array(segs, dtype=np.intp), np.array(lo), np.array(hi)


def _columns(cols: Array, tau: Array, order: int = 0) -> Array:
    """:func:`~flatstep.plan.piecewise.horner` on coefficients stored by power (11, m): contiguous reads."""
    a = cols[0] * FALL[order, 0] if order else cols[0].copy()
    for j in range(1, NCOEF - order):  # a loop over the degree, vectorized over the rows
        a = a * tau + (cols[j] * FALL[order, j] if order else cols[j])
    return a


def _crossings(coef: Array, sign: Array, level: Array, lo: Array, hi: Array,
               piece: NDArray[np.intp]) -> tuple[Array, Array, float]:
    """Each row's crossing of its level: the local time, a half-width that brackets it, the largest offset.

    The offset is the most the polynomial differs from its level anywhere within those brackets.

    A row rises through its level (``sign`` +1) or falls (-1) on its piece ``[lo, hi][piece]``. The start is
    the grid cell of :data:`GRID` samples per piece that holds the crossing, then :data:`NEWTON_STEPS` Newton
    steps kept inside the bracket (a bisection where Newton would leave it). The half-width ``w`` is checked: at
    most :data:`TAU_TOLERANCE`, the polynomial within 64 roundings of its level, and its sign differs at
    ``tau - w`` and ``tau + w``; a row where any fails is bisected to :data:`BISECTION_STEPS` halvings.
    """
    cols = np.ascontiguousarray(coef.T)  # one contiguous row per power: Horner reads them in turn
    grid = np.linspace(0.0, 1.0, GRID)
    pieces = np.unique(piece)
    t_lo, t_hi = lo[piece].copy(), hi[piece].copy()
    starts = np.searchsorted(piece, pieces)  # the steps of a piece are contiguous
    ends = np.searchsorted(piece, pieces, side="right")
    for p, a, b in zip(pieces, starts, ends, strict=True):  # a loop over monotone pieces (tens)
        where = lo[p] + grid * (hi[p] - lo[p])
        values = sign[a] * horner(np.repeat(coef[a:a + 1], GRID, axis=0), where)
        cell = np.clip(np.searchsorted(values, sign[a:b] * level[a:b], side="left") - 1, 0, GRID - 2)
        t_lo[a:b], t_hi[a:b] = where[cell], where[cell + 1]
    t = 0.5 * (t_lo + t_hi)
    for _ in range(NEWTON_STEPS):  # a loop over iterations, vectorized over every step
        f = sign * (_columns(cols, t) - level)
        slope = sign * _columns(cols, t, 1)
        below = f < 0
        t_lo, t_hi = np.where(below, t, t_lo), np.where(below, t_hi, t)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = t - f / slope
        inside = np.isfinite(step) & (step > t_lo) & (step < t_hi)
        t = np.where(inside, step, 0.5 * (t_lo + t_hi))
    f = sign * (_columns(cols, t) - level)
    noise = 16 * np.finfo(float).eps * (np.abs(level) + 1.0)  # the rounding of one evaluation of theta
    with np.errstate(divide="ignore", invalid="ignore"):
        width = (2.0 * np.abs(f) + noise) / np.abs(_columns(cols, t, 1))
    width = np.where(np.isfinite(width), width, np.inf)
    ok = ((width <= TAU_TOLERANCE) & (np.abs(f) <= 64 * noise) & (sign * (_columns(cols, t - width) - level) < 0)
          & (sign * (_columns(cols, t + width) - level) >= 0))
    bad = np.flatnonzero(~ok)
    if bad.size:  # the few Newton did not settle: bisection on their brackets
        b_lo, b_hi = lo[piece[bad]].copy(), hi[piece[bad]].copy()
        for _ in range(BISECTION_STEPS):
            mid = 0.5 * (b_lo + b_hi)
            below = sign[bad] * (horner(coef[bad], mid) - level[bad]) < 0
            b_lo, b_hi = np.where(below, mid, b_lo), np.where(below, b_hi, mid)
        t[bad], width[bad] = b_hi, b_hi - b_lo
        f[bad] = sign[bad] * (horner(coef[bad], t[bad]) - level[bad])
    # within a bracket theta moves by at most |f| + noise on either side of the crossing (it is monotone there)
    return t, width, float(np.max(2.0 * np.abs(f) + noise, initial=0.0))


def step_times(plan: Plan, motor: MotorParams, microsteps: int = 16, *,
               timer_rate: Optional[float] = None) -> StepTrain:
    r"""The step timestamps that make a step/dir driver follow ``plan`` to the nearest microstep.

    Parameters
    ----------
    plan : Plan
        Any plan (its segment table is used).
    motor : MotorParams
        The motor: its ``Nr`` gives the full step :math:`\pi/(2N_r)`.
    microsteps : int
        Microsteps per full step of the driver, 1 to 1024.
    timer_rate : float, optional
        The step timer's clock [Hz]: each timestamp rounds to its tick. Default: exact (double) times.

    Returns
    -------
    StepTrain
        The step times and directions, with the timing and position error bounds.

    Raises
    ------
    ValueError
        A bad argument, or a move needing more than :data:`MAX_STEPS` steps.
    """
    check_plan(plan)
    microsteps = check_count("microsteps", microsteps)
    if timer_rate is not None:
        timer_rate = check_quantity("rate", timer_rate, as_name="timer_rate")
    table = plan.to_table()
    increment = math.pi / (2 * motor.Nr * microsteps)
    theta1 = table.theta1
    segs, lo, hi = _pieces(table)
    rows = table.theta[segs]
    a_val, b_val = horner(rows, lo), horner(rows, hi)
    n_a = np.floor((a_val - theta1) / increment + 0.5)
    n_b = np.floor((b_val - theta1) / increment + 0.5)
    counts = np.abs(n_b - n_a).astype(np.int64)
    total = int(counts.sum())
    if total > MAX_STEPS:
        raise InputError("microsteps", microsteps, f"the move needs {total} steps at microsteps={microsteps}, more "
                         f"than the {MAX_STEPS} one export holds; use fewer microsteps")
    piece = np.repeat(np.arange(segs.size), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    j = np.arange(total) - first  # the crossing's rank within its piece
    up = n_b[piece] >= n_a[piece]
    k = np.where(up, n_a[piece] + 1 + j, n_a[piece] - j)  # the level crossed: theta1 + (k - 1/2) increment
    level = theta1 + (k - 0.5) * increment
    coef = rows[piece]
    sign = np.where(up, 1.0, -1.0)
    tau, halfwidth, off_level = _crossings(coef, sign, level, lo, hi, piece)
    breaks = table.breaks
    i = segs[piece]
    h = breaks[i + 1] - breaks[i]
    t = breaks[i] + tau * h
    order = np.argsort(t, kind="stable")
    t, direction = t[order], np.where(up, 1, -1).astype(np.int8)[order]
    exact_error = float(np.max(halfwidth * h, initial=0.0))
    speed = float(np.max(np.abs(table.theta_deriv(np.linspace(table.t0, table.tf, 4097), 1))))
    bound = 0.5 * increment + off_level
    if timer_rate is not None:
        t = np.round(t * timer_rate) / timer_rate
        return StepTrain(t, direction, increment, theta1, 0.5 / timer_rate + exact_error,
                         bound + speed * 0.5 / timer_rate)
    return StepTrain(t, direction, increment, theta1, exact_error, bound)


@dataclass(frozen=True)
class SetpointStream:
    """Setpoints sampled at a fixed rate: row k at ``t0 + k / rate``.

    Attributes
    ----------
    t0 : float
        The first row's time [s].
    rate : float
        Rows per second [Hz].
    rows : ndarray
        (n, 6) float64: :data:`SETPOINT_COLUMNS` per row.
    """

    t0: float
    rate: float
    rows: Array

    @property
    def t(self) -> Array:
        """Each row's time [s]."""
        return self.t0 + np.arange(self.rows.shape[0]) / self.rate

    def to_csv(self, path: Union[str, Path]) -> None:
        """Write the stream as CSV: ``t`` then :data:`SETPOINT_COLUMNS`, one row per sample, full precision."""
        header = "t," + ",".join(f"{c}" for c in SETPOINT_COLUMNS)
        np.savetxt(path, np.column_stack([self.t, self.rows]), delimiter=",", header=header, comments="",
                   fmt="%.17g")

    def c_table(self, name: str = "setpoints") -> str:
        """The stream as a C header: a ``static const float`` table for ``setpoint_at`` (csrc/setpoints.h)."""
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            raise InputError("name", name, f"name={name!r} is not a C identifier (letters, digits, _; not a digit "
                             "first)")
        upper = name.upper()
        buffer = io.StringIO()  # %#.9g: 9 digits give back the float exactly; '#' keeps the point ("1.00000000f")
        np.savetxt(buffer, self.rows.astype(np.float32).astype(np.float64),
                   fmt="    {" + ", ".join(["%#.9gf"] * len(SETPOINT_COLUMNS)) + "},")
        rows = buffer.getvalue().rstrip().rstrip(",")
        units = ", ".join(f"{c} [{u}]" for c, u in zip(SETPOINT_COLUMNS, SETPOINT_UNITS, strict=True))
        return (f"/* Setpoints written by flatstep: row k at {upper}_T0 + k / {upper}_RATE; columns {units}.\n"
                f"   Replay with setpoint_at() (csrc/setpoints.h). */\n"
                f"#ifndef {upper}_TABLE_H\n#define {upper}_TABLE_H\n"
                f"#define {upper}_ROWS {self.rows.shape[0]}u\n"
                f"#define {upper}_T0 {self.t0!r}\n#define {upper}_RATE {self.rate!r}\n"
                f"static const float {name}[{upper}_ROWS][{len(SETPOINT_COLUMNS)}] = {{\n{rows}\n}};\n"
                f"#endif\n")


def setpoint_stream(plan: Plan, motor: MotorParams, rate: float, *, load_torque: float = 0.0,
                    d_current: Optional[DCurrentPlan] = None, t_end: Optional[float] = None) -> SetpointStream:
    r"""The plan sampled at ``rate`` as setpoints for a field-oriented drive (module docstring).

    Parameters
    ----------
    plan : Plan
        Any plan.
    motor : MotorParams
        The motor model of the flat maps.
    rate : float
        Samples per second [Hz].
    load_torque : float
        The constant load torque the feedforward includes [N m].
    d_current : DCurrentPlan, optional
        The planned d current (for the d-q law's plans); default: the currents of the plan's own state.
    t_end : float, optional
        The last sample's time [s], at least the plan's end (default: its end).

    Returns
    -------
    SetpointStream
        The samples from the plan's start.

    Raises
    ------
    ValueError
        A bad argument, more than :data:`MAX_ROWS` rows, or a plan outside the flat maps' domain.
    """
    check_plan(plan)
    rate = check_quantity("rate", rate)
    load_torque = check_finite("load_torque", load_torque)
    end = plan.tf if t_end is None else check_finite("t_end", t_end)
    if end < plan.tf:
        raise InputError("t_end", t_end, f"t_end={t_end!r} s ends before the plan does ({plan.tf!r} s)")
    n = int(math.floor((end - plan.t0) * rate * (1 + 1e-12))) + 1
    if n > MAX_ROWS:
        raise InputError("rate", rate, f"{n} rows at rate={rate!r} Hz: more than the {MAX_ROWS} a stream holds")
    t = plan.t0 + np.arange(n) / rate
    flag = plan.flag(t)
    theta, omega, alpha = (np.asarray(a, dtype=float) for a in (flag.theta, flag.dtheta, flag.ddtheta))
    torque = motor.J * alpha + motor.B * omega + load_torque
    if d_current is None:
        x, _ = flat_to_state(flag, motor, load_torque)
        i_d, i_q = park(x[0], x[1], motor.Nr * theta)
    else:
        i_d, _ = d_current.flag(t, omega, alpha)
        i_q = torque / motor.Km
    rows = np.column_stack([theta, omega, alpha, torque, i_d, i_q])
    if not np.isfinite(rows).all():
        raise ValueError("the setpoints are not finite: the plan leaves the flat maps' domain")
    return SetpointStream(float(plan.t0), rate, rows)


__all__ = ["BISECTION_STEPS", "GRID", "NEWTON_STEPS", "TAU_TOLERANCE", "MAX_ROWS", "MAX_STEPS", "SETPOINT_COLUMNS",
           "SETPOINT_UNITS", "SetpointStream", "StepTrain", "setpoint_stream", "step_times"]
