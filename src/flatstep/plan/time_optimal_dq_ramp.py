r"""The terminal ramp of a field-weakening shot: the bridge from the braking phase, the ramp to rest, its voltage.

Part of :mod:`flatstep.plan.time_optimal_dq_shoot` (the policy: :mod:`flatstep.plan.time_optimal_dq_policy`): once
the braking current meets the switching curve, a short bridge takes the jerk and the d current's rate linearly to
the ramp's (so that the voltage passes between the two sides', within the bus), then the acceleration falls
linearly to 0 over :math:`\tau = -2\omega/\dot\omega` and the speed with it, to rest, and :math:`i_d` to 0 as a
quadratic whose start rate is the share :math:`c` of the linear one (:func:`ramp_share`: 1 unless the start's
voltage is above the end's; then the two are balanced, so that a braking current beyond the envelope leaves its d
current later). The reference of csrc/time_optimal_dq_ramp.c, operation for operation.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from .time_optimal_dq_policy import State, _Model

#: Of a step, the bridge from the braking rates to the terminal ramp's.
BRIDGE = 0.05
#: Halvings of the bisection on the terminal ramp's d rate share.
SHARE_HALVINGS = 24


class End(NamedTuple):
    """The end of the braking phase, at rest.

    The bridge's start (time, state, the braking target there), its length, the ramp's start (theta, omega, i_d,
    i_q), the ramp's duration and its d share :math:`c` (:func:`ramp_share`).
    """

    t: float
    theta: float
    omega: float
    i_d: float
    i_q: float
    t_d: float
    t_q: float
    bridge: float
    theta1: float
    omega1: float
    i_d1: float
    i_q1: float
    tau: float
    d_share: float

    @property
    def angle(self) -> float:
        """The end angle: the speed falls as a parabola over the ramp, a third of its start times tau."""
        return self.theta1 + self.omega1 * self.tau / 3.0

    @property
    def t_end(self) -> float:
        """The end time [s]."""
        return self.t + self.bridge + self.tau


def terminal_ramp(md: _Model, t: float, s: State, tg: tuple[float, float]) -> End:
    r"""The bridge from ``s`` at ``t`` and the terminal ramp after it (module docstring).

    Over the bridge (:data:`BRIDGE` steps, at most half the ramp) the jerk and the d current's rate pass linearly
    from the braking policy's to the ramp's; the ramp then takes the acceleration linearly to 0 as the speed falls
    to 0 over :math:`\tau = -2\omega/\dot\omega`, and the d current to 0 as a quadratic in time, its rate
    :math:`-c\,i_{d1}/\tau` at the start and :math:`-(2 - c)\,i_{d1}/\tau` at rest (:func:`ramp_share`).
    """
    th, w, i_d, i_q = s
    a0 = (md.Km * i_q - md.B * w) / md.J
    if not (a0 < 0 and w > 0):
        return End(t, th, max(w, 0.0), i_d, i_q, tg[0], tg[1], 0.0, th, max(w, 0.0), i_d, i_q, 0.0, 1.0)
    tau0 = -2.0 * w / a0
    if not tau0 > 0:
        return End(t, th, max(w, 0.0), i_d, i_q, tg[0], tg[1], 0.0, th, max(w, 0.0), i_d, i_q, 0.0, 1.0)
    dt = min(BRIDGE * md.h, 0.5 * tau0)
    dt = (t + dt) - t  # the bridge its samples' times t, t + dt span (the C core in single precision)
    did, diq, _ = md.deriv(i_d, i_q, w, tg[0], tg[1])
    j_l = (md.Km * diq - md.B * a0) / md.J
    j_r = -a0 / tau0
    a1 = a0 + 0.5 * (j_l + j_r) * dt
    w1 = w + a0 * dt + (j_l / 3.0 + j_r / 6.0) * dt * dt
    th1 = th + w * dt + a0 * dt * dt / 2.0 + (j_l / 8.0 + j_r / 24.0) * (dt * dt * dt)
    c = ramp_share(md, w, i_d, i_q, tau0)
    i_d1 = i_d + 0.5 * (did - c * i_d / tau0) * dt
    tau = -2.0 * w1 / a1 if a1 < 0 and w1 > 0 else 0.0
    return End(t, th, w, i_d, i_q, tg[0], tg[1], dt, th1, max(w1, 0.0), i_d1, (md.J * a1 + md.B * w1) / md.Km, tau, c)


def ramp_ends(md: _Model, w: float, i_d: float, i_q: float, tau: float, c: float) -> tuple[float, float]:
    r"""The terminal ramp's voltage [V] at its start and at rest, from (``w``, ``i_d``, ``i_q``) over ``tau``.

    ``c``: the d current's rate at the start, of :math:`-i_d/\tau` (at rest: 2 - c of it).
    """
    a = (md.Km * i_q - md.B * w) / md.J
    jerk = -a / tau
    diq = (md.J * jerk + md.B * a) / md.Km
    x = md.Nr * w * md.L
    v_d = md.R * i_d - x * i_q - md.L * c * i_d / tau
    v_q = md.R * i_q + x * i_d + md.Km * w + md.L * diq
    end_d, end_q = (2.0 - c) * i_d / tau, md.J * jerk / md.Km
    return math.sqrt(v_d * v_d + v_q * v_q), md.L * math.sqrt(end_d * end_d + end_q * end_q)


def ramp_share(md: _Model, w: float, i_d: float, i_q: float, tau: float) -> float:
    """The terminal ramp's d share :math:`c` in [0, 1] (the d current's rate at the start, of its linear one).

    1 (the d current linear) unless the start's voltage is above the end's; then the share where the two are equal
    (bisection, :data:`SHARE_HALVINGS`), or 0.

    A braking current beyond the steady envelope needs most of the bus at the ramp's start: its d current then
    leaves later and faster.
    """
    s1, e1 = ramp_ends(md, w, i_d, i_q, tau, 1.0)
    if s1 <= e1:
        return 1.0
    s0, e0 = ramp_ends(md, w, i_d, i_q, tau, 0.0)
    if s0 >= e0:
        return 0.0
    lo, hi = 0.0, 1.0
    for _ in range(SHARE_HALVINGS):
        mid = 0.5 * (lo + hi)
        sm, em = ramp_ends(md, w, i_d, i_q, tau, mid)
        if sm < em:
            lo = mid
        else:
            hi = mid
    return lo


def ramp_voltage(md: _Model, e: End) -> float:
    """The largest voltage of the terminal ramp over the bus: at its start and at its end."""
    if not e.tau > 0:
        return 0.0
    start, end = ramp_ends(md, e.omega1, e.i_d1, e.i_q1, e.tau, e.d_share)
    return max(start, end) / md.v
