"""The planning comparison (flatstep.studies.plan_compare) on one move: plans, durations, tracking on the drive."""
import math

import pytest

from flatstep.model.motor import PRESETS
from flatstep.studies.plan_compare import I_RUN, PLANNERS, TORQUE_ANGLE, V_USE, _row, plans_for
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal import bang_bang_time

MOTOR = PRESETS["nema17"]
FULL_STEP = 2 * math.pi / 200


def test_one_move_compared_and_tracked():
    limits = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.1, v_use=0.87)
    plans = plans_for(1.0, MOTOR, limits)  # asserts Ruckig's duration is the table's
    assert set(plans) == set(PLANNERS) and all(p.t0 == 0.005 for p in plans.values())
    row = _row("1 rad", plans, MOTOR, limits, bang_bang_time(1.0, MOTOR, limits))
    assert row["bound"] < row["flatstep"]["duration"] < row["ruckig"]["duration"]
    assert row["ratio_ruckig"] < 0.9  # the planned rho* buys speed at 24 V
    for name in ("flatstep", "ruckig"):
        assert row[name]["max_error"] < 0.1 * FULL_STEP and row[name]["faults"] == 0
        assert row[name]["v_peak"] <= 24.0 and row[name]["saturated"] == 0.0
    assert row["flatstep"]["voltage"] <= 0.87 * 1.005 and row["ruckig"]["voltage"] <= 0.9 * 1.005


def test_the_default_is_20_percent_shorter_than_ruckig_at_5_rad_without_clipping():
    limits = MotorLimits(v_bus=24.0, i_max=1.0, i_run=I_RUN, v_use=V_USE, torque_angle_max=TORQUE_ANGLE)
    plans = plans_for(5.0, MOTOR, limits)
    row = _row("5 rad", plans, MOTOR, limits, None)
    assert row["ratio_ruckig"] <= 0.8  # the target (docs/planning.md)
    assert row["flatstep"]["saturated"] == 0.0 and row["flatstep"]["v_peak"] < 24.0  # never clipped at the bus
    assert row["flatstep"]["max_error"] < 0.1 * FULL_STEP and row["flatstep"]["faults"] == 0
    assert plans["ruckig"].tf - plans["ruckig"].t0 == pytest.approx(0.09818, abs=2e-5)  # the baseline unchanged
