r"""Fair baselines for the time-optimal planner: field-oriented profiles at their best, on the same limits and drive.

:mod:`flatstep.plan.baselines` holds the trapezoid and the Ruckig S-curve to the paper's (rho, theta) law: a
holding current across the torque axis throughout, which costs them reactance voltage at speed. A field-oriented
drive carries no such current, and one that weakens the field carries a negative one. The baselines here are
those drives' own, each checked through the d-q flat maps (:func:`flatstep.model.flat_dq.dq_voltages`) against
the same electrical limits as the planner (the voltage vector's norm within ``v_use v_bus``, the current
vector's within ``i_max``) and tracked by the d-q law (:class:`~flatstep.control.dq_smc.DQFlatnessSMC`) on the
same 20 kHz drive:

* **Ruckig, i_d = 0** (:func:`best_ruckig`): the time-optimal jerk-limited profile of the ``ruckig`` package
  with the three caps searched on a grid of speed, acceleration and jerk time, then a finer grid around the best
  (feasibility is not monotone in the acceleration cap: a bisection can stop on a local edge). Every cap triple
  is ordered by its duration (known in closed form, :func:`flatstep.plan.segments.scurve_phases`) and checked
  in that order, so the first feasible one is the grid's best.
* **Trapezoid with field weakening** (:func:`best_trapezoid`): acceleration in {+a, 0, -a} and the d current
  :math:`i_d = -k_w\max(|\dot\theta| - \omega_w, 0)` of :class:`~flatstep.plan.d_current.DCurrentPlan`, with
  :math:`k_w` set so that at the cruise speed :math:`v` the d current is the steady one that minimises the
  voltage, :math:`i_d = -N_rLK_m v^2/(R^2 + (N_r v L)^2)` (the back EMF cancelled as far as it pays), times a
  searched factor, within the current. Its acceleration steps need infinite :math:`L\,di_q/dt`: its limits are
  checked inside the segments, which favours it; the drive shows what that costs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..model.flat_dq import dq_voltages
from ..model.motor import MotorParams
from ..plan.arguments import check_angle, check_limits, check_motor
from ..plan.baselines import ruckig_duration, trapezoid_rows
from ..plan.d_current import DCurrentPlan
from ..plan.limits import MotorLimits
from ..plan.piecewise import NCOEF, PiecewisePlan
from ..plan.segments import scurve_phases, scurve_rows
from ..validate import InputError

Array = NDArray[np.float64]
_SAMPLES = 12  # samples per phase of a profile's check, both ends included (one-sided at the steps)


@dataclass(frozen=True)
class Baseline:
    """A baseline at its best: its duration [s], caps, d current, worst use of the limits and its plan.

    ``margins``: ``voltage`` (peak voltage norm over ``v_use v_bus``) and ``current`` (peak current norm over
    ``i_max``), both at most 1; ``speed_peak`` [rad/s], ``i_d_min`` [A].
    """

    kind: str
    duration: float
    caps: dict[str, float]
    d_current: DCurrentPlan
    margins: dict[str, float]
    plan: PiecewisePlan


def _margins(motor: MotorParams, limits: MotorLimits, omega: Array, acc: Array, jerk: Array,
             i_d: Array, di_d: Array) -> dict[str, float]:
    """The worst use of the bus and the current along sampled (omega, theta'', theta''', i_d, i_d')."""
    m = motor
    i_q = (m.J * acc + m.B * omega) / m.Km
    v_d, v_q = dq_voltages(m, i_d, i_q, omega, acc, di_d, jerk)
    return dict(voltage=float(np.max(np.hypot(v_d, v_q))) / (limits.v_use * limits.v_bus),
                current=float(np.max(np.hypot(i_d, i_q))) / limits.i_max,
                speed_peak=float(np.max(np.abs(omega))), i_d_min=float(np.min(i_d)))


def _phase_samples(durations: Array, jerks: Array) -> tuple[Array, Array, Array]:
    """Speed, acceleration and jerk at :data:`_SAMPLES` points of each constant-jerk phase (both ends)."""
    tau = np.linspace(0.0, 1.0, _SAMPLES)
    v0 = np.concatenate([[0.0], np.cumsum(np.cumsum(jerks * durations) * durations
                                          - 0.5 * jerks * durations**2)])[:-1]
    a0 = np.concatenate([[0.0], np.cumsum(jerks * durations)])[:-1]
    t = durations[:, None] * tau[None, :]
    acc = a0[:, None] + jerks[:, None] * t
    omega = v0[:, None] + a0[:, None] * t + 0.5 * jerks[:, None] * t**2
    return omega.ravel(), acc.ravel(), np.repeat(jerks, _SAMPLES)


def ruckig_margins(distance: float, motor: MotorParams, limits: MotorLimits, v_max: float, a_max: float,
                   j_max: float) -> tuple[float, dict[str, float]]:
    """The S-curve's duration [s] under the caps and its worst use of the limits with ``i_d = 0``."""
    durations, jerks = scurve_phases(abs(distance), v_max, a_max, j_max)
    omega, acc, jerk = _phase_samples(durations, jerks)
    zero = np.zeros_like(omega)
    return float(durations.sum()), _margins(motor, limits, omega, acc, jerk, zero, zero)


def _trapezoid_phases(distance: float, v_max: float, a_max: float) -> tuple[Array, Array]:
    """Durations and accelerations of the trapezoid (or triangle) over ``distance`` > 0."""
    ta = v_max / a_max
    if a_max * ta * ta >= distance:
        ta, cruise = math.sqrt(distance / a_max), 0.0
    else:
        cruise = (distance - a_max * ta * ta) / v_max
    return np.array([ta, cruise, ta]), np.array([a_max, 0.0, -a_max])


def weakening_current(omega: float, motor: MotorParams) -> float:
    r"""The steady d current [A] that minimises the voltage at speed ``omega`` with no torque current.

    .. math:: i_d = -\frac{N_rLK_m\omega^2}{R^2 + (N_r\omega L)^2}

    (:math:`\partial|v|^2/\partial i_d = 0` with :math:`v_d = Ri_d`, :math:`v_q = N_r\omega Li_d + K_m\omega`).
    """
    e = motor.Nr * omega * motor.L
    return -e * motor.Km * omega / (motor.R**2 + e * e)


def trapezoid_margins(distance: float, motor: MotorParams, limits: MotorLimits, v_max: float, a_max: float,
                      d_current: DCurrentPlan) -> tuple[float, dict[str, float]]:
    """The trapezoid's duration [s] and its worst use of the limits with the d current ``d_current``.

    Sampled inside its three phases (the acceleration's steps at the ends of each counted from inside).
    """
    durations, accs = _trapezoid_phases(abs(distance), v_max, a_max)
    tau = np.linspace(0.0, 1.0, _SAMPLES)
    v0 = np.concatenate([[0.0], np.cumsum(accs * durations)])[:-1]
    omega = (v0[:, None] + accs[:, None] * durations[:, None] * tau[None, :]).ravel()
    acc = np.repeat(accs, _SAMPLES)
    i_d, di_d = d_current.flag(np.zeros_like(omega), omega, acc)
    return float(durations.sum()), _margins(motor, limits, omega, acc, np.zeros_like(omega), i_d, di_d)


def dq_plan(rows: Array, durations: Array, distance: float, limits: MotorLimits) -> PiecewisePlan:
    """A theta table (from 0, positive) as a plan over ``distance`` for the d-q law.

    The d-q law does not read the plan's rho; it is held at ``2 i_max``, above any torque current the limits
    allow, so that the paper's flat maps (which a run's reference columns use) are defined along the plan.
    """
    theta = (1.0 if distance >= 0 else -1.0) * rows
    rho = np.zeros((rows.shape[0], NCOEF))
    rho[:, -1] = 2.0 * limits.i_max
    return PiecewisePlan(np.concatenate([[0.0], np.cumsum(durations)]), theta, rho)


def _first_feasible(candidates: list[tuple[float, Any]], check: Any) -> Optional[tuple[float, Any, Any]]:
    """The shortest candidate ``(duration, caps)`` whose ``check(caps)`` returns margins within the limits."""
    for duration, caps in sorted(candidates, key=lambda c: c[0]):
        out = check(caps)
        if out is not None:
            return duration, caps, out
    return None


def _grid(lo: float, hi: float, n: int) -> Array:
    """``n`` points from ``lo`` to ``hi``, geometric."""
    return np.geomspace(lo, hi, n)


def _check_move(distance: Any, motor: Any, limits: Any) -> float:
    """``|distance|``, or an InputError for a zero or invalid one (motor and limits checked too)."""
    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    check_motor(motor)
    check_limits(limits)
    return abs(d)


def best_ruckig(distance: float, motor: MotorParams, limits: MotorLimits, *, n: int = 16) -> Baseline:
    """The fastest Ruckig profile with ``i_d = 0`` within the limits: its caps on a 3-D grid, then a finer one.

    The grid: ``n`` speed caps up to 1.2 times the steady top speed :math:`v_{use}v_{bus}/K_m` (or up to the
    limits' ``speed_max`` where that is less), ``n`` acceleration caps up to :math:`K_m i_{max}/J`, ``n`` jerk
    times :math:`a/j` from 0.05 to 10 L/R, all geometric; then ``n`` of each across one step either side of the
    best. Ruckig's own duration for the caps found is checked against the closed form.
    """
    d = _check_move(distance, motor, limits)
    m = motor
    w_top = 1.2 * limits.v_use * limits.v_bus / m.Km
    if limits.speed_max is not None:
        w_top = min(w_top, limits.speed_max)
    a_top = m.Km * limits.i_max / m.J
    tau = m.L / m.R

    def check(caps: tuple[float, float, float]) -> Optional[dict[str, float]]:
        _, out = ruckig_margins(d, m, limits, *caps)
        return out if out["voltage"] <= 1.0 and out["current"] <= 1.0 else None

    def search(vs: Array, accs: Array, tjs: Array) -> Optional[tuple[float, Any, Any]]:
        cands = []
        for v in vs:
            for a in accs:
                for tj in tjs:
                    dur, _ = scurve_phases(d, float(v), float(a), float(a / tj))
                    cands.append((float(dur.sum()), (float(v), float(a), float(a / tj))))
        return _first_feasible(cands, check)

    vs, accs, tjs = _grid(0.05 * w_top, w_top, n), _grid(0.02 * a_top, a_top, n), _grid(0.05 * tau, 10 * tau, n)
    found = search(vs, accs, tjs)
    if found is None:
        raise ValueError(f"no Ruckig profile over {distance} rad keeps the limits {limits} with i_d = 0")
    v, a, j = found[1]
    ratio_v, ratio_a, ratio_t = (vs[1] / vs[0], accs[1] / accs[0], tjs[1] / tjs[0])
    fine = search(_grid(v / ratio_v, min(v * ratio_v, w_top), n), _grid(a / ratio_a, min(a * ratio_a, a_top), n),
                  _grid(a / j / ratio_t, a / j * ratio_t, n))
    duration, (v, a, j), margins = fine if fine is not None and fine[0] < found[0] else found
    own = ruckig_duration(d, v, a, j)
    if abs(own - duration) > 1e-9 * max(1.0, duration):
        raise ValueError(f"ruckig's duration {own} s differs from the S-curve's {duration} s for caps {(v, a, j)}")
    plan = dq_plan(*scurve_rows(0.0, d, v, a, j), distance, limits)
    return Baseline("ruckig", duration, dict(v_max=v, a_max=a, j_max=j), DCurrentPlan(0.0, 0.0, 0.0, plan.tf),
                    margins, plan)


def best_trapezoid(distance: float, motor: MotorParams, limits: MotorLimits, *, n: int = 24) -> Baseline:
    r"""The fastest trapezoid with field weakening within the limits (module docstring): its caps searched.

    ``n`` speed caps from 0.05 to 8 times :math:`v_{use}v_{bus}/K_m` and ``n`` acceleration caps up to
    :math:`K_m i_{max}/J` (geometric); for each, the weakening from :math:`\omega_w` in {0, 0.25, 0.5, 0.75}
    of the cruise speed and the factor in {0.5, 0.75, 1, 1.25} on the voltage-minimising d current there
    (within 0.98 ``i_max``), or none; then ``n`` of each cap across one step either side of the best.
    """
    d = _check_move(distance, motor, limits)
    m = motor
    w_ref = limits.v_use * limits.v_bus / m.Km
    a_top = m.Km * limits.i_max / m.J
    if limits.speed_max is not None:
        w_ref = min(w_ref, limits.speed_max / 8.0)

    def weakenings(v_peak: float) -> list[DCurrentPlan]:
        out = [DCurrentPlan(0.0, 0.0, 0.0, 1.0)]
        target = max(weakening_current(v_peak, m), -0.98 * limits.i_max)
        for start in (0.0, 0.25, 0.5, 0.75):
            for factor in (0.5, 0.75, 1.0, 1.25):
                k = -factor * target / (v_peak * (1.0 - start))
                if k > 0:
                    out.append(DCurrentPlan(0.0, 0.0, 0.0, 1.0, weakening=k, weakening_speed=start * v_peak))
        return out

    def check(caps: tuple[float, float]) -> Optional[tuple[dict[str, float], DCurrentPlan]]:
        v, a = caps
        v_peak = min(v, math.sqrt(d * a))
        for dc in weakenings(v_peak):
            _, out = trapezoid_margins(d, m, limits, v, a, dc)
            if out["voltage"] <= 1.0 and out["current"] <= 1.0:
                return out, dc
        return None

    def search(vs: Array, accs: Array) -> Optional[tuple[float, Any, Any]]:
        cands = []
        for v in vs:
            for a in accs:
                v_eff = min(float(v), math.sqrt(d * float(a)))  # a triangle: a higher cap is the same move
                cands.append((float(_trapezoid_phases(d, v_eff, float(a))[0].sum()), (v_eff, float(a))))
        return _first_feasible(list(dict((c[1], c) for c in cands).values()), check)

    top = 8.0 * w_ref if limits.speed_max is None else limits.speed_max
    vs, accs = _grid(0.05 * w_ref, top, n), _grid(0.02 * a_top, a_top, n)
    found = search(vs, accs)
    if found is None:
        raise ValueError(f"no trapezoid over {distance} rad keeps the limits {limits}")
    v, a = found[1]
    rv, ra = vs[1] / vs[0], accs[1] / accs[0]
    fine = search(_grid(v / rv, min(v * rv, top), n), _grid(a / ra, min(a * ra, a_top), n))
    duration, (v, a), (margins, dc) = fine if fine is not None and fine[0] < found[0] else found
    plan = dq_plan(*trapezoid_rows(d, v, a), distance, limits)
    d_current = DCurrentPlan(0.0, 0.0, 0.0, plan.tf, weakening=dc.weakening, weakening_speed=dc.weakening_speed)
    return Baseline("trapezoid", duration, dict(v_max=v, a_max=a, weakening=dc.weakening,
                                                weakening_speed=dc.weakening_speed), d_current, margins, plan)
