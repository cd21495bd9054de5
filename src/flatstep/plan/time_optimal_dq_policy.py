r"""The field-weakening shot's model under the bus-saturated current-steering policy, and one RK4 step of it.

Part of :mod:`flatstep.plan.time_optimal_dq_shoot`. The d-q model

.. math::
    L\dot i_d = v_d - Ri_d + N_r\omega Li_q,\quad L\dot i_q = v_q - Ri_q - N_r\omega Li_d - K_m\omega,\quad
    J\dot\omega = K_m i_q - B\omega,\quad \dot\theta = \omega

is integrated by RK4 on steps :math:`h` (:meth:`_Model.step`) under the voltage that brings the current to its
target with the time constant :math:`T_c` (:data:`LAG` rise times),
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
that the cruise settles). Braking ends once the braking current meets the terminal ramp's switching curve
(:meth:`_Model.curve`).

The reference of csrc/time_optimal_dq_policy.c, operation for operation.
"""
from __future__ import annotations

import math

from ..model.motor import MotorParams
from .time_optimal_dq_envelope import best_currents, top_speed

State = tuple[float, float, float, float]  # theta, omega, i_d, i_q
#: The current's time constant under the policy, in current rise times (the fit follows it between knots).
LAG = 0.5
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
#: Of V / L, the torque current's rate the approach to the speed cap and the terminal ramp count on (the ramp's
#: falls where it would leave the bus).
Q_RATE = 0.97
#: Of the top speed where no torque is left, the cruise speed when that speed is below the cap.
TOP_SHARE = 0.999


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
