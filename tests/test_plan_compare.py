"""The planning comparison (flatstep.plan.compare) on one move: plans, durations, tracking on the drive."""
import math

from flatstep.model.motor import PRESETS
from flatstep.plan.compare import PLANNERS, _row, plans_for
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
