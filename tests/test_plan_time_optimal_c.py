"""The C time-optimal planner (csrc/time_optimal.c) against the Python reference (flatstep.plan.time_optimal).

Both run the same algorithm; they differ in rounding only (a few ulp in the envelope's Newton roots, in the
Hermite solve, in the voltage's sqrt against hypot). The search tries gamma on a 2^-16 grid, so both try the same
tables unless a guess straddles a grid point (rare: the guesses differ by 1e-15 to 1e-9 relative, the grid step is 1.5e-5): the
durations agree to 1e-12 relative, and both plans pass plan_margins on a 4x finer check.
"""
import math

import numpy as np
import pytest

from flatstep.plan.time_optimal_c import WORK_LEN, plan_raw
from flatstep._flatstep_core import lib
from flatstep.model.motor import PRESETS
from flatstep.plan.limits import MotorLimits
from flatstep.plan.margins import plan_margins
from flatstep.plan.time_optimal import MAX_SEGMENTS, plan_move, time_optimal, time_optimal_sequence
from flatstep.validate import InputError

MOTOR = PRESETS["nema17"]
DISTANCES = (0.1, 0.3, 1.0, 2.5, 5.0, 10.0, 20.0)


@pytest.mark.parametrize("v_bus", [24.0, 12.0])
@pytest.mark.parametrize("i_run", [None, 0.025])
def test_c_and_python_plan_the_same_moves(v_bus, i_run):
    limits = MotorLimits(v_bus=v_bus, i_max=1.0, i_run=i_run)
    for d in DISTANCES:
        c, py = time_optimal(d, MOTOR, limits, engine="c"), time_optimal(d, MOTOR, limits, engine="python")
        assert c.n == py.n <= MAX_SEGMENTS
        assert math.isclose(c.tf, py.tf, rel_tol=1e-12), (d, c.tf, py.tf)
        scale = np.abs(py.theta).max(axis=1, keepdims=True)
        np.testing.assert_allclose(c.theta / scale, py.theta / scale, rtol=0, atol=1e-9)
        for plan in (c, py):
            m = plan_margins(plan, MOTOR, limits, samples_per_segment=97)  # four times the planner's sampling
            assert m["voltage"] <= limits.v_use * 1.005 and m["current"] <= 1 and m["torque_angle"] <= 1, (d, m)
            assert abs(plan.theta2 - d) < 1e-9


def test_the_search_reports_its_table_and_margins():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    rc, out = plan_raw(5.0, MOTOR, limits)
    ref = plan_move(5.0, MOTOR, limits)
    assert rc == lib.TO_OK and out.tables >= 1
    assert math.isclose(out.gamma, ref.gamma, rel_tol=1e-12) and math.isclose(out.width, ref.width, rel_tol=1e-12)
    assert out.margins.worst <= 0 and math.isclose(out.margins.voltage, ref.margins["voltage"], rel_tol=1e-9)


def test_negative_moves_and_offsets_agree():
    limits = MotorLimits(v_bus=12.0, i_max=1.0)
    c = time_optimal(-3.0, MOTOR, limits, theta1=1.5, t0=0.2)
    py = time_optimal(-3.0, MOTOR, limits, theta1=1.5, t0=0.2, engine="python")
    t = np.linspace(c.t0, c.tf, 301)
    np.testing.assert_allclose(c.theta_deriv(t, 0), py.theta_deriv(t, 0), atol=1e-9)
    assert c.theta1 == 1.5 and abs(c.theta2 + 1.5) < 1e-9 and c.t0 == 0.2


@pytest.mark.parametrize("engine", ["c", "python"])
def test_a_sequence_is_its_moves_and_dwells(engine):
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    points = [(0.0, 0.01), (2.0, 0.0), (-1.0, 0.02), (4.0, 0.0)]
    plan = time_optimal_sequence(points, MOTOR, limits, t0=0.1, engine=engine)
    moves = sum(time_optimal(b[0] - a[0], MOTOR, limits, engine=engine).tf for a, b in zip(points, points[1:]))
    assert math.isclose(plan.tf, 0.1 + 0.03 + moves, rel_tol=1e-12)
    assert abs(plan.theta2 - 4.0) < 1e-9 and np.all(np.abs(plan.continuity(3)) <= 1e-6 * np.array([1, 1e2, 1e4, 1e7]))


def test_a_100_waypoint_sequence_agrees_between_engines():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    theta = np.cumsum(np.random.default_rng(0).uniform(0.2, 5.0, 100) * np.where(np.arange(100) % 3, 1, -1))
    points = [(float(x), 0.0) for x in theta]
    c = time_optimal_sequence(points, MOTOR, limits)
    py = time_optimal_sequence(points, MOTOR, limits, engine="python")
    assert math.isclose(c.tf, py.tf, rel_tol=1e-12) and c.n == py.n
    assert plan_margins(c, MOTOR, limits)["voltage"] <= limits.v_use * 1.005


