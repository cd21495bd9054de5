r"""The smoothed move of the field-weakening planner: the bang-bang move and its d current, filtered, fitted, checked.

The second stage of :mod:`flatstep.plan.time_optimal_dq`, after :mod:`~flatstep.plan.time_optimal_dq_envelope`.
The bang-bang move on the envelope is sampled with the d current of its side (the top of the envelope's discs while
speeding up and cruising, the bottom while braking), both are convolved twice with a box of width :math:`w` (as
:mod:`flatstep.plan.smoothing` does for the speed alone), and fitted at the knots: theta as degree-7 segments
through :math:`(\theta, \dot\theta, \ddot\theta, \theta^{(3)})`, :math:`i_d^*` as cubic Hermite pieces through
:math:`(i_d, \dot i_d)`, so the d-q law reads a continuous :math:`\dot i_d^*` and :math:`\theta^{(3)}`.
Averaging keeps the currents inside the current disc (it is convex); the bus disc moves with the speed, and the
inductance needs :math:`L\dot i` on top, which :func:`dq_margins` measures on the fitted table.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from .d_current import hermite_cubic
from .envelope import Envelope
from .piecewise import horner_rows
from .segments import hermite_rows
from .smoothing import _box, _gradient, _knots, timing
from .time_optimal_dq_envelope import DQEnvelope

Array = NDArray[np.float64]
#: Samples per segment of the margin check (tau = j / CHECK, and the end).
CHECK = 8
#: The d current's extra centred box, in smoothing widths either side.
ID_SPREAD = 4


class DQTable(NamedTuple):
    """A move from theta = 0 at t = 0: breaks [s], theta rows, and the d current's knots [A] and slopes [A/s]."""

    breaks: Array
    theta: Array
    i_d: Array
    di_d: Array


def dq_table(distance: float, env: DQEnvelope, width: float, passes: int = 2) -> DQTable:
    """The bang-bang move on ``env`` over ``distance`` > 0 and its d current, smoothed by ``width`` [s], as a table.

    The sampling, the cut of a long cruise and the knots are those of :func:`flatstep.plan.smoothing.smoothed_table`.
    """
    speed_env = Envelope(env.omega, env.a_plus, env.a_minus)
    b, dt, n_box, n, r, k = timing(distance, speed_env, width)
    total = b.t1 + b.cruise + b.t2
    i = np.arange(n - k)
    t = np.where(i < r, i, i + k) * dt
    braking = t >= b.t1 + b.cruise
    speed = np.where(t <= b.t1, np.interp(t, b.t_acc, env.omega),
                     np.where(~braking, b.w_peak, np.interp(total - t, b.t_dec, env.omega)))
    speed[-1] = 0.0
    # the d current of the side: the envelope's top while speeding up and cruising, its bottom while braking
    i_d = np.where(braking, np.interp(speed, env.omega, env.id_minus), np.interp(speed, env.omega, env.id_plus))
    i_d[-1] = 0.0
    for _ in range(passes):
        i_d = _box(i_d, n_box)
    # a centred running mean more, of ID_SPREAD widths either side, narrowed towards the ends so that the d
    # current still starts and ends at rest: the d current changes slower than the torque current
    j = np.arange(i_d.size)
    half = np.minimum(np.minimum(j, i_d.size - 1 - j), ID_SPREAD * n_box)
    csum = np.concatenate([[0.0], np.cumsum(i_d)])
    i_d = (csum[j + half + 1] - csum[j - half]) / (2 * half + 1)
    for _ in range(passes):
        speed = _box(speed, n_box)
    inc = 0.5 * (speed[1:] + speed[:-1]) * dt
    r = min(r, speed.size - 1)
    cruise = speed[r] if k else 0.0
    covered = float(np.sum(inc) + k * dt * cruise)
    if not (covered > 0 and math.isfinite(covered)):
        raise ValueError(f"the smoothed profile of {distance:g} rad at width {width:g} s covers no angle")
    scale = distance / covered
    knots = _knots(speed.size - 1 + k, (b.t1 + passes * width) / dt + 4, (b.t1 + b.cruise) / dt - 4, b.cruise > 0)
    at = np.where(knots < r, knots, np.where(knots >= r + k, knots - k, r))
    sums = np.where(at[1:] > at[:-1], np.add.reduceat(inc, np.minimum(at[:-1], inc.size - 1)), 0.0)
    cut = np.clip(knots[1:], r, r + k) - np.clip(knots[:-1], r, r + k)
    step = (sums + cut * dt * cruise) * scale
    angle = np.concatenate([[0.0], np.cumsum(step)])
    step[-1] = distance - angle[-2]
    speed = speed * scale
    acc = _gradient(speed, dt)
    jerk = _gradient(acc, dt)
    state = np.column_stack([angle, speed[at], acc[at], jerk[at]])
    state[0, 1:] = state[-1, 1:] = 0.0
    h = np.diff(knots) * dt
    start, end = state[:-1].copy(), state[1:].copy()
    start[:, 0], end[:, 0] = 0.0, step
    rows = hermite_rows(start, end, h)
    rows[:, -1] += angle[:-1]
    id_k, did_k = i_d[at], _gradient(i_d, dt)[at]
    did_k[0] = did_k[-1] = 0.0
    return DQTable(np.concatenate([[0.0], np.cumsum(h)]), rows, id_k, did_k)


def dq_margins(table: DQTable, motor: MotorParams, v_limit: float, i_max: float, speed_max: float,
               samples: int = CHECK) -> dict[str, float]:
    r"""The table's worst use of the bus, the current and the speed cap, at ``samples`` points per segment and the end.

    The voltages are the d-q flat inverse along the plan (the steady terms and :math:`L\dot i_d`,
    :math:`L\dot i_q`, :math:`i_q = (J\ddot\theta + B\dot\theta)/K_m`); ``worst`` is the largest ratio less 1.
    """
    m = motor
    hs = np.diff(table.breaks)
    tau = np.arange(samples) / samples
    seg = np.append(np.repeat(np.arange(hs.size), tau.size), hs.size - 1)
    tt = np.append(np.tile(tau, hs.size), 1.0)
    w, acc, jerk = (horner_rows(table.theta, seg, tt, k) / hs[seg] ** k for k in (1, 2, 3))
    i_d, di_d = hermite_cubic(table.breaks[seg] + tt * hs[seg], table.breaks, table.i_d, table.di_d)
    i_q = (m.J * acc + m.B * w) / m.Km
    di_q = (m.J * jerk + m.B * acc) / m.Km
    x = m.Nr * w * m.L
    v_d = m.R * i_d + m.L * di_d - x * i_q
    v_q = m.R * i_q + m.L * di_q + x * i_d + m.Km * w
    out = dict(voltage=float(np.max(np.hypot(v_d, v_q))) / v_limit,
               current=float(np.max(np.hypot(i_d, i_q))) / i_max,
               speed=float(np.max(np.abs(w))) / speed_max, i_d_min=float(np.min(i_d)),
               speed_peak=float(np.max(np.abs(w))))
    out["worst"] = max(out["voltage"], out["current"], out["speed"]) - 1.0
    return out

