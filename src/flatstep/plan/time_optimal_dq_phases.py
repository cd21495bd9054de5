r"""The field-weakening shot's phases: speeding up from rest, the state at a switch time, braking from it.

Part of :mod:`flatstep.plan.time_optimal_dq_shoot`, integrated under the policy of
:mod:`flatstep.plan.time_optimal_dq_policy` on steps :math:`h`. The speeding-up phase (:func:`_speed_up`) is
integrated once, until it settles at the cap (a cruise: the state then constant but the angle) or passes the
distance. The braking phase (:func:`_brake`) starts from it at the switch time :math:`t_s` (:func:`switch_state`):
the target passes linearly from the speeding-up one to the braking one over :data:`SWITCH` steps (the currents'
rates stay continuous, and slow enough for the fit), and once the braking current meets the switching curve
:math:`-i_q = \sqrt{2 Q_{RATE}(V/L)(J/K_m)\omega}` (within the step: the fraction where the interpolated distance to
the curve is 0, integrated from the step's start) the move ends in the terminal ramp
(:mod:`flatstep.plan.time_optimal_dq_ramp`). A phase has at most :data:`MAX_STEPS` steps.

The reference of csrc/time_optimal_dq_phases.c, operation for operation; its loops run over time steps in Python
(the default engine is the C one).
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from .time_optimal_dq_policy import State, _Model
from .time_optimal_dq_ramp import End, terminal_ramp

Array = NDArray[np.float64]
#: Steps of one phase, at most (``TOD_MAX_STEPS``); more double the step.
MAX_STEPS = 512
#: Steps over which the target passes from the speeding-up one to the braking one at the switch.
SWITCH = 4
#: A cruise has settled when its speed and currents are this close to their targets, relatively.
SETTLE = 1e-7


class Phase(NamedTuple):
    """Samples of a phase at steps h from its start: theta, omega, i_d, i_q and the target currents there."""

    theta: Array
    omega: Array
    i_d: Array
    i_q: Array
    t_d: Array
    t_q: Array


def _empty(n: int) -> list[Array]:
    return [np.zeros(n) for _ in range(6)]


def _speed_up(md: _Model, d: float) -> Optional[tuple[list[Array], int, bool]]:
    """The speeding-up phase: arrays, samples, whether it settled in a cruise (None: MAX_STEPS too few)."""
    th, w, i_d, i_q, t_d, t_q = a = _empty(MAX_STEPS + 1)
    s: State = (0.0, 0.0, 0.0, 0.0)
    tg = md.target(0.0, False)
    for k in range(MAX_STEPS + 1):
        th[k], w[k], i_d[k], i_q[k] = s
        t_d[k], t_q[k] = tg
        if s[0] >= d:
            return a, k + 1, False
        if (abs(md.cap - s[1]) <= SETTLE * md.cap and abs(tg[0] - s[2]) <= SETTLE * md.i_max
                and abs(tg[1] - s[3]) <= SETTLE * md.i_max):
            w[k], i_d[k], i_q[k] = md.cap, tg[0], tg[1]  # settled: the cruise's steady state
            return a, k + 1, True
        if k < MAX_STEPS:
            nxt = md.next_speed_up(s, tg)
            s, tg = md.step(s, tg, nxt), nxt
    return None


def _step_index(t: float, h: float, n_acc: int) -> int:
    """The speeding-up step that time ``t`` >= 0 lies in, at most ``n_acc`` - 1."""
    k = t / h
    if not k > 0:
        return 0
    return int(k) if k < n_acc - 1 else n_acc - 1


def switch_state(md: _Model, acc: list[Array], n_acc: int, cruise: bool,
                 t_s: float) -> tuple[State, tuple[float, float]]:
    """The state at the switch ``t_s`` and the speeding-up target there."""
    h = md.h
    th, w, i_d, i_q, t_d, t_q = acc
    if cruise and t_s >= (n_acc - 1) * h:
        k = n_acc - 1
        return (th[k] + w[k] * (t_s - k * h), w[k], i_d[k], i_q[k]), (t_d[k], t_q[k])
    k = _step_index(t_s, h, n_acc)
    s: State = (th[k], w[k], i_d[k], i_q[k])
    t0 = (float(t_d[k]), float(t_q[k]))
    if not t_s > k * h:
        return s, t0
    t1 = (float(t_d[k + 1]), float(t_q[k + 1])) if k + 1 < n_acc else md.next_speed_up(s, t0)
    f = (t_s - k * h) / h
    return md.step(s, t0, t1, f), (t0[0] + f * (t1[0] - t0[0]), t0[1] + f * (t1[1] - t0[1]))


def _brake(md: _Model, acc: list[Array], n_acc: int, cruise: bool, t_s: float,
           out: Optional[list[Array]]) -> tuple[Optional[End], int]:
    """The braking phase from the switch ``t_s``: its terminal ramp and samples (None: MAX_STEPS too few)."""
    h = md.h
    s, tg = switch_state(md, acc, n_acc, cruise, t_s)  # the target passes to braking over SWITCH steps
    into = tg
    g = md.curve(s)
    if g >= 0 or not s[1] > 0:
        return terminal_ramp(md, t_s, s, tg), 0
    for j in range(MAX_STEPS):
        if out is not None:
            for arr, x in zip(out, (*s, *tg), strict=True):
                arr[j] = x
        t1 = md.next_target(s, True)
        if j + 1 < SWITCH:
            lam = (j + 1.0) / SWITCH
            t1 = (into[0] + lam * (t1[0] - into[0]), into[1] + lam * (t1[1] - into[1]))
        t_j = t_s + j * h
        w_j = (t_s + (j + 1) * h - t_j) / h  # the step the samples' times span (as the C core, for its float build)
        nxt = md.step(s, tg, t1, w_j)
        g_next = md.curve(nxt)
        if g_next >= 0 or not nxt[1] > 0:
            f = w_j * (g / (g - g_next) if g_next >= 0 else s[1] / (s[1] - nxt[1]))
            t_end = t_j + f * h
            f = (t_end - t_j) / h
            at = (tg[0] + f * (t1[0] - tg[0]), tg[1] + f * (t1[1] - tg[1]))
            return terminal_ramp(md, t_end, md.step(s, tg, t1, f), at), j + 1
        s, g, tg = nxt, g_next, t1
    return None, 0
