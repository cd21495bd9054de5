"""Bad input at the planning and interop API: refused at entry with an InputError naming the argument and the value.

A table of (function, argument, bad value, call): each row must raise :class:`flatstep.validate.InputError` (a
ValueError; never a TypeError, an AttributeError, a KeyError, a run for minutes or a plan that silently goes on)
whose message names the argument and shows the value, before any planning work.
"""
from __future__ import annotations

import math
import time
from collections import Counter
from typing import Any, Callable, Optional

import numpy as np
import pytest

from flatstep.model.motor import MotorParams
from flatstep.plan.baselines import baseline_plan, best_baseline, ruckig_duration, trapezoid_rows
from flatstep.plan.copper import copper_loss, min_copper_plan
from flatstep.plan.d_current import DCurrentPlan
from flatstep.plan.envelope import bang_bang_time
from flatstep.plan.feasibility import check_feasibility
from flatstep.plan.limits import MotorLimits
from flatstep.plan.margins import plan_margins
from flatstep.plan.loss_aware import LossAwareRho
from flatstep.plan.piecewise import PiecewisePlan
from flatstep.plan.rest_to_rest import PAPER_PLAN, point_to_point, psi
from flatstep.plan.time_optimal import smoothed_plan, time_optimal, time_optimal_sequence
from flatstep.plan.waypoints import Caps, Waypoint, plan_waypoints
from flatstep.validate import InputError
from flatstep.validate.limits import MAX_OPTIMAL_MOVES

control = pytest.importorskip("control")
from flatstep.interop import (  # noqa: E402  (after the skip: the interop needs python-control)
    DQFlag,
    PsiFamily,
    controller_nlsys,
    dq_flag_to_state,
    dq_state_to_flag,
    flatsys,
    inverse_park,
    nlsys,
    park,
)

MOTOR = MotorParams.preset("nema17")
PAPER = MotorParams.preset("paper")
LIMITS = MotorLimits(v_bus=24.0, i_max=1.0)
CAPS = Caps(100.0, 2000.0, 1e5)
TABLE = PiecewisePlan.from_rest_to_rest(PAPER_PLAN)
GOOD_LIMITS = dict(v_bus=24.0, i_max=1.0)
#: a rho of 100 (tau - c)^2 - 1e-4: below 0 only near tau = c, between the 17 points the old check sampled
C = 0.53125
DIP = [[100.0, -200.0 * C, 100.0 * C * C - 1e-4]]
#: the same with its minimum exactly 0 (in exact arithmetic): not > 0
TOUCH = [[100.0, -200.0 * C, 100.0 * C * C]]
MANY = list(range(10**6))
NOT_A_NUMBER: list[Any] = [math.nan, math.inf, "1.0", True, None, [1.0]]


class Row:
    """One bad input: the function, the argument, the value, how to call it, and how the message shows the value."""

    def __init__(self, function: str, argument: str, value: Any, call: Callable[[Any], Any],
                 shown: Optional[str] = None) -> None:
        self.function, self.argument, self.value, self.call, self.shown = function, argument, value, call, shown

    def __repr__(self) -> str:
        return f"{self.function}.{self.argument}={self.shown or repr(self.value)}"[:80]


ROWS: list[Row] = []


def bad(function: str, argument: str, call: Callable[[Any], Any], values: list[Any],
        shown: Optional[str] = None) -> None:
    """Rows of ``function``'s ``argument`` for each of ``values``."""
    ROWS.extend(Row(function, argument, v, call, shown) for v in values)


def limits_with(**kw: Any) -> MotorLimits:
    return MotorLimits(**{**GOOD_LIMITS, **kw})


