r"""The shot move of the field-weakening planner as a table: knots picked, theta and i_d fitted, the margins checked.

The second stage of :mod:`flatstep.plan.time_optimal_dq`, after :mod:`~flatstep.plan.time_optimal_dq_shoot`.
The samples of the shot (its steps, the switch, the start of the terminal ramp and the end at rest) carry the state
and, on either side, the currents' rates of the model under the held voltages. :func:`dq_fit` keeps at most
:data:`KNOTS` of them as knots (the switch, the cruise's ends and the ramp's start always; the others where the
currents' rates change most, with a share per rise time), and fits theta as degree-7 segments through
:math:`(\theta, \dot\theta, \ddot\theta, \theta^{(3)})` at both ends of each segment, the jerk from the segment's own
side (it jumps where the held voltage jumps, which the d-q law takes), and :math:`i_d^*` as cubic Hermite pieces
through :math:`(i_d, \dot i_d)`, the rate the mean of both sides. :func:`dq_margins` measures the voltages of the
d-q flat inverse on the fitted table, the :math:`L\dot i` terms included.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from .d_current import hermite_cubic
from .piecewise import horner_rows
from .segments import hermite_rows
from .time_optimal_dq_phases import SWITCH
from .time_optimal_dq_shoot import Shot

Array = NDArray[np.float64]
#: Samples per segment of the margin check (tau = j / CHECK, and the end).
CHECK = 8
#: Of the bus, the voltage a table may reach at its samples: the peak between them may be a little higher.
V_MARGIN = 0.995
#: Knots picked by the measure, at most (besides the switch, the cruise's ends, the ramp's start and the ends).
KNOTS = 62
#: The measure's share of one current rise time, against one full change of a current's rate (V / L).
TIME_WEIGHT = 2.0
#: Samples closer than this share of a step to the next one are dropped.
CLOSE = 0.25


class DQTable(NamedTuple):
    """A move from theta = 0 at t = 0: breaks [s], theta rows, and the d current's knots [A] and slopes [A/s]."""

    breaks: Array
    theta: Array
    i_d: Array
    di_d: Array


class Samples(NamedTuple):
    """The shot's samples: times, states, the currents' rates, and the knots that must stay."""

    t: Array
    theta: Array
    omega: Array
    i_d: Array
    i_q: Array
    did: Array
    diq: Array
    keep: NDArray[np.bool_]


def _rates(m: MotorParams, v: float, gain: float, s: Array, tg: Array) -> tuple[Array, Array]:
    """(di_d, di_q) of the model at states ``s`` (rows theta, omega, i_d, i_q) under the shot's policy.

    ``tg``: the targets (rows t_d, t_q; time_optimal_dq_shoot's ``policy``).
    """
    _, w, i_d, i_q = s
    x = m.Nr * w * m.L
    a_d, a_q = m.R * i_d - x * i_q, m.R * i_q + x * i_d + m.Km * w
    v_d, v_q = a_d + gain * (tg[0] - i_d), a_q + gain * (tg[1] - i_q)
    n2 = v_d * v_d + v_q * v_q
    scale = np.where(n2 > v * v, v / np.sqrt(np.where(n2 > 0, n2, 1.0)), 1.0)
    inv_l = 1.0 / m.L
    return (v_d * scale - a_d) * inv_l, (v_q * scale - a_q) * inv_l


