r"""The field-weakening move by shooting: the nominal d-q model driven at the bus's full rate, the switch found.

The first stage of :mod:`flatstep.plan.time_optimal_dq`. The d-q model

.. math::
    L\dot i_d = v_d - Ri_d + N_r\omega Li_q,\quad L\dot i_q = v_q - Ri_q - N_r\omega Li_d - K_m\omega,\quad
    J\dot\omega = K_m i_q - B\omega,\quad \dot\theta = \omega

is integrated by RK4 on steps :math:`h` of :data:`STEPS` per current rise time :math:`L i_{max}/V`, under the
voltage that brings the current to its target with the time constant :math:`T_c` (:data:`LAG` rise times),
:math:`v = (R + jN_r\omega L)i + jK_m\omega + L(i^* - i)/T_c`, scaled onto :math:`|v| = V` where it is beyond
the bus (as a drive's current loop saturates); the target moves linearly within each step (the currents' rates
stay continuous, so that a cubic and a degree-7 fit follow them). The target is the envelope's best current
(:func:`~flatstep.plan.time_optimal_dq_envelope.best_currents`) at the speed each step ends at: the top of the two
discs while speeding up, the bottom while braking. Where the bus limits the whole move (the resistive share
:math:`\rho = R i_{max}/V` large), the currents go beyond the steady envelope on the inductance's transient, as the
optimum's do (the collocation yardstick, :mod:`flatstep.bench.collocation`): speeding up, the d target is the
envelope's at the speed :data:`AHEAD` :math:`T_c` ahead (the field weakened before the speed needs it; in full
for :math:`\rho` from :data:`RHO_FULL`, in proportion below, and only where the reactance at the cruise
:math:`N_rWL` is several times R: :data:`X_END`, :data:`X_FULL`), its moves slew-limited to :data:`D_SLEW` times
the bus's current rate (a d target that jumps within a step bends the d current's rate there, and the fitted
table crosses the bus between knots); braking, the
envelope's bus disc is scaled by up to :math:`1 +` :data:`BRAKE_REACH` (from :math:`\rho` = :data:`REACH_FROM`
on), so that the voltage stays on the bus, and pulled in where the current passes the current limit
(:data:`PULL_FROM`). Speeding up, the torque current is held to
:math:`i_q^* \le B W/K_m + g(W - \omega)` so that the speed meets the cap :math:`W` at the current's rate
:data:`Q_RATE` :math:`V/L` (:math:`g` the square root of the time-optimal approach, linear within a small band so
that the cruise settles).

At the switch the target passes linearly from the speeding-up one to the braking one over :data:`SWITCH` steps
(the currents' rates stay continuous, and slow enough for the fit). Braking ends in a terminal ramp: once the
braking current meets the switching curve :math:`-i_q = \sqrt{2 Q_{RATE}(V/L)(J/K_m)\omega}` (within the step: the
fraction where the interpolated distance to the curve is 0, integrated from the step's start), a short bridge
takes the jerk and the d current's rate linearly to the ramp's (so that the voltage passes between the two sides',
within the bus), then the acceleration falls linearly to 0 over :math:`\tau = -2\omega/\dot\omega` and the speed
with it, to rest, and :math:`i_d` to 0 as a quadratic whose start rate is the share :math:`c` of the linear one
(:func:`~flatstep.plan.time_optimal_dq_ramp.ramp_share`: 1 unless the start's voltage is above the end's; then the
two are balanced, so that a braking current beyond the envelope leaves its d current later; the ramp's part is
:mod:`flatstep.plan.time_optimal_dq_ramp`). Where the ramp would leave the bus (at its start or its
end), its rate falls, and a rate that fell far within it is raised once (:func:`shoot`).

The speeding-up phase is integrated once, until it settles at the cap (a cruise: the state then constant but the
angle) or passes the distance. The braking phase starts from it at the switch time :math:`t_s`; its end angle rises
with :math:`t_s`, and the Illinois variant of regula falsi finds the :math:`t_s` that lands on the distance in at
most :data:`ROOT` braking phases; its first try is :func:`estimate` (the braking distance from the bracket's top,
scaled by the square of the speed; exact on a cruise). A phase that needs more than :data:`MAX_STEPS` steps
doubles the step (at most :data:`DOUBLINGS` times).

This module is the reference of csrc/time_optimal_dq_shoot.c, operation for operation; its loops run over time
steps in Python (the default engine is the C one).
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from .time_optimal_dq_envelope import best_currents, top_speed
from .time_optimal_dq_ramp import End, State, ramp_voltage, terminal_ramp

Array = NDArray[np.float64]
#: Integration steps per current rise time L i_max / V (csrc/time_optimal_dq.h ``TOD_STEPS``).
STEPS = 10
#: Steps of one phase, at most (``TOD_MAX_STEPS``); more double the step.
MAX_STEPS = 512
#: The current's time constant under the policy, in current rise times (the fit follows it between knots).
LAG = 0.5
#: Steps over which the target passes from the speeding-up one to the braking one at the switch.
SWITCH = 4
#: Speeding up, the d target is the envelope's at the speed the acceleration adds over this many time constants
#: T_c ahead, where that weakens more (the d current takes about that long to get there), in full where the
#: resistive share of the bus :math:`\rho = R i_{max}/V` is at least :data:`RHO_FULL` (less in proportion below),
#: and where the reactance at the cruise, :math:`N_r W L`, is at least :data:`X_FULL` times R; none where it is
#: below :data:`X_END` times R, linear between. Each ampere of d current takes :math:`N_r\omega L` off the back
#: EMF's voltage and costs R of its own: where the reactance at the move's speeds is not well above R the d
#: current's resistive drop eats the voltage it saves (the Sanyo 103H5208, :math:`N_r W L/R` 1.1 and 1.9, is
#: 0.1-1.9 % slower with it; the motors from 0.6 to 20 gain, the JK42HS34 and the 14HS13 at 12 V among them,
#: whose resistive share 0.69 and 0.78 a rule on :math:`\rho` alone took the look-ahead from).
AHEAD = 3.0
RHO_FULL = 0.4
X_END = 3.0
X_FULL = 5.0
#: Speeding up, the d target moves by at most this many times the bus's current rate V / L (a target that jumps
#: within a step turns the d current's rate sharply there, and the fitted table overshoots the bus between knots:
#: the QSH5718-51 at 12 V, 1.36 A in one step, 3.4 times V / L h; at 1 V / L h the NEMA 17 preset at 12 V, 0.3 rad,
#: was 0.4 % slower).
D_SLEW = 2.0
#: Braking, where the current is beyond this share of i_max, its target is scaled by :math:`q^2`,
#: :math:`q = (s\,i_{max}/|i|)^2`: the bus-saturated voltage, scaled back along its own direction, bends the current
#: out of the current disc while the target moves along the disc's edge (the QSH5718-51 at 24 V: 1.4 % beyond the
#: shot's i_max, and its fitted table 1 % beyond the limit: a second shot).
PULL_FROM = 0.995
#: Braking, the target is the bottom of the envelope with its bus disc scaled by
#: :math:`1 + \min(\max(2(\rho - \rho_0), 0), r)`, :math:`\rho_0` = :data:`REACH_FROM`, r = :data:`BRAKE_REACH`:
#: beyond the steady envelope, so that the voltage stays on the bus while the current's transient carries it there,
#: where the bus binds the whole move (the resistance takes much of it); the steady envelope where it does not.
BRAKE_REACH = 0.5
REACH_FROM = 0.2
#: Doublings of the step, at most (``TOD_DOUBLINGS``).
DOUBLINGS = 8
#: Braking phases tried by the root finder on the switch time, at most (``TOD_ROOT``).
ROOT = 48
#: The root finder stops when the end angle is this close to the distance, relatively; a shot that does not land
#: within LAND_TOL of it is refused.
ROOT_TOL = 1e-10
LAND_TOL = 1e-6
#: Of V / L, the torque current's rate the approach to the speed cap and the terminal ramp count on (the ramp's
#: falls where it would leave the bus).
Q_RATE = 0.97
#: Of the bus, the voltage the terminal ramp's rate aims at where the ramp would leave the bus; and the ramp's rate
#: changes at most this many times.
RAMP_SHARE = 0.99
RAMP_TRIES = 4
#: Of the secant's rate, the one tried (a little below, so that the next try lands within the bus).
RAMP_AIM = 0.995
#: Of the bus, the ramp's voltage below which a rate that fell is raised once more (by the secant between the last
#: rate beyond the bus and the one within it).
RAMP_LOW = 0.97
#: Of the top speed where no torque is left, the cruise speed when that speed is below the cap.
TOP_SHARE = 0.999
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


class _Model:
    """The motor's constants, the bus, the current and the speed cap of one shooting run."""

    def __init__(self, m: MotorParams, v: float, i_max: float, cap: float, h: float) -> None:
        self.R, self.L, self.Km, self.J, self.B, self.Nr = m.R, m.L, m.Km, m.J, m.B, float(m.Nr)
        self.m, self.v, self.i_max, self.h = m, v, i_max, h
        self.inv_l, self.inv_j = 1.0 / m.L, 1.0 / m.J
        self.lk = self.tc = self.rho = self.rate = self.end_rate = self.cap = self.hold = self.band = math.nan
        self.valid = self._constants(cap)

    def _constants(self, cap: float) -> bool:
        """Whether the run's constants are finite and positive (every divisor checked before it divides)."""
        m, v, i_max, h = self.m, self.v, self.i_max, self.h
        den = LAG * i_max
        if not (den > 0 and math.isfinite(h) and h > 0):
            return False
        self.lk = v / den  # the current loop's gain L / T_c
        if not (math.isfinite(self.lk) and self.lk > 0):
            return False
        self.tc = m.L / self.lk
        self.rho = m.R * i_max / v  # the resistive share of the bus
        self.rate = Q_RATE * v / m.L * (m.J / m.Km)  # the cap's approach law's current rate times J / Km
        self.end_rate = self.rate  # the terminal ramp's (lowered where the ramp would leave the bus)
        top = top_speed(m, v, i_max, cap)
        self.cap = cap if top >= cap else TOP_SHARE * top
        self.hold = m.B * self.cap / m.Km
        self.reactance = m.Nr * self.cap * m.L / m.R if m.R > 0 else math.inf  # N_r W L / R at the cap W
        den = 4.0 * h * m.Km
        if not (math.isfinite(self.rate) and self.rate > 0 and math.isfinite(self.cap) and self.cap > 0 and den > 0):
            return False
        k = m.J / den  # the linear band's slope: the speed error falls by a quarter per step
        if not (k * k > 0 and math.isfinite(k * k)):
            return False
        self.band = 2.0 * self.rate / (k * k)
        return math.isfinite(self.band) and self.band > 0

    def policy(self, i_d: float, i_q: float, w: float, t_d: float, t_q: float) -> tuple[float, float, float, float]:
        """The voltage towards the target and the steady voltage of the state: (v_d, v_q, a_d, a_q) (module doc)."""
        x = self.Nr * w * self.L
        a_d = self.R * i_d - x * i_q
        a_q = self.R * i_q + x * i_d + self.Km * w
        v_d = a_d + self.lk * (t_d - i_d)
        v_q = a_q + self.lk * (t_q - i_q)
        n2 = v_d * v_d + v_q * v_q
        if n2 > self.v * self.v:
            scale = self.v / math.sqrt(n2)
            v_d, v_q = v_d * scale, v_q * scale
        return v_d, v_q, a_d, a_q

    def deriv(self, i_d: float, i_q: float, w: float, t_d: float, t_q: float) -> tuple[float, float, float]:
        """(di_d, di_q, dw) of the model under the policy towards (t_d, t_q)."""
        v_d, v_q, a_d, a_q = self.policy(i_d, i_q, w, t_d, t_q)
        return (v_d - a_d) * self.inv_l, (v_q - a_q) * self.inv_l, (self.Km * i_q - self.B * w) * self.inv_j

    def target(self, w: float, braking: bool, lead: float = 0.0, ahead: float = 0.0) -> tuple[float, float]:
        """The target current at speed ``w`` (module docstring).

        ``lead``: the speed the current's lag adds [rad/s]; ``ahead``: the speed ahead whose d target is taken
        where it weakens more (speeding up).
        """
        reach = 1.0 + min(max(2.0 * (self.rho - REACH_FROM), 0.0), BRAKE_REACH) if braking else 1.0
        c = best_currents(min(max(w, 0.0), self.cap), self.m, reach * self.v, self.i_max)
        if math.isnan(c[1]):  # the discs do not meet (not below the top speed): no current
            c = (0.0, 0.0, 0.0, 0.0)
        if braking:
            return c[2], c[3]
        e = self.cap - w - lead
        g = math.sqrt(2.0 * self.rate * e) if e >= self.band else e * math.sqrt(2.0 * self.rate / self.band)
        t_d = c[0]
        if ahead > 0:
            c2 = best_currents(min(max(w + ahead, 0.0), self.cap), self.m, self.v, self.i_max)
            if not math.isnan(c2[1]):
                t_d = min(t_d, c2[0])
        return t_d, min(c[1], self.hold + g)

    def next_target(self, s: State, braking: bool) -> tuple[float, float]:
        """The target at the end of the step from ``s``: at the speed predicted there.

        The approach to the cap counts the speed the current's lag behind its target adds (T_c times the acceleration);
        speeding up, the d target looks :data:`AHEAD` T_c ahead.
        """
        alpha = (self.Km * s[3] - self.B * s[1]) / self.J
        share = min(self.rho / RHO_FULL, 1.0) * min(max((self.reactance - X_END) / (X_FULL - X_END), 0.0), 1.0)
        ahead = min(max((self.cap - s[1]) / self.band, 0.0), 1.0) * AHEAD * share
        t = self.target(s[1] + self.h * alpha, braking, self.tc * alpha, ahead * self.tc * max(alpha, 0.0))
        if braking:  # a current beyond PULL_FROM i_max pulls its target in (PULL_FROM)
            n2 = s[2] * s[2] + s[3] * s[3]
            r2 = (PULL_FROM * self.i_max) * (PULL_FROM * self.i_max)
            if n2 > r2:
                q = r2 / n2
                t = (t[0] * q * q, t[1] * q * q)
        return t

    def next_speed_up(self, s: State, tg: tuple[float, float]) -> tuple[float, float]:
        """The speeding-up target at the end of the step from ``s``, its d part slew-limited (:data:`D_SLEW`).

        Within :data:`D_SLEW` ``h V / L`` of ``tg``'s, the target at the step's start.
        """
        t_d, t_q = self.next_target(s, False)
        slew = D_SLEW * self.h * self.v * self.inv_l
        return min(max(t_d, tg[0] - slew), tg[0] + slew), t_q

    def step(self, s: State, t0: tuple[float, float], t1: tuple[float, float], f: float = 1.0) -> State:
        """RK4 over ``f h`` from ``s``, the target moving from ``t0`` towards ``t1`` (reached at a full step)."""
        h = f * self.h
        th, w, i_d, i_q = s
        dd, dq = t1[0] - t0[0], t1[1] - t0[1]
        d1, q1, w1 = self.deriv(i_d, i_q, w, t0[0], t0[1])
        d2, q2, w2 = self.deriv(i_d + 0.5 * h * d1, i_q + 0.5 * h * q1, w + 0.5 * h * w1, t0[0] + 0.5 * f * dd,
                                t0[1] + 0.5 * f * dq)
        d3, q3, w3 = self.deriv(i_d + 0.5 * h * d2, i_q + 0.5 * h * q2, w + 0.5 * h * w2, t0[0] + 0.5 * f * dd,
                                t0[1] + 0.5 * f * dq)
        d4, q4, w4 = self.deriv(i_d + h * d3, i_q + h * q3, w + h * w3, t0[0] + f * dd, t0[1] + f * dq)
        return (th + h / 6.0 * (w + 2.0 * (w + 0.5 * h * w1) + 2.0 * (w + 0.5 * h * w2) + (w + h * w3)),
                w + h / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4),
                i_d + h / 6.0 * (d1 + 2.0 * d2 + 2.0 * d3 + d4),
                i_q + h / 6.0 * (q1 + 2.0 * q2 + 2.0 * q3 + q4))

    def curve(self, s: State) -> float:
        """The braking current beyond the terminal ramp's switching curve [A] (>= 0: ramp now)."""
        return -s[3] - math.sqrt(2.0 * self.end_rate * max(s[1], 0.0))


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
                if excess <= 1.0 and (excess >= RAMP_LOW or not e_prev > 1.0 or kept is not None):
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