# MotorLimits: every field in its documented range (flatstep.validate.ranges)
bad("MotorLimits", "v_bus", lambda v: limits_with(v_bus=v), [1e300, 1e5, 0.0, -24.0] + NOT_A_NUMBER)
bad("MotorLimits", "i_max", lambda v: limits_with(i_max=v), [1e6, 0.0, -1.0, "1", math.nan, False])
bad("MotorLimits", "i_hold", lambda v: limits_with(i_hold=v), [1.0, 0.0, -0.3, math.nan, "0.3"])
bad("MotorLimits", "i_run", lambda v: limits_with(i_run=v), [0.5, 0.0, math.nan, True])
bad("MotorLimits", "speed_corner", lambda v: limits_with(speed_corner=v), [0.0, -10.0, 1e9, math.inf])
bad("MotorLimits", "torque_angle_max", lambda v: limits_with(torque_angle_max=v), [0.0, math.pi / 2, 2.0, "1.2"])
bad("MotorLimits", "v_use", lambda v: limits_with(v_use=v), [0.0, 1.5, -0.5, math.nan, True])
bad("MotorLimits", "speed_max", lambda v: limits_with(speed_max=v), [0.0, -1.0, 1e7, "100"])
bad("MotorLimits", "accel_max", lambda v: limits_with(accel_max=v), [0.0, 1e10, math.nan])
bad("MotorLimits", "jerk_max", lambda v: limits_with(jerk_max=v), [0.0, 1e13, True])

# time_optimal
bad("time_optimal", "distance", lambda v: time_optimal(v, MOTOR, LIMITS), [0.0, 1e-9, 1e7] + NOT_A_NUMBER)
bad("time_optimal", "motor", lambda v: time_optimal(1.0, v, LIMITS), ["nema17", None, {"R": 1.0}])
bad("time_optimal", "limits", lambda v: time_optimal(1.0, MOTOR, v), [GOOD_LIMITS, None, "limits"])
bad("time_optimal", "theta1", lambda v: time_optimal(1.0, MOTOR, LIMITS, theta1=v), [1e7, math.nan, "0"])
bad("time_optimal", "t0", lambda v: time_optimal(1.0, MOTOR, LIMITS, t0=v), [-0.01, -1e-9, 1e7, math.nan, True])
bad("time_optimal", "widths", lambda v: time_optimal(1.0, MOTOR, LIMITS, widths=v),
    [(), 0.001, "0.001", (2.0,), (math.nan,), (1e-3,) * 9])
bad("time_optimal", "engine", lambda v: time_optimal(1.0, MOTOR, LIMITS, engine=v), ["fortran", None, 1])

# time_optimal_sequence
bad("time_optimal_sequence", "waypoints", lambda v: time_optimal_sequence(v, MOTOR, LIMITS),
    [None, "0 1", [(0.0, 0.0)], {0.0: 0.0}, [1.0, 2.0], [(0.0,), (1.0, 0.0)], [("0", 0.0), (1.0, 0.0)],
     [(0.0, -1.0), (1.0, 0.0)], [(0.0, 0.0), (math.nan, 0.0)], [(0.0, 0.0), (True, 0.0)]])
bad("time_optimal_sequence", "waypoints", lambda v: time_optimal_sequence(v, MOTOR, LIMITS),
    [[(0.0, 0.0), (0.0, 0.1)]], shown="at 0.0 rad")
bad("time_optimal_sequence", "waypoints", lambda v: time_optimal_sequence(v, MOTOR, LIMITS),
    [[(float(i), 0.0) for i in range(MAX_OPTIMAL_MOVES + 2)]], shown=str(MAX_OPTIMAL_MOVES + 2))
bad("time_optimal_sequence", "motor", lambda v: time_optimal_sequence([(0.0, 0.0), (1.0, 0.0)], v, LIMITS),
    ["nema17"])
bad("time_optimal_sequence", "limits", lambda v: time_optimal_sequence([(0.0, 0.0), (1.0, 0.0)], MOTOR, v),
    [GOOD_LIMITS])
bad("time_optimal_sequence", "t0", lambda v: time_optimal_sequence([(0.0, 0.0), (1.0, 0.0)], MOTOR, LIMITS, t0=v),
    [-0.5, math.nan])
bad("time_optimal_sequence", "engine",
    lambda v: time_optimal_sequence([(0.0, 0.0), (1.0, 0.0)], MOTOR, LIMITS, engine=v), ["C"])

