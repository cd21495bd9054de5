r"""The fastest rest-to-rest move the motor and its bus can make: a speed-dependent envelope, smoothed and checked.

**Envelope.** At speed :math:`\omega`, with the current :math:`i_q` along the torque axis and the planned
:math:`i_d` across it (:meth:`~flatstep.plan.limits.MotorLimits.across`: the holding current at rest, less at
speed, never so little that the torque angle passes its cap), the steady phase voltage (:math:`di/dt = 0`) is

.. math::
    v_d = R i_d - N_r\omega L i_q,\qquad v_q = R i_q + N_r\omega L i_d + K_m\omega,\qquad
    v_d^2 + v_q^2 \le (\gamma V_{bus})^2,

solved by bisection for the largest :math:`\pm i_q` within ``i_max``: they bound the torque current and so the
acceleration :math:`a_\pm(\omega) = (K_m i_{q\pm} - B\omega)/J` (back EMF helps braking: :math:`|a_-| > a_+`).

**Bang-bang profile.** Accelerate on :math:`a_+`, cruise at the speed cap if reached, brake on :math:`a_-`:
the distances :math:`\int \omega/a\,d\omega` and times :math:`\int d\omega/a` over a speed grid give the peak
speed where acceleration and braking distances add up to the move. With :math:`\gamma = 1` and no inductance
this is the *bang-bang bound* :func:`bang_bang_time`, the lower bound the planned times are compared with.

**Smoothing.** The speed profile is convolved twice with a box of width :math:`w` (an FIR filter, as
firmwares smooth moves): the jerk becomes continuous, theta''' exists for the law's feedforward, the duration
grows by :math:`2w`, and the end position is kept. The result becomes a table of degree-7 segments through
the profile's (theta, theta', theta'', theta''') at its knots (:func:`.segments.hermite_rows`), with
:math:`\rho^* = \sqrt{i_q^2 + i_d^2}` (:meth:`~flatstep.plan.limits.MotorLimits.rho`).

**Search.** The inductance needs voltage headroom, which the envelope's :math:`\gamma < 1` leaves. For each
smoothing width of a small set (multiples of :math:`L/R`) a bisection finds the largest :math:`\gamma` whose
table passes :func:`~flatstep.plan.limits.plan_margins` (every ratio within ``v_use`` for the bus, 1 for the
rest); the shortest feasible table wins. Its feasibility is checked on the table itself, the plan that runs.
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import Optional

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import cumulative_trapezoid

from ..model.motor import MotorParams
from ..validate import InputError, check_finite
from ..validate.limits import MAX_PLAN_SAMPLES
from .limits import MotorLimits, plan_margins
from .piecewise import PiecewisePlan
from .segments import hermite_rows

Array = NDArray[np.float64]
_GRID = 1500         # speed-grid points of the phase plane
_FINE = 3000         # time samples of the smoothed profile
_KNOTS = 96          # segments of the table
_WIDTHS = (0.0625, 0.125, 0.25, 0.5, 1.0, 2.0, 4.0)  # smoothing widths tried, in units of L / R
_BISECT = 9


def _voltage2(iq: Array, omega: Array, motor: MotorParams, limits: MotorLimits) -> Array:
    """The steady squared voltage magnitude at torque current ``iq``, speed ``omega`` and the planned i_d."""
    m, i_d = motor, limits.across(iq, omega)
    e = m.Nr * omega * m.L
    return (m.R * i_d - e * iq) ** 2 + (m.R * iq + e * i_d + m.Km * omega) ** 2


def iq_bounds(omega: Array, motor: MotorParams, limits: MotorLimits, gamma: float = 1.0) -> tuple[Array, Array]:
    """The torque currents (lowest, highest) the bus and i_max allow at speeds ``omega`` >= 0 (module docstring).

    A bisection on each side of 0, vectorized over the speeds; 0 where even no torque exceeds the bus.
    """
    omega = np.asarray(omega, dtype=float)
    cap = limits.iq_cap(omega)
    v2 = (gamma * limits.v_bus) ** 2
    bounds = []
    for sign in (-1.0, 1.0):
        ok, bad = np.zeros_like(omega), sign * cap
        full = _voltage2(bad, omega, motor, limits) <= v2
        for _ in range(32):  # a loop over halvings, vectorized over the speeds
            mid = 0.5 * (ok + bad)
            inside = _voltage2(mid, omega, motor, limits) <= v2
            ok, bad = np.where(inside, mid, ok), np.where(inside, bad, mid)
        bounds.append(np.where(full, sign * cap, ok))
    reach = _voltage2(np.zeros_like(omega), omega, motor, limits) <= v2
    return np.where(reach, bounds[0], 0.0), np.where(reach, bounds[1], 0.0)


@lru_cache(maxsize=512)
def _envelope(motor: MotorParams, limits: MotorLimits, gamma: float) -> tuple[Array, Array, Array]:
    """Speed grid up to the top speed and the accelerations a+ > 0, a- < 0 on it."""
    m = motor
    top = limits.speed_max or math.inf
    # the top speed where a+ reaches 0: below the speed where the back EMF alone takes the bus
    w_emf = gamma * limits.v_bus / m.Km
    probe = np.linspace(0.0, min(top, w_emf), _GRID)
    _, hi = iq_bounds(probe, m, limits, gamma)
    acc = (m.Km * hi - m.B * probe) / m.J
    if not acc[0] > 0:
        raise ValueError(f"the motor cannot start: at rest the bus {limits.v_bus} V (x {gamma:.3g}) and the limits "
                         f"{limits} leave no torque")
    stop = np.flatnonzero(acc <= 0)
    w_top = probe[stop[0] - 1] if stop.size else probe[-1]
    omega = np.linspace(0.0, w_top, _GRID)
    lo, hi = iq_bounds(omega, m, limits, gamma)
    a_plus = (m.Km * hi - m.B * omega) / m.J
    a_minus = (m.Km * lo - m.B * omega) / m.J
    if limits.accel_max:
        a_plus, a_minus = np.minimum(a_plus, limits.accel_max), np.maximum(a_minus, -limits.accel_max)
    a_plus[-1] = max(a_plus[-1], 1e-12 * a_plus[0])  # the top speed is reached in finite time on the grid
    for a in (omega, a_plus, a_minus):  # cached: shared by every caller
        a.flags.writeable = False
    return omega, a_plus, a_minus


def _bang_bang(distance: float, motor: MotorParams, limits: MotorLimits,
               gamma: float) -> tuple[Array, Array, Array, Array, float, float]:
    """Speed grid, acceleration and braking times along it, the peak speed and the cruise time."""
    omega, a_plus, a_minus = _envelope(motor, limits, gamma)
    t_acc = cumulative_trapezoid(1.0 / a_plus, omega, initial=0.0)
    t_dec = cumulative_trapezoid(1.0 / -a_minus, omega, initial=0.0)
    d_both = cumulative_trapezoid(omega / a_plus + omega / -a_minus, omega, initial=0.0)
    if distance >= d_both[-1]:
        return omega, t_acc, t_dec, d_both, omega[-1], (distance - d_both[-1]) / omega[-1]
    return omega, t_acc, t_dec, d_both, float(np.interp(distance, d_both, omega)), 0.0


def bang_bang_time(distance: float, motor: MotorParams, limits: MotorLimits) -> float:
    """The lower bound: the bang-bang move on the full bus ignoring inductance and jerk (module docstring)."""
    d = abs(check_finite("distance", distance))
    omega, t_acc, t_dec, _, w_peak, cruise = _bang_bang(d, motor, limits, 1.0)
    return float(np.interp(w_peak, omega, t_acc) + cruise + np.interp(w_peak, omega, t_dec))


def _box(x: Array, n: int) -> Array:
    """``x`` convolved with a unit-area box of ``n`` samples (the output is ``n - 1`` samples longer)."""
    c = np.concatenate([[0.0], np.cumsum(np.concatenate([np.zeros(n - 1), x, np.zeros(n - 1)]))])
    return (c[n:] - c[:-n]) / n


def _timing(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float,
            width: float) -> tuple[float, float, float, float, int, int]:
    """Of the smoothed move: speed-up, cruise and braking times [s], the sample step [s], box and profile samples.

    The table :func:`smoothed_plan` builds lasts ``(n + 2 (n_box - 1) - 1) dt`` (:func:`smoothed_duration`).
    """
    d = abs(distance)
    omega, t_acc, t_dec, _, w_peak, cruise = _bang_bang(d, motor, limits, gamma)
    t1, t2 = float(np.interp(w_peak, omega, t_acc)), float(np.interp(w_peak, omega, t_dec))
    total = t1 + cruise + t2
    # fine enough for the shortest of speed-up, braking and smoothing, and for the whole move
    dt = min((total + 2 * width) / _FINE, min(t1, t2, width) / 40)
    if total / dt > MAX_PLAN_SAMPLES:
        raise InputError("distance", distance, f"the move of {distance:g} rad takes {total:.4g} s at this motor's "
                         f"speed limit, which the time-optimal planner would sample {total / dt:.3g} times (every "
                         f"{dt:.3g} s), above the limit of {MAX_PLAN_SAMPLES:.3g} (flatstep.validate.limits."
                         "MAX_PLAN_SAMPLES); split it into shorter moves with waypoints, or plan it with a spline")
    return t1, cruise, t2, dt, max(1, int(round(width / dt))), int(math.ceil(total / dt)) + 1


def smoothed_duration(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float, width: float) -> float:
    """The duration [s] of :func:`smoothed_plan`'s table, without building it (the envelope is cached)."""
    *_, dt, n_box, n = _timing(distance, motor, limits, gamma, width)
    return (n + 2 * (n_box - 1) - 1) * dt


