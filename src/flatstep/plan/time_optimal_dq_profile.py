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

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from .d_current import hermite_cubic
from .envelope import Envelope
from .limits import MotorLimits
from .piecewise import horner_rows
from .smoothing import _box, _gradient, smoothed_table, timing
from .time_optimal_dq_envelope import DQEnvelope

Array = NDArray[np.float64]
#: Samples per segment of the margin check (tau = j / CHECK, and the end).
CHECK = 8
#: Of the bus, the voltage a table may reach at its samples: the peak between them may be a little higher.
V_MARGIN = 0.995
#: The d current's extra centred box, in smoothing widths either side.
ID_SPREAD = 4
# smoothed_table's rho rows need limits; the d-q table does not read them
_ANY_LIMITS = MotorLimits(v_bus=24.0, i_max=1.0)


class DQTable(NamedTuple):
    """A move from theta = 0 at t = 0: breaks [s], theta rows, and the d current's knots [A] and slopes [A/s]."""

    breaks: Array
    theta: Array
    i_d: Array
    di_d: Array


def dq_table(distance: float, env: DQEnvelope, width: float, motor: MotorParams, passes: int = 2) -> DQTable:
    """The move on ``env`` over ``distance`` > 0 and its d current, boxed ``passes`` times by ``width`` [s], as a table.

    Theta's rows are :func:`flatstep.plan.smoothing.smoothed_table`'s (csrc/time_optimal_table.c's in C); the d
    current is sampled, cut and boxed as its speed is, then spread by a centred running mean of ``ID_SPREAD``
    widths either side (narrowed towards the ends, where it is 0 at rest): it changes slower than the torque
    current. Its knots are theta's.
    """
    speed_env = Envelope(env.omega, env.a_plus, env.a_minus)
    table = smoothed_table(distance, speed_env, width, motor, _ANY_LIMITS, passes)
    b, dt, n_box, n, r, k = timing(distance, speed_env, width)
    total = b.t1 + b.cruise + b.t2
    i = np.arange(n - k)
    t = np.where(i < r, i, i + k) * dt
    # the d current of the side at the bang-bang move's speed, read against time (the envelope's speed and d current
    # are both linear between the same grid points): the top while speeding up and cruising, the bottom while braking
    cruise = np.interp(b.w_peak, env.omega, env.id_plus)
    i_d = np.where(t <= b.t1, np.interp(t, b.t_acc, env.id_plus),
                   np.where(t < b.t1 + b.cruise, cruise, np.interp(total - t, b.t_dec, env.id_minus)))
    i_d[-1] = 0.0
    for _ in range(passes):
        i_d = _box(i_d, n_box)
    j = np.arange(i_d.size)
    half = np.minimum(np.minimum(j, i_d.size - 1 - j), ID_SPREAD * n_box)
    csum = np.concatenate([[0.0], np.cumsum(i_d)])
    i_d = (csum[j + half + 1] - csum[j - half]) / (2 * half + 1)
    r = min(r, i_d.size - 1)
    knots = np.rint(table.breaks / dt).astype(np.intp)  # the breaks are knot indices times dt
    at = np.where(knots < r, knots, np.where(knots >= r + k, knots - k, r))
    id_k, did_k = i_d[at], _gradient(i_d, dt)[at]
    did_k[0] = did_k[-1] = 0.0
    return DQTable(table.breaks, table.theta, id_k, did_k)


def dq_margins(table: DQTable, motor: MotorParams, v_limit: float, i_max: float, speed_max: float,
               samples: int = CHECK) -> dict[str, float]:
    r"""The table's worst use of the bus, the current and the speed cap, at ``samples`` points per segment and the end.

    The voltages are the d-q flat inverse along the plan (the steady terms and :math:`L\dot i_d`,
    :math:`L\dot i_q`, :math:`i_q = (J\ddot\theta + B\dot\theta)/K_m`); ``worst`` is the largest ratio less 1,
    the voltage's over ``V_MARGIN``.
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
    out["worst"] = max(out["voltage"] / V_MARGIN, out["current"], out["speed"]) - 1.0
    return out