# smoothed_plan
bad("smoothed_plan", "gamma", lambda v: smoothed_plan(1.0, MOTOR, LIMITS, v, 1e-3), [0.0, 1.5, math.nan])
bad("smoothed_plan", "width", lambda v: smoothed_plan(1.0, MOTOR, LIMITS, 0.5, v), [0.0, 2.0, "1e-3"])
bad("smoothed_plan", "t0", lambda v: smoothed_plan(1.0, MOTOR, LIMITS, 0.5, 1e-3, t0=v), [-1.0])

# plan_waypoints (every family): the count before any work
bad("plan_waypoints", "waypoints", lambda v: plan_waypoints(v, caps=CAPS),
    [None, "1.0", 1.0, [0.0], [0.0, "1.0"], [0.0, True], [0.0, None], [0.0, math.nan], [0.0, 1e7], {0: 1},
     [0.0, [1.0]]])
bad("plan_waypoints", "waypoints", lambda v: plan_waypoints(v, caps=CAPS), [[0.0, 0.0]], shown="at 0.0 rad")
bad("plan_waypoints", "waypoints", lambda v: plan_waypoints((x for x in v), caps=CAPS), [[0.0, 1.0]],
    shown="generator")
for family in ("psi", "hermite", "spline", "scurve"):
    bad("plan_waypoints", "waypoints", lambda v, f=family: plan_waypoints(v, family=f, caps=CAPS), [MANY],
        shown=str(len(MANY)))
bad("plan_waypoints", "family", lambda v: plan_waypoints([0.0, 1.0], family=v, caps=CAPS), ["bezier", None, 1])
bad("plan_waypoints", "rho", lambda v: plan_waypoints([0.0, 1.0], rho=v, caps=CAPS),
    [0.0, -0.5, 1e4, math.nan, "0.5", True])
bad("plan_waypoints", "t0", lambda v: plan_waypoints([0.0, 1.0], t0=v, caps=CAPS), [-0.01, math.nan, "0", 1e7])
bad("plan_waypoints", "durations", lambda v: plan_waypoints([0.0, 1.0], durations=v),
    [[-0.1], ["0.1"], "0.1", 0.1, [0.1, 0.1], [math.nan], [True], {0: 0.1}])
bad("plan_waypoints", "durations", lambda v: plan_waypoints([0.0, 1.0], durations=v), [[0.0]], shown="=0.0 s")
bad("plan_waypoints", "durations", lambda v: plan_waypoints([0.0, 1.0], family="scurve", durations=v, caps=CAPS),
    [[0.1]])
bad("plan_waypoints", "caps", lambda v: plan_waypoints([0.0, 1.0], caps=v),
    [{"v_max": 1.0, "a_max": 1.0, "j_max": 1.0}, (1.0, 1.0, 1.0), "caps", None])

# Waypoint and Caps
bad("Waypoint", "theta", lambda v: Waypoint(v), [math.nan, 1e7, "1"])
bad("Waypoint", "velocity", lambda v: Waypoint(1.0, velocity=v), [1e7, math.nan, "1"])
bad("Waypoint", "dwell", lambda v: Waypoint(1.0, dwell=v), [-1.0, math.nan, 1e7])
bad("Caps", "v_max", lambda v: Caps(v, 1.0, 1.0), [0.0, -1.0, 1e7, math.nan, "1"])
bad("Caps", "a_max", lambda v: Caps(1.0, v, 1.0), [0.0, 1e10])
bad("Caps", "j_max", lambda v: Caps(1.0, 1.0, v), [0.0, 1e13, True])

# PiecewisePlan: breaks, coefficients, rho > 0 on every whole segment, a flag that cannot overflow
bad("PiecewisePlan", "breaks", lambda v: PiecewisePlan(v, [[1.0]], [[1.0]]),
    [[0.0, 0.0], [-1.0, 0.0], [0.0, math.nan], "01", [0.0, 1e-90], [0.0, 1e7], [0.0]])
