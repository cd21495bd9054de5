"""Time-optimal planning under the motor's limits (flatstep.plan.time_optimal, flatstep.plan.limits)."""
import math
from typing import Any, cast

import numpy as np
import pytest

from flatstep.loop.design import design_gains
from flatstep.control.smc import FlatnessSMC
from flatstep.engine.simulate import simulate
from flatstep.loop.drive import Drive
from flatstep.loop.reference import DriveLoop
from flatstep.loop.sensors import Sensors
from flatstep.model.motor import PRESETS
from flatstep.plan.limits import MotorLimits
from flatstep.plan.margins import plan_margins
from flatstep.plan.time_optimal import (
    bang_bang_time,
    iq_bounds,
    smoothed_duration,
    smoothed_plan,
    time_optimal,
    time_optimal_sequence,
)

MOTOR = PRESETS["nema17"]
FULL_STEP = 2 * math.pi / 200


@pytest.fixture(scope="module")
def moves():
    """The 5 rad move at 24 V and at 12 V."""
    return {v: time_optimal(5.0, MOTOR, MotorLimits(v_bus=v, i_max=1.0)) for v in (24.0, 12.0)}


@pytest.mark.parametrize("v_bus", [24.0, 12.0])
def test_the_plan_is_feasible_on_a_finer_check_and_near_the_bound(moves, v_bus):
    limits = MotorLimits(v_bus=v_bus, i_max=1.0)
    plan = moves[v_bus]
    m = plan_margins(plan, MOTOR, limits, samples_per_segment=97)  # four times the planner's sampling
    # within the bus with the controller's headroom (v_use) kept up to 0.5 %, the current and the torque angle
    assert m["voltage"] <= limits.v_use * 1.005 and m["current"] <= 1 and m["torque_angle"] <= 1, m
    assert m["voltage"] > 0.85  # the bus is what limits a 5 rad move
    bound = bang_bang_time(5.0, MOTOR, limits)
    assert bound < plan.tf < 1.2 * bound, (plan.tf, bound)
    assert abs(plan.theta2 - 5.0) < 1e-9 and plan.theta1 == 0.0
    assert np.all(np.abs(plan.continuity(3)) <= 1e-6 * np.array([1.0, 1e2, 1e4, 1e7]))


def test_a_lower_bus_is_slower_and_the_envelope_brakes_harder_than_it_accelerates(moves):
    assert moves[12.0].tf > 1.8 * moves[24.0].tf
    lo, hi = iq_bounds(np.array([0.0, 50.0]), MOTOR, MotorLimits(v_bus=24.0, i_max=1.0))
    assert hi[0] == -lo[0] > 0 and -lo[1] > hi[1]  # back EMF helps braking


def test_negative_moves_mirror_positive_ones():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    up, down = time_optimal(1.0, MOTOR, limits, theta1=2.0), time_optimal(-1.0, MOTOR, limits, theta1=2.0)
    t = np.linspace(0, up.tf, 501)
    np.testing.assert_allclose(down.theta_deriv(t, 0) - 2.0, -(up.theta_deriv(t, 0) - 2.0), atol=1e-12)
    np.testing.assert_allclose(down.flag(t).rho, up.flag(t).rho, rtol=1e-12)


def test_the_move_is_tracked_on_the_20khz_drive_within_the_bus_and_a_step(moves):
    plan = moves[24.0]
    d = design_gains(MOTOR, cast(Any, plan), control_period=5e-5, v_bus=24.0)
    loop = DriveLoop(control_period=5e-5, substeps=4, drive=Drive(v_bus=24.0), sensors=Sensors(), observer=d.observer)
    r = simulate(MOTOR, plan, FlatnessSMC(MOTOR, plan, d.gains, "observer"), loop=loop, t_end=plan.tf + 0.03)
    assert np.max(np.abs(r.theta - r.theta_ref)) < 0.1 * FULL_STEP
    assert np.max(np.abs([r.va, r.vb])) <= 24.0
    assert abs(r.theta[-1] - 5.0) < 0.01 * FULL_STEP


def test_a_sequence_of_optimal_moves_with_dwells():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    plan = time_optimal_sequence([(0.0, 0.01), (2.0, 0.02), (-1.0, 0.0)], MOTOR, limits, t0=0.005)
    single = time_optimal(2.0, MOTOR, limits).tf + time_optimal(-3.0, MOTOR, limits).tf
    assert math.isclose(plan.tf, 0.005 + 0.01 + 0.02 + single, rel_tol=1e-12)
    assert plan.theta_deriv(np.array([0.006]), 0)[0] == 0.0 and plan.theta2 == pytest.approx(-1.0, abs=1e-9)
    assert plan_margins(plan, MOTOR, limits)["voltage"] <= limits.v_use * (1 + 1e-3)


@pytest.mark.parametrize("kwargs, match", [
    (dict(v_bus=0.0, i_max=1.0), "v_bus"),
    (dict(v_bus=24.0, i_max=1.0, i_hold=1.0), "i_hold"),
    (dict(v_bus=24.0, i_max=1.0, torque_angle_max=2.0), "torque_angle_max"),
    (dict(v_bus=24.0, i_max=1.0, v_use=1.5), "v_use"),
])
def test_bad_limits_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        MotorLimits(**kwargs)


def test_impossible_requests_are_refused():
    with pytest.raises(ValueError, match="distance=0.0"):
        time_optimal(0.0, MOTOR, MotorLimits(v_bus=24.0, i_max=1.0))
    with pytest.raises(ValueError, match="cannot start"):  # the resistance alone takes the bus at i_hold
        time_optimal(1.0, MOTOR, MotorLimits(v_bus=0.5, i_max=1.0))
    with pytest.raises(ValueError, match="sit at"):
        time_optimal_sequence([(0.0, 0.0), (0.0, 0.0)], MOTOR, MotorLimits(v_bus=24.0, i_max=1.0))


@pytest.mark.parametrize("distance, gamma, k", [(0.1, 0.7, 0.0625), (5.0, 0.86, 0.5), (-2.0, 1.0, 4.0)])
def test_the_search_prunes_on_the_tables_own_duration(distance, gamma, k):
    # the search skips a candidate whose smoothed_duration is not shorter than the best: it must be the table's
    limits = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.05)
    width = k * MOTOR.L / MOTOR.R
    plan = smoothed_plan(distance, MOTOR, limits, gamma, width)
    assert smoothed_duration(distance, MOTOR, limits, gamma, width) == pytest.approx(plan.tf - plan.t0, rel=1e-12)
    assert smoothed_duration(distance, MOTOR, limits, 0.9 * gamma, width) > plan.tf  # slower at less bus