def smoothed_plan(distance: float, motor: MotorParams, limits: MotorLimits, gamma: float, width: float, *,
                  theta1: float = 0.0, t0: float = 0.0) -> PiecewisePlan:
    """The bang-bang move on the envelope at ``gamma``, smoothed twice by a box of ``width`` [s], as a table."""
    d = abs(distance)
    t1, cruise, t2, dt, n_box, n = _timing(distance, motor, limits, gamma, width)
    omega, t_acc, t_dec, _, w_peak, _ = _bang_bang(d, motor, limits, gamma)
    total = t1 + cruise + t2
    t = np.arange(n) * dt
    speed = np.where(t <= t1, np.interp(t, t_acc, omega),
                     np.where(t < t1 + cruise, w_peak, np.interp(total - t, t_dec, omega)))
    speed[-1] = 0.0
    speed = _box(_box(speed, n_box), n_box)
    tt = np.arange(speed.size) * dt
    theta = cumulative_trapezoid(speed, tt, initial=0.0)
    scale = d / theta[-1]
    acc = np.gradient(speed, dt) * scale
    jerk = np.gradient(acc, dt)
    # knots dense where the speed changes (speed-up and braking, smoothing included), few in the cruise
    last, up, down = speed.size - 1, (t1 + 2 * width) / dt, (t1 + cruise) / dt
    edges = np.clip([0.0, up, down, last], 0, last) if cruise > 0 else np.array([0.0, last / 2, last / 2, last])
    knots = np.unique(np.concatenate([np.linspace(edges[0], edges[1], _KNOTS // 2 + 1),
                                      np.linspace(edges[1], edges[2], 5),
                                      np.linspace(edges[2], edges[3], _KNOTS // 2 + 1)]).round().astype(int))
    state = np.column_stack([theta * scale, speed * scale, acc, jerk])[knots]
    state[0, 1:] = state[-1, 1:] = 0.0
    state[-1, 0] = d
    h = np.diff(tt[knots])
    sign = 1.0 if distance >= 0 else -1.0
    rows = sign * hermite_rows(state[:-1], state[1:], h)
    rows[:, -1] += theta1
    rho_fine = limits.rho((motor.J * acc + motor.B * speed * scale) / motor.Km, speed * scale)
    # rho and rho' at the knots (the law reads rho' only); rho'' and rho''' set to 0 keep each segment monotone
    rho_state = np.column_stack([rho_fine, np.gradient(rho_fine, dt), 0 * rho_fine, 0 * rho_fine])[knots]
    rho_rows = hermite_rows(rho_state[:-1], rho_state[1:], h)
    return PiecewisePlan(t0 + np.concatenate([[0.0], np.cumsum(h)]), rows, rho_rows)


def _feasible(plan: PiecewisePlan, motor: MotorParams, limits: MotorLimits) -> bool:
    """Whether the table keeps every limit (the bus within ``v_use``)."""
    m = plan_margins(plan, motor, limits)
    # 0.2 % below v_use: the sampled check may miss the peak between its samples by about that much
    return m["voltage"] <= limits.v_use * 0.998 and max(m["current"], m["torque_angle"], m["speed"], m["acceleration"],
                                                  m["jerk"]) <= 1.0


def time_optimal(distance: float, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                 t0: float = 0.0, widths: Optional[tuple[float, ...]] = None) -> PiecewisePlan:
    """The shortest feasible smoothed envelope move over ``distance`` [rad] (module docstring).

    Raises
    ------
    ValueError
        For a zero distance, or when no smoothing width and headroom give a feasible table.
    """
    d = check_finite("distance", distance)
    if d == 0:
        raise ValueError("distance=0.0 rad: a move needs a distance; a rest is a dwell")
    tau_e = motor.L / motor.R
    best: Optional[PiecewisePlan] = None
    for w in widths or tuple(k * tau_e for k in _WIDTHS):
        # the duration falls as gamma rises: a width whose full-bus move is not shorter than the best cannot win,
        # and below a gamma whose move is not shorter, neither can any (feasibility falls as gamma rises)
        if best is not None and smoothed_duration(d, motor, limits, 1.0, w) >= best.tf:
            continue
        lo, hi = 0.0, 1.0
        found: Optional[PiecewisePlan] = None
        top = smoothed_plan(d, motor, limits, hi, w)
        if _feasible(top, motor, limits):
            found = top
        else:
            for _ in range(_BISECT):
                mid = 0.5 * (lo + hi)
                if best is not None and mid > 0.05 and smoothed_duration(d, motor, limits, mid, w) >= best.tf:
                    lo = mid  # no shorter feasible move at or below mid: search above
                    continue
                try:  # a table that cannot be built (rho of a too coarse fit below 0) is a rejected candidate
                    candidate = smoothed_plan(d, motor, limits, mid, w) if mid > 0.05 else None
                except ValueError:
                    candidate = None
                if candidate is not None and _feasible(candidate, motor, limits):
                    lo, found = mid, candidate
                else:
                    hi = mid
        if found is not None and (best is None or found.tf < best.tf):
            best = found
    if best is None:
        raise ValueError(f"no feasible plan of {d} rad within {limits}: raise v_bus or i_max, lower i_hold or i_run")
    # planned from 0 at t = 0, so that a move's plan does not depend on where and when it starts
    theta = best.theta.copy()
    theta[:, -1] += theta1
    return PiecewisePlan(best.breaks + t0, theta, best.rho)



def time_optimal_sequence(waypoints: list[tuple[float, float]], motor: MotorParams, limits: MotorLimits, *,
                          t0: float = 0.0) -> PiecewisePlan:
    """Time-optimal rest-to-rest moves through ``waypoints`` ``[(theta, dwell), ...]``, each followed by its dwell.

    The first waypoint is the start; a dwell of the first holds the start before the first move.
    """
    if len(waypoints) < 2:
        raise ValueError(f"{len(waypoints)} waypoint(s): a sequence needs at least 2")
    theta = [check_finite(f"waypoint {i} theta", w[0]) for i, w in enumerate(waypoints)]
    dwell = [check_finite(f"waypoint {i} dwell", w[1]) for i, w in enumerate(waypoints)]
    if min(dwell) < 0:
        raise ValueError(f"dwells {dwell} s must be >= 0")
    parts: list[PiecewisePlan] = []
    t = t0
    for i in range(len(theta)):
        if dwell[i] > 0:
            parts.append(PiecewisePlan.hold(theta[i], limits.i_hold, t, t + dwell[i]))
            t = parts[-1].tf
        if i + 1 < len(theta):
            if theta[i + 1] == theta[i]:
                raise ValueError(f"waypoints {i} and {i + 1} sit at {theta[i]} rad: give the rest as a dwell")
            parts.append(time_optimal(theta[i + 1] - theta[i], motor, limits, theta1=theta[i], t0=t))
            t = parts[-1].tf
    return PiecewisePlan.concatenate(parts)