bad("PiecewisePlan", "theta", lambda v: PiecewisePlan([0.0, 1.0], v, [[1.0]]),
    [[[math.inf]], "x", [[1.0], [2.0]], np.ones((1, 12))])
bad("PiecewisePlan", "theta", lambda v: PiecewisePlan([0.0, 1.0], v, [[1.0]]), [[[1e300, 0.0]]], shown="1e+300")
bad("PiecewisePlan", "theta", lambda v: PiecewisePlan([0.0, 1e-8], v, [[1.0]]), [[[1.0, 0.0, 0.0, 0.0, 0.0]]],
    shown="2.4e+33")
bad("PiecewisePlan", "rho", lambda v: PiecewisePlan([0.0, 1.0], [[0.0]], v), [[[-2.0, 1.0]]], shown="-1.0")
bad("PiecewisePlan", "rho", lambda v: PiecewisePlan([0.0, 1.0], [[0.0]], v), [DIP], shown="-0.0001")
bad("PiecewisePlan", "rho", lambda v: PiecewisePlan([0.0, 1.0], [[0.0]], v), [TOUCH], shown="e-1")
bad("PiecewisePlan", "rho", lambda v: PiecewisePlan([0.0, 1.0], [[0.0]], v), [[[1e300, 1.0]]], shown="1e+300")
bad("PiecewisePlan.hold", "rho", lambda v: PiecewisePlan.hold(0.0, v, 0.0, 1.0), [0.0, -1.0, math.nan])
bad("PiecewisePlan.hold", "t0", lambda v: PiecewisePlan.hold(0.0, 0.5, v, 1.0), [-1.0])
bad("PiecewisePlan.concatenate", "parts", PiecewisePlan.concatenate, [[], None, [TABLE, "x"]])
bad("PiecewisePlan.theta_deriv", "order", lambda v: TABLE.theta_deriv(0.03, v), [5, -1, 1.5, "1"])
bad("PiecewisePlan.from_ppoly", "theta", lambda v: PiecewisePlan.from_ppoly(v, 0.5), ["x", None])
bad("PiecewisePlan._of_checked_table", "rho",
    lambda v: PiecewisePlan._of_checked_table(np.array([0.0, 1.0]), np.zeros((1, 11)),
                                              np.hstack([np.zeros((1, 8)), np.array(v)])), [DIP], shown="-0.0001")

# margins, copper loss, baselines, the bang-bang bound
bad("plan_margins", "plan", lambda v: plan_margins(v, MOTOR, LIMITS), ["plan", PAPER_PLAN])
bad("plan_margins", "motor", lambda v: plan_margins(TABLE, v, LIMITS), ["nema17"])
bad("plan_margins", "limits", lambda v: plan_margins(TABLE, MOTOR, v), [GOOD_LIMITS])
bad("plan_margins", "samples_per_segment", lambda v: plan_margins(TABLE, MOTOR, LIMITS, v), [0, 1.5, 10**7, "24"])
bad("copper_loss", "plan", lambda v: copper_loss(v, MOTOR), [None])
bad("copper_loss", "samples_per_segment", lambda v: copper_loss(TABLE, MOTOR, v), [0, 10**9])
bad("min_copper_plan", "distance", lambda v: min_copper_plan(v, 0.1, MOTOR, LIMITS), [0.0, math.nan, "1"])
bad("min_copper_plan", "duration", lambda v: min_copper_plan(1.0, v, MOTOR, LIMITS), [0.0, -1.0, math.nan])
bad("min_copper_plan", "limits", lambda v: min_copper_plan(1.0, 0.1, MOTOR, v), [GOOD_LIMITS])
bad("min_copper_plan", "t0", lambda v: min_copper_plan(1.0, 0.1, MOTOR, LIMITS, t0=v), [-1.0])
bad("baseline_plan", "kind", lambda v: baseline_plan(v, 1.0, MOTOR, LIMITS, 1.0, 1.0), ["bezier", None])
bad("baseline_plan", "distance", lambda v: baseline_plan("trapezoid", v, MOTOR, LIMITS, 1.0, 1.0), [0.0, math.nan])
bad("baseline_plan", "v_max", lambda v: baseline_plan("trapezoid", 1.0, MOTOR, LIMITS, v, 1.0), [0.0, -1.0])
bad("baseline_plan", "a_max", lambda v: baseline_plan("trapezoid", 1.0, MOTOR, LIMITS, 1.0, v), [0.0])
bad("baseline_plan", "j_max", lambda v: baseline_plan("ruckig", 1.0, MOTOR, LIMITS, 1.0, 1.0, v), [0.0, None])
bad("baseline_plan", "t0", lambda v: baseline_plan("trapezoid", 1.0, MOTOR, LIMITS, 1.0, 1.0, t0=v), [-1.0])
bad("best_baseline", "limits", lambda v: best_baseline("trapezoid", 1.0, MOTOR, v), [GOOD_LIMITS])
bad("best_baseline", "distance", lambda v: best_baseline("trapezoid", v, MOTOR, LIMITS), [0.0])
bad("ruckig_duration", "j_max", lambda v: ruckig_duration(1.0, 1.0, 1.0, v), [0.0, "1"])
bad("trapezoid_rows", "v_max", lambda v: trapezoid_rows(1.0, v, 1.0), [0.0])
bad("bang_bang_time", "distance", lambda v: bang_bang_time(v, MOTOR, LIMITS), [math.nan, "1"])
bad("bang_bang_time", "limits", lambda v: bang_bang_time(1.0, MOTOR, v), [GOOD_LIMITS])