def test_bad_arguments_are_refused_before_c():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    with pytest.raises(ValueError, match="engine='fortran'"):
        time_optimal(1.0, MOTOR, limits, engine="fortran")
    with pytest.raises(ValueError, match="engine='fortran'"):
        time_optimal_sequence([(0.0, 0.0), (1.0, 0.0)], MOTOR, limits, engine="fortran")
    with pytest.raises(ValueError, match="distance"):
        time_optimal(math.nan, MOTOR, limits)
    with pytest.raises(ValueError, match="theta1"):
        time_optimal(1.0, MOTOR, limits, theta1=math.inf)
    with pytest.raises(ValueError, match="widths"):
        time_optimal(1.0, MOTOR, limits, widths=(0.001, -0.001))
    with pytest.raises(ValueError, match="cannot start"):
        time_optimal(1.0, MOTOR, MotorLimits(v_bus=0.5, i_max=1.0))
    for engine in ("c", "python"):  # the same message from both: the move's samples
        with pytest.raises(InputError, match="move of 100000 rad takes .*MAX_PLAN_SAMPLES"):
            time_optimal(1e5, MOTOR, limits, engine=engine)
    with pytest.raises(ValueError, match="no feasible plan"):  # R i_hold alone takes more than 5 % of the bus
        time_optimal(1.0, MOTOR, MotorLimits(v_bus=24.0, i_max=1.0, v_use=0.05))


def test_the_c_error_codes():
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    assert plan_raw(1.0, MOTOR, limits, work_len=WORK_LEN - 1)[0] == lib.TO_EWORK
    assert plan_raw(0.0, MOTOR, limits)[0] == lib.TO_EARGS
    assert plan_raw(1.0, MOTOR, MotorLimits(v_bus=0.5, i_max=1.0))[0] == lib.TO_ESTART
    assert plan_raw(1e5, MOTOR, limits)[0] == lib.TO_ELONG
    rc, out = plan_raw(1.0, MOTOR, MotorLimits(v_bus=24.0, i_max=1.0, v_use=0.05))
    assert rc == lib.TO_ENOPLAN and out.n == 0


@pytest.mark.parametrize("caps", [dict(speed_max=20.0), dict(accel_max=3000.0), dict(jerk_max=2e6),
                                  dict(speed_max=30.0, accel_max=5000.0, jerk_max=5e6)])
def test_speed_acceleration_and_jerk_caps_are_kept(caps):
    # a capped speed or acceleration is planned a little inside its cap, so that the fit does not cross it
    limits = MotorLimits(v_bus=24.0, i_max=1.0, **caps)
    for d in (0.5, 5.0):
        c, py = time_optimal(d, MOTOR, limits), time_optimal(d, MOTOR, limits, engine="python")
        assert math.isclose(c.tf, py.tf, rel_tol=1e-12)
        m = plan_margins(c, MOTOR, limits, samples_per_segment=97)
        assert m["worst"] <= 1.0 and m["voltage"] <= limits.v_use * 1.005, (d, m)


def test_the_c_plans_skip_only_the_rho_sampling():
    """engine="c" builds its plan without the constructor's rho sampling; the plan is the constructor's, bad tables fail."""
    from flatstep.plan.piecewise import PiecewisePlan

    limits = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.025)
    fast = time_optimal(-1.0, MOTOR, limits, theta1=0.5, t0=0.25)
    full = PiecewisePlan(fast.breaks, fast.theta, fast.rho)
    for a, b in ((fast.breaks, full.breaks), (fast.theta, full.theta), (fast.rho, full.rho)):
        np.testing.assert_array_equal(a, b)
        assert not a.flags.writeable
    t = np.linspace(fast.t0, fast.tf, 101)
    np.testing.assert_array_equal(fast.theta_deriv(t, 1), full.theta_deriv(t, 1))
    b, th, rh = fast.breaks.copy(), fast.theta.copy(), fast.rho.copy()
    bad_breaks = b.copy()
    bad_breaks[3] = bad_breaks[2]
    bad_rho = rh.copy()
    bad_rho[5, 2] = math.nan
    for args in ((bad_breaks, th, rh), (b, th, bad_rho), (b, th[:, 1:], rh), (b[:1], th[:0], rh[:0])):
        with pytest.raises(ValueError, match="not a finished C plan"):
            PiecewisePlan._of_checked_table(*args)
    seq = time_optimal_sequence([(0.0, 0.01), (2.0, 0.0), (-1.0, 0.02)], MOTOR, limits)
    ref = PiecewisePlan(seq.breaks, seq.theta, seq.rho)
    np.testing.assert_array_equal(seq.rho, ref.rho)


@pytest.mark.parametrize("distance", [1e-7, 3e-6, 1e-5, -1.2e-5, 1.5e-5, 2e-5])
def test_tiny_moves_plan_alike_in_c_and_the_reference(distance):
    """Moves of 1e-7 to 2e-5 rad once overflowed the C planner's box filter (heap corruption): now both engines plan."""
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    c, py = time_optimal(distance, MOTOR, limits), time_optimal(distance, MOTOR, limits, engine="python")
    assert c.tf == py.tf
    assert c.theta_deriv(np.array([c.tf]), 0)[0] == pytest.approx(distance, abs=1e-15)


@pytest.mark.parametrize("widths", [(1e300,), (1e-300,), (math.nan,), (2.0,), (1e-3, "1e-3"), (True,), ()])
def test_smoothing_widths_out_of_range_are_refused_by_both_engines(widths):
    limits = MotorLimits(v_bus=24.0, i_max=1.0)
    for engine in ("c", "python"):
        with pytest.raises(ValueError, match=r"widths=.*smoothing width"):
            time_optimal(1.0, MOTOR, limits, widths=widths, engine=engine)


@pytest.mark.parametrize("distance", [1e-9, -5e-8])
def test_moves_below_the_planners_resolution_are_refused(distance):
    with pytest.raises(ValueError, match="MIN_MOVE_DISTANCE"):
        time_optimal(distance, MOTOR, MotorLimits(v_bus=24.0, i_max=1.0))