def samples(shot: Shot, d: float, m: MotorParams) -> Samples:
    """The samples of ``shot`` over ``d`` in time order, with the currents' rates (module docstring).

    The rates are continuous: the bridge at the end of the braking takes them from the braking policy's to the
    terminal ramp's (time_optimal_dq_shoot), and its ends are knots.
    """
    h, a, b, e = shot.h, shot.accel, shot.brake, shot.end
    na, nb = shot.n_acc, shot.n_brake
    tt = np.concatenate([np.arange(na) * h, shot.t_s + np.arange(nb) * h])
    s = np.hstack([np.array([a.theta[:na], a.omega[:na], a.i_d[:na], a.i_q[:na]]),
                   np.array([b.theta[:nb], b.omega[:nb], b.i_d[:nb], b.i_q[:nb]])])
    tg = np.hstack([np.array([a.t_d[:na], a.t_q[:na]]), np.array([b.t_d[:nb], b.t_q[:nb]])])
    did, diq = _rates(m, shot.v, shot.gain, s, tg)
    keep = np.zeros(tt.size, dtype=bool)
    keep[0] = True
    if shot.cruise:
        keep[na - 1] = True
    if nb:
        keep[na] = True  # the switch
    if nb > SWITCH:
        keep[na + SWITCH] = True  # the end of the target's passage to braking (the rates turn there)
    # the bridge's start (the braking rates), the ramp's start and the end at rest (module docstring)
    r_d, r_q = _rates(m, shot.v, shot.gain, np.array([[e.theta], [e.omega], [e.i_d], [e.i_q]]),
                      np.array([[e.t_d], [e.t_q]]))
    alpha1 = (m.Km * e.i_q1 - m.B * e.omega1) / m.J
    jerk = -alpha1 / e.tau if e.tau > 0 else 0.0
    ramp_d = -e.d_share * e.i_d1 / e.tau if e.tau > 0 else 0.0
    rest_d = -(2.0 - e.d_share) * e.i_d1 / e.tau if e.tau > 0 else 0.0
    tt = np.concatenate([tt, [e.t, e.t + e.bridge, e.t_end]])
    s = np.column_stack([s, [e.theta, e.omega, e.i_d, e.i_q], [e.theta1, e.omega1, e.i_d1, e.i_q1], [d, 0.0, 0.0, 0.0]])
    did = np.concatenate([did, r_d, [ramp_d, rest_d]])
    diq = np.concatenate([diq, r_q, [(m.J * jerk + m.B * alpha1) / m.Km, m.J * jerk / m.Km]])
    keep = np.concatenate([keep, [True, True, True]])
    # a sample closer than CLOSE h to the one before is dropped (a kept one replaces one not kept, the end any)
    idx = [0]
    for i in range(1, tt.size):
        if tt[i] - tt[idx[-1]] >= CLOSE * h or keep[i] and keep[idx[-1]] and tt[i] > tt[idx[-1]] * (1 + 1e-12):
            idx.append(i)
        elif keep[i] and (not keep[idx[-1]] or i == tt.size - 1) and len(idx) > 1:
            idx[-1] = i  # (the end at rest is never dropped: it replaces the one before it)
    th, w, i_d, i_q = s[:, idx]
    return Samples(tt[idx], th, w, i_d, i_q, did[idx], diq[idx], keep[idx])


def pick_knots(sm: Samples, rise: float, rate: float) -> NDArray[np.intp]:
    """Indices of the knots: the kept samples and :data:`KNOTS` more at equal steps of the measure."""
    n = sm.t.size
    if n <= KNOTS + 6:
        return np.arange(n)
    dt = np.diff(sm.t)
    change = (np.abs(np.diff(sm.diq)) + np.abs(np.diff(sm.did))) / rate
    cruise = (np.diff(sm.omega) == 0) & (np.diff(sm.i_q) == 0) & (np.diff(sm.i_d) == 0)  # settled: only theta moves
    weight = np.where(cruise, 0.0, TIME_WEIGHT * dt / rise + change)
    meas = np.concatenate([[0.0], np.cumsum(weight)])
    levels = meas[-1] * np.arange(1, KNOTS + 1) / (KNOTS + 1)
    chosen = np.searchsorted(meas, levels)
    return np.union1d(np.flatnonzero(sm.keep), chosen)


def dq_fit(shot: Shot, d: float, m: MotorParams, v: float, i_max: float) -> DQTable:
    """The table of ``shot`` over ``d`` > 0, integrated at bus ``v`` [V] and current ``i_max`` [A] (module doc)."""
    sm = samples(shot, d, m)
    k = pick_knots(sm, m.L * i_max / v, v / m.L)
    t = sm.t[k]
    alpha = (m.Km * sm.i_q[k] - m.B * sm.omega[k]) / m.J
    jerk = (m.Km * sm.diq[k] - m.B * alpha) / m.J
    state = np.column_stack([sm.theta[k], sm.omega[k], alpha, jerk])
    theta = hermite_rows(state[:-1], state[1:], np.diff(t))
    did = sm.did[k].copy()
    did[0] = 0.0
    i_d = sm.i_d[k].copy()
    i_d[-1] = 0.0
    return DQTable(t - t[0], theta, i_d, did)


def dq_margins(table: DQTable, motor: MotorParams, v_limit: float, i_max: float, speed_max: float,
               samples: int = CHECK) -> dict[str, float]:
    r"""The table's worst use of the bus, the current and the speed cap, at ``samples`` points per segment and the end.

    The voltages are the d-q flat inverse along the plan (the steady terms and :math:`L\dot i_d`,
    :math:`L\dot i_q`, :math:`i_q = (J\ddot\theta + B\dot\theta)/K_m`); ``worst`` is the largest ratio less 1,
    the voltage's over ``V_MARGIN``.
    """
    m = motor
    hs = np.diff(table.breaks)
    ih = 1.0 / hs
    if not np.all(np.isfinite(ih * ih * ih * ih)):  # a segment too short for a table (traj_valid): none
        return dict(voltage=math.inf, current=math.inf, speed=math.inf, i_d_min=math.nan, speed_peak=math.nan,
                    worst=math.inf)
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