# the paper's move and its parts
bad("point_to_point", "motor", lambda v: point_to_point(v, 0.0, 0.02, 0.4, 0.4), ["paper"])
bad("point_to_point", "t0", lambda v: point_to_point(PAPER, 0.0, 0.02, 0.4, 0.4, t0=v), [-0.01, math.nan])
bad("point_to_point", "theta2", lambda v: point_to_point(PAPER, 0.0, v, 0.4, 0.4), [1e7, "0.02"])
bad("check_feasibility", "plan", lambda v: check_feasibility(v, PAPER), ["plan"])
bad("check_feasibility", "motor", lambda v: check_feasibility(PAPER_PLAN, v), ["paper"])
bad("check_feasibility", "n", lambda v: check_feasibility(PAPER_PLAN, PAPER, n=v), [10**7, 2, "2001"])
bad("psi", "order", lambda v: psi(0.03, 0.02, 0.04, v), [6, -1, 1.5])
bad("psi", "tf", lambda v: psi(0.03, 0.02, v), [0.01, math.nan])
bad("DCurrentPlan", "t0", lambda v: DCurrentPlan(t0=v), [-1.0, math.nan])
bad("DCurrentPlan", "i_d1", lambda v: DCurrentPlan(i_d1=v), [1e4, math.nan])
bad("DCurrentPlan", "weakening", lambda v: DCurrentPlan(weakening=v), [-1.0])
bad("LossAwareRho", "rho_hold", lambda v: LossAwareRho(v), [0.0, 1e4, math.nan])
bad("LossAwareRho", "margin", lambda v: LossAwareRho(0.1, v), [2.0, math.nan])

