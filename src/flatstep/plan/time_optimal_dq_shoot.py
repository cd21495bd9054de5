r"""The field-weakening move by shooting: the nominal d-q model driven at the bus's full rate, the switch found.

The first stage of :mod:`flatstep.plan.time_optimal_dq`, in four parts. The d-q model is integrated by RK4 on steps
:math:`h` of :data:`STEPS` per current rise time :math:`L i_{max}/V` under a bus-saturated current-steering policy
whose target is the envelope's best current at the speed each step ends at: the top of the two discs while speeding
up, the bottom while braking (:mod:`flatstep.plan.time_optimal_dq_policy`). The speeding-up phase is integrated
once, until it settles at the cap (a cruise) or passes the distance; the braking phase starts from it at the switch
time :math:`t_s` and ends where the braking current meets the terminal ramp's switching curve
(:mod:`flatstep.plan.time_optimal_dq_phases`); a short bridge and the terminal ramp then take the move to rest
(:mod:`flatstep.plan.time_optimal_dq_ramp`). This module finds the switch and keeps the ramp within the bus.

The braking phase's end angle rises with :math:`t_s`, and the Illinois variant of regula falsi finds the
:math:`t_s` that lands on the distance in at most :data:`ROOT` braking phases; its first try is :func:`estimate`
(the braking distance from the bracket's top, scaled by the square of the speed; exact on a cruise). Where the ramp
would leave the bus (at its start or its end), its rate falls, and a rate that fell far within it is raised once
(:func:`shoot`). A phase that needs more than :data:`MAX_STEPS` steps doubles the step (at most :data:`DOUBLINGS`
times).

This module is the reference of csrc/time_optimal_dq_shoot.c, operation for operation; its loops run over time
steps in Python (the default engine is the C one).
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

from ..model.motor import MotorParams
from .time_optimal_dq_phases import MAX_STEPS, Array, Phase, _brake, _empty, _speed_up, _step_index
from .time_optimal_dq_policy import _Model
from .time_optimal_dq_ramp import End, ramp_voltage

#: Integration steps per current rise time L i_max / V (csrc/time_optimal_dq.h ``TOD_STEPS``).
STEPS = 10
#: Doublings of the step, at most (``TOD_DOUBLINGS``).
DOUBLINGS = 8
#: Braking phases tried by the root finder on the switch time, at most (``TOD_ROOT``).
ROOT = 48
#: The root finder stops when the end angle is this close to the distance, relatively; a shot that does not land
#: within LAND_TOL of it is refused.
ROOT_TOL = 1e-10
LAND_TOL = 1e-6
#: Of the bus, the voltage the terminal ramp's rate aims at where the ramp would leave the bus; and the ramp's rate
#: changes at most this many times.
RAMP_SHARE = 0.99
RAMP_TRIES = 4
#: Of the secant's rate, the one tried (a little below, so that the next try lands within the bus).
RAMP_AIM = 0.995
#: Of the bus, the ramp's voltage below which a rate that fell is raised once more (by the secant between the last
#: rate beyond the bus and the one within it).
RAMP_LOW = 0.97


class Shot(NamedTuple):
    """The move: the speeding-up phase up to the switch, the cruise if any, the braking phase and its ramp."""

    accel: Phase  # samples 0..n_acc - 1 at k h
    n_acc: int
    cruise: bool  # the speeding-up phase settled at sample n_acc - 1 and cruises until t_s
    t_s: float
    brake: Phase  # samples 0..n_brake - 1 at t_s + j h
    n_brake: int
    end: End
    v: float  # the bus [V], the policy's gain L / T_c [ohm] and the step [s] of the shot
    gain: float
    h: float
    ramp: float  # the terminal ramp's rate, of Q_RATE V / L


def _guess(md: _Model, acc: list[Array], n_acc: int, cruise: bool, d: float, guess: float,
           top: float) -> Optional[tuple[float, float, float, float, float, float, End]]:
    """A bracket from a guessed switch time and a probe one step from it towards the distance (None: none).

    (lo, f_lo, hi, f_hi, the switch time last evaluated, its miss f, its end).
    """
    if not (0.0 < guess < top):
        return None
    end, _ = _brake(md, acc, n_acc, cruise, guess, None)
    if end is None or not math.isfinite(end.angle - d):
        return None
    f_g = end.angle - d
    if abs(f_g) <= ROOT_TOL * d:
        return guess, f_g, guess, f_g, guess, f_g, end
    probe = guess + md.h if f_g < 0 else guess - md.h
    if not (0.0 < probe < top):
        return None
    end, _ = _brake(md, acc, n_acc, cruise, probe, None)
    if end is None or not math.isfinite(end.angle - d) or (end.angle - d < 0) == (f_g < 0):
        return None
    f = end.angle - d
    return (guess, f_g, probe, f, probe, f, end) if f_g < 0 else (probe, f, guess, f_g, probe, f, end)


def estimate(md: _Model, acc: list[Array], n_acc: int, cruise: bool, d: float, top: float, over: float) -> float:
    """A first switch time for the root finder (NaN: none).

    Where the braking distance from ``top`` (``over`` beyond ``d``), scaled by the square of the speed, lands on
    ``d``. From a cruise, the braking from any switch on it is the same move shifted in time: exact there.
    """
    k = n_acc - 1
    th, w = acc[0], acc[1]
    if not w[k] > 0:
        return math.nan
    if cruise:
        t = top - over / w[k]
        if t >= k * md.h:
            return t
        b = over
    else:
        b = over + d - th[k]
    c = w[k] * w[k]
    if not c > 0:  # the speed's square underflows: no estimate
        return math.nan
    c = b / c
    if not (math.isfinite(c) and c > 0):
        return math.nan
    g0 = -d
    for j in range(1, n_acc):
        g = th[j] + c * w[j] * w[j] - d
        if g >= 0:
            return (j - 1 + g0 / (g0 - g)) * md.h
        g0 = g
    return math.nan


def _land(md: _Model, acc: list[Array], n_acc: int, cruise: bool, d: float,
          guess: float = math.nan) -> Optional[tuple[float, End]]:
    """The switch time that lands the move on ``d`` and its end (None: a braking phase too long).

    ``guess``: a switch time to start from (a former shot's): where it and a probe one step from it bracket the
    distance, the root finder starts from that bracket instead of the whole speeding-up phase.
    """
    last = (n_acc - 1) * md.h
    if cruise and not acc[1][n_acc - 1] > 0:  # a cruise at no speed: the cap is 0 in floating point
        return None
    top = last + (d - acc[0][n_acc - 1]) / acc[1][n_acc - 1] if cruise else last
    near = _guess(md, acc, n_acc, cruise, d, guess, top) if math.isfinite(guess) else None
    end: Optional[End]
    est = math.nan
    if near is not None:
        lo, f_lo, hi, f_hi, t_s, f, end = near
    else:
        t_s = hi = top
        end, _ = _brake(md, acc, n_acc, cruise, hi, None)
        if end is None:
            return None
        lo, f_lo = 0.0, -d
        f_hi = f = end.angle - d
        if not (math.isfinite(f) and t_s >= 0) or f < 0:  # the bracket's top must not fall short
            return None
        est = estimate(md, acc, n_acc, cruise, d, top, f)
    side = 0
    for _ in range(ROOT):
        if abs(f) <= ROOT_TOL * d or not hi - lo > 1e-15 * hi:
            break
        if not f_hi - f_lo > 0:
            break
        t_s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if lo < est < hi:  # the first try: the estimate from the top's braking distance
            t_s = est
        est = math.nan
        end, _ = _brake(md, acc, n_acc, cruise, t_s, None)
        if end is None:
            return None
        f = end.angle - d
        if not math.isfinite(f):
            return None
        if f < 0:
            lo, f_lo = t_s, f
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = t_s, f
            if side == 1:
                f_lo *= 0.5
            side = 1
    return t_s, end


def shoot(d: float, motor: MotorParams, v: float, i_max: float, cap: float, ramp: float = 1.0,
          switch: float = math.nan) -> Optional[Shot]:
    """The move over ``d`` > 0 at bus ``v`` [V], current ``i_max`` [A] and speed cap [rad/s] (None: not found).

    ``ramp``: the terminal ramp's rate to start from, of :data:`Q_RATE` ``v / L``. Where the ramp would leave the
    bus (at its start or its end), its rate is set by the secant on the ramp's voltage towards :data:`RAMP_SHARE`
    of the bus (the first step scales it by the square of the excess) and the switch is found again, at most
    :data:`RAMP_TRIES` times; a rate that fell below :data:`RAMP_LOW` of the bus is raised once by the secant (and
    kept where the raise leaves the bus); the shot keeps the rate (the planner starts its next shot from it).
    ``switch``: a switch time to start the root finder from (the planner's former shot's; each landing starts from
    the last).
    """
    h = motor.L * i_max / v / STEPS
    for _ in range(DOUBLINGS + 1):
        md = _Model(motor, v, i_max, cap, h)
        if not md.valid:
            return None
        md.end_rate = ramp * md.rate
        up = _speed_up(md, d)
        landed = None
        if up is not None:
            acc, n_acc, cruise = up
            prev, e_prev, guess, excess = math.nan, math.nan, switch, math.nan
            kept: Optional[tuple[float, float]] = None  # a rate and switch within the bus, before a raise
            for _ in range(RAMP_TRIES + 1):
                landed = _land(md, acc, n_acc, cruise, d, guess)
                if landed is None:
                    break
                guess = landed[0]
                excess = ramp_voltage(md, landed[1])
                # (no ramp voltage, excess 0, leaves nothing to aim the rate from: kept as it is)
                if excess <= 1.0 and (excess >= RAMP_LOW or not e_prev > 1.0 or kept is not None or excess == 0.0):
                    break
                rate = md.end_rate
                if excess <= 1.0:  # well within the bus after a fall: raised once, between the two
                    kept = (rate, guess)
                if math.isfinite(e_prev) and excess != e_prev:
                    nxt = rate + (RAMP_SHARE - excess) * (rate - prev) / (excess - e_prev)
                    nxt = min(max(nxt, 0.25 * rate), max(rate, prev))
                else:
                    nxt = rate * (RAMP_SHARE / excess) ** 2
                prev, e_prev, md.end_rate = rate, excess, RAMP_AIM * nxt
            if kept is not None and (landed is None or not excess <= 1.0):
                md.end_rate = kept[0]  # the raise left the bus: back to the rate within it
                landed = _land(md, acc, n_acc, cruise, d, kept[1])
        if landed is None:
            h *= 2.0
            continue
        t_s = landed[0]
        out = _empty(MAX_STEPS)
        end, n_b = _brake(md, acc, n_acc, cruise, t_s, out)
        if end is None:
            h *= 2.0
            continue
        if not abs(end.angle - d) <= LAND_TOL * d:  # the root finder stopped short of the distance
            return None
        cruising = cruise and t_s >= (n_acc - 1) * h
        k_s = n_acc if cruising else _step_index(t_s, h, n_acc) + 1
        return Shot(Phase(*acc), k_s, cruising, t_s, Phase(*out), n_b, end, v, md.lk, h, md.end_rate / md.rate)
    return None
