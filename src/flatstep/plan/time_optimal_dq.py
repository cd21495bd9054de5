r"""The fastest rest-to-rest move in the d-q flat outputs :math:`(\theta, i_d)`, with field weakening where it pays.

This module is the readable reference; csrc/time_optimal_dq.c runs the same algorithm (``engine="c"``, the
default) and the two agree on the planned durations to rounding (tests/test_time_optimal_dq.py).

**Stages.** :mod:`~flatstep.plan.time_optimal_dq_shoot` integrates the nominal d-q model under a bus-saturated
current-steering policy: speed up on the envelope's best current (:mod:`~flatstep.plan.time_optimal_dq_envelope`:
the largest torque current over the d current within the bus and ``i_max``, closed form), hold the speed cap, switch
at :math:`t_s` to the braking envelope, and end in a ramp of both currents to 0 as the speed reaches 0; the switch
time is found by a bracketing root finder so that the move lands on the distance. The currents change at the bus's
full rate, and no share of the bus is kept back for the inductance: the model is integrated within the bus.
:mod:`~flatstep.plan.time_optimal_dq_profile` fits theta (degree-7 segments through theta and its first three
derivatives) and :math:`i_d` (cubic Hermite) at knots picked from the samples, and measures the voltages of the
d-q flat inverse on the fitted table.

**The bus share.** The move is shot at :data:`SHARE` of the bus, :data:`CURRENT_PLAN` of ``i_max`` and
:data:`CAP_PLAN` of the speed cap; where the fitted table crosses a limit (the fit between knots, the held voltage's
steps), the share of that limit shrinks by the excess and the move is shot again, at most :data:`SHRINKS` times.

**Limits.** The bus :math:`|v| \le v_{use}v_{bus}` (``voltage="phase"``: the inscribed circle of each phase's
:math:`\pm v_{use}v_{bus}`, met once per electrical turn; ``"vector"``: the norm itself), :math:`|i| \le i_{max}`,
the speed cap: the least of ``limits.speed_max`` and the commutation cap :math:`N_r\omega \le 2\pi\,s_e f_c`
(:data:`ELECTRICAL_SHARE` :math:`s_e` of the control rate :math:`f_c`: at least :math:`1/s_e` control periods per
electrical turn, so that a sampled drive still commutates). The torque-angle cap and ``i_hold`` belong to the
paper's :math:`(\rho, \theta)` law and are not used: the d-q law has no singularity.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..model.motor import MotorParams
from ..validate import InputError, check_choice
from .arguments import check_angle, check_engine, check_limits, check_motor, check_t0
from .d_current import DCurrentPlan, hermite_cubic
from .limits import MotorLimits
from .piecewise import PiecewisePlan, horner_rows
from .segments import hermite_rows
from .time_optimal_dq_envelope import best_currents
from .time_optimal_dq_profile import V_MARGIN, DQTable, dq_fit, dq_margins
from .time_optimal_dq_shoot import LAND_TOL, shoot

__all__ = ["CAP_PLAN", "CURRENT_PLAN", "ELECTRICAL_SHARE", "SHARE", "SHRINKS", "DQCandidate", "DQPlan",
           "plan_dq_move", "speed_cap", "time_optimal_dq"]
#: The largest electrical frequency over the control rate (csrc/time_optimal_dq.h ``TOD_ELECTRICAL_SHARE``).
ELECTRICAL_SHARE = 0.035
#: Of v_use v_bus, the bus the move is first shot at.
SHARE = 0.98
#: Of the speed cap, the share the move is shot at.
CAP_PLAN = 0.995
#: Of i_max, the share the move is first shot at.
CURRENT_PLAN = 0.995
#: Shots after the first, at most: each shrinks the share of the limit the last fitted table crossed.
SHRINKS = 6
#: Of the excess, the extra the share shrinks by, and the power of the excess it shrinks by (a smaller share
#: lowers the fitted table's peak by less: so that the next shot lands inside). The bus's power is higher: on the
#: benchmark's seven motors the fitted table's peak voltage fell by 0.49-2.0 times the share's relative fall
#: (its excess is the fit's bend where the bus saturates within a step, which a smaller bus does not shrink), the
#: current's by 0.76-0.79.
_EXTRA = 0.002
_POWER = 1.5
_V_POWER = 2.0
VOLTAGES = ("phase", "vector")
#: Of i_max, the least floor of the plan's rho channel (DQPlan).
RHO_FLOOR = 0.1
#: The control rate [Hz] the speed cap follows when none is given.
DEFAULT_RATE = 20000.0


class DQCandidate(NamedTuple):
    """The planned table: duration [s], bus share kappa (of v_use v_bus), integration step [s], margins, table."""

    tf: float
    kappa: float
    width: float
    margins: dict[str, float]
    table: DQTable


def speed_cap(motor: MotorParams, limits: MotorLimits, control_rate: float) -> float:
    """The speed cap [rad/s]: ``limits.speed_max`` and :data:`ELECTRICAL_SHARE` of ``control_rate`` [Hz] (module)."""
    cap = ELECTRICAL_SHARE * 2.0 * math.pi * control_rate / motor.Nr
    return min(cap, limits.speed_max) if limits.speed_max else cap


def plan_dq_move(distance: float, motor: MotorParams, limits: MotorLimits, *, voltage: str = "phase",
                 control_rate: float = DEFAULT_RATE, engine: str = "python") -> DQCandidate:
    """The shortest feasible field-weakening table over ``distance`` != 0 [rad] (module docstring).

    Raises
    ------
    InputError
        An argument out of range.
    ValueError
        When the motor cannot start, or no shot's table keeps the limits.
    """
    d = abs(check_angle(distance, "distance"))
    check_motor(motor)
    check_limits(limits)
    check_choice("voltage", voltage, VOLTAGES)
    if not (isinstance(control_rate, (int, float)) and math.isfinite(control_rate) and control_rate > 0):
        raise InputError("control_rate", control_rate, f"control_rate={control_rate!r}: the drive's control rate "
                         "is a number of Hz > 0")
    if d == 0:
        raise InputError("distance", distance, "distance=0 rad: a move needs a distance; a rest is a dwell")
    check_engine(engine)
    if engine == "c":
        from .time_optimal_dq_c import plan_table

        table, margins, kappa, step = plan_table(d, motor, limits, control_rate)
        return DQCandidate(float(table.breaks[-1]), kappa, step, margins, table)
    cap = speed_cap(motor, limits, control_rate)
    v_bus = limits.v_use * limits.v_bus
    share, current, speed, ramp, switch = SHARE, CURRENT_PLAN, CAP_PLAN, 1.0, math.nan
    if not best_currents(0.0, motor, share * v_bus, current * limits.i_max)[1] > 0:
        raise ValueError(f"the motor cannot start: at rest {v_bus:g} V and {limits.i_max:g} A give no torque")
    for _ in range(SHRINKS + 1):
        v, i_max = share * v_bus, current * limits.i_max
        if not (v > 0 and i_max > 0 and cap > 0 and motor.L * i_max / v > 0):
            break
        shot = shoot(d, motor, v, i_max, speed * cap, ramp, switch)
        if shot is None:
            break
        ramp, switch = shot.ramp, shot.t_s
        table = dq_fit(shot, d, motor, v, i_max)
        if not abs(float(np.sum(table.theta[-1])) - d) <= LAND_TOL * (1.0 + d):  # segments so long that the fit
            break  # loses the angle
        mg = dq_margins(table, motor, v_bus, limits.i_max, cap)
        if not math.isfinite(mg["worst"]):
            break
        if mg["worst"] <= 0:
            return DQCandidate(float(table.breaks[-1]), share, shot.h, mg, table)
        if mg["voltage"] / V_MARGIN - 1.0 > 0:
            share /= (mg["voltage"] / V_MARGIN + _EXTRA) ** _V_POWER
        if mg["current"] > 1.0:
            current /= (mg["current"] + _EXTRA) ** _POWER
        if mg["speed"] > 1.0:
            speed /= (mg["speed"] + _EXTRA) ** _POWER
    raise ValueError(f"no feasible field-weakening plan of {distance} rad within {limits}: raise v_bus or i_max")


class DQPlan(NamedTuple):
    r"""A field-weakening move: the plan of theta (the plan protocol's object) and the planned d current.

    The d-q law tracks both: ``DQSMC(motor, plan, gains, d_current=d_current)``. The plan's rho channel holds
    a bound on the planned current magnitude :math:`\sqrt{i_q^2 + i_d^2 + f^2}`, :math:`f` the larger of
    ``i_hold`` and :data:`RHO_FLOOR` ``i_max`` (so that the paper's flat maps stay defined and the move starts
    from a holding current; the d-q law does not read it).
    """

    plan: PiecewisePlan
    d_current: DCurrentPlan
    found: DQCandidate


def _rho_rows(tb: DQTable, motor: MotorParams, floor: float, samples: int = 16) -> np.ndarray:
    """Rows of the plan's rho channel: at each knot the largest hypot(i_q, i_d, floor) over its two segments.

    Each segment then rises or falls monotonically between its knots (its three derivatives are 0 there), so the
    channel stays above the planned current magnitude sampled at ``samples`` points per segment.
    """
    m = motor
    hs = np.diff(tb.breaks)
    seg = np.repeat(np.arange(hs.size), samples)
    tau = np.tile(np.arange(samples) / (samples - 1.0), hs.size)
    w, acc = (horner_rows(tb.theta, seg, tau, k) / hs[seg] ** k for k in (1, 2))
    i_d, _ = hermite_cubic(tb.breaks[seg] + tau * hs[seg], tb.breaks, tb.i_d, tb.di_d)
    i_q = (m.J * acc + m.B * w) / m.Km
    peak = np.max(np.sqrt(i_q * i_q + i_d * i_d + floor * floor).reshape(hs.size, samples), axis=1)
    rho = np.maximum(np.append(peak, peak[-1]), np.insert(peak, 0, peak[0]))
    state = np.column_stack([rho, 0 * rho, 0 * rho, 0 * rho])
    return hermite_rows(state[:-1], state[1:], hs)


def time_optimal_dq(distance: float, motor: MotorParams, limits: MotorLimits, *, theta1: float = 0.0,
                    t0: float = 0.0, voltage: str = "phase", control_rate: float = DEFAULT_RATE,
                    engine: str = "c") -> DQPlan:
    """The shortest feasible field-weakening move over ``distance`` [rad] from ``theta1`` at ``t0`` (module docstring).

    Raises
    ------
    InputError
        An argument out of range, before any planning.
    ValueError
        When the motor cannot start, or no shot's table keeps the limits.
    """
    d = check_angle(distance, "distance")
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    c = plan_dq_move(d, motor, limits, voltage=voltage, control_rate=control_rate, engine=engine)
    tb = c.table
    sign = 1.0 if d >= 0 else -1.0
    theta = sign * tb.theta
    theta[:, -1] += theta1
    breaks = tb.breaks + t0
    plan = PiecewisePlan(breaks, theta, _rho_rows(tb, motor, max(limits.i_hold, RHO_FLOOR * limits.i_max)))
    d_current = DCurrentPlan(t0=t0, tf=float(breaks[-1]), knot_t=tuple(breaks), knot_id=tuple(tb.i_d),
                             knot_did=tuple(tb.di_d))
    return DQPlan(plan, d_current, c)