# the interop
bad("nlsys", "plant", nlsys, ["motor", None, 1])
bad("nlsys", "load_input", lambda v: nlsys(PAPER, load_input=v), ["yes", 1])
bad("nlsys", "name", lambda v: nlsys(PAPER, name=v), [3, ""])
bad("flatsys", "motor", flatsys, ["paper", None])
bad("flatsys", "outputs", lambda v: flatsys(PAPER, v), ["rho_phi", None, ["rho_theta"]])
bad("flatsys", "load_torque", lambda v: flatsys(PAPER, load_torque=v), [math.nan, 1e300, "0"])
bad("flatsys", "name", lambda v: flatsys(PAPER, name=v), [3])
bad("PsiFamily", "flaglen", lambda v: PsiFamily(v, 0.0, 0.1), [(), (2, 7), "24", None, (2.5,), (True,)])
bad("PsiFamily", "flaglen", lambda v: PsiFamily(v, 0.0, 0.1), [(0,)], shown="flaglen=0")
bad("PsiFamily", "t0", lambda v: PsiFamily((2, 4), v, 0.1), [-1.0, math.nan, "0"])
bad("PsiFamily", "tf", lambda v: PsiFamily((2, 4), 0.02, v), [0.01, 1e7])
bad("PsiFamily.eval_deriv", "i", lambda v: PsiFamily((2, 4), 0.0, 0.1).eval_deriv(v, 0, 0.05, 0), [4, -1, 1.5])
bad("PsiFamily.eval_deriv", "k", lambda v: PsiFamily((2, 4), 0.0, 0.1).eval_deriv(0, v, 0.05, 0), [-1, 9])
bad("PsiFamily.eval_deriv", "var", lambda v: PsiFamily((2, 4), 0.0, 0.1).eval_deriv(0, 0, 0.05, v), [2, "0"])
bad("controller_nlsys", "controller", controller_nlsys, ["smc", None])
bad("controller_nlsys", "name", lambda v: controller_nlsys(None, name=v), [3])
bad("park", "Nr", lambda v: park(1.0, 0.0, 0.0, v), [0, 1.5, "50"])
bad("inverse_park", "Nr", lambda v: inverse_park(1.0, 0.0, 0.0, v), [-50])
bad("dq_state_to_flag", "motor", lambda v: dq_state_to_flag(np.zeros(4), np.zeros(2), v), ["paper"])
bad("dq_state_to_flag", "load_torque", lambda v: dq_state_to_flag(np.zeros(4), np.zeros(2), PAPER, v), [math.nan])
bad("dq_flag_to_state", "flag", lambda v: dq_flag_to_state(v, PAPER), ["flag", (0.0,) * 6])
bad("dq_flag_to_state", "motor", lambda v: dq_flag_to_state(DQFlag(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), v), [None])


def _forms(value: Any) -> set[str]:
    """How a message may write ``value`` (or, for a sequence, the element that is wrong)."""
    forms = {repr(value), str(value)}
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        forms |= {repr(float(value)), f"{float(value):g}", f"{float(value):.4g}"}
    if isinstance(value, (tuple, list)):
        for v in value:
            if not isinstance(v, (int, float)) or isinstance(v, bool) or v != 0:
                forms |= _forms(v)
    return forms


@pytest.mark.parametrize("row", ROWS, ids=[repr(r) for r in ROWS])
def test_a_planning_function_refuses_the_value_and_names_it(row):
    start = time.perf_counter()
    with pytest.raises(InputError) as err:
        row.call(row.value)
    message = str(err.value)
    assert row.argument in message, message
    shown = {row.shown} if row.shown else _forms(row.value)
    assert any(s in message for s in shown), message
    assert time.perf_counter() - start < 0.5, "refused only after work"


def test_the_table_is_large_and_covers_every_function():
    counts = Counter(r.function for r in ROWS)
    assert len(ROWS) >= 250 and len(counts) >= 35, counts


def test_valid_edges_are_accepted():
    """The checks refuse what they should, not a blanket refusal: plans at the edges of the ranges are made."""
    assert MotorLimits(v_bus=1e4, i_max=1e3, i_hold=1e-3, torque_angle_max=1.5, v_use=1.0).v_bus == 1e4
    plan = plan_waypoints(np.array([0.0, 1.0]), t0=0.0, caps=CAPS)
    assert plan.t0 == 0.0 and plan.theta2 == pytest.approx(1.0)
    just_positive = [[100.0, -200.0 * C, 100.0 * C * C + 1e-9]]  # min 1e-9 A between the old check points
    assert PiecewisePlan([0.0, 1.0], [[0.0]], just_positive).rho1 > 0
    assert time_optimal_sequence([(0.0, 0.0), (1.0, 0.01)], MOTOR, LIMITS, t0=0.0).t0 == 0.0
    assert PsiFamily([2, 4], 0.0, 0.1).nvars == 2
