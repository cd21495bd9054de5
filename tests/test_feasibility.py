import numpy as np
import pytest

import flatstep as fs


def test_paper_plan_is_feasible_with_the_worst_point_reported(motor, plan):
    rep = fs.check_feasibility(plan, motor)
    assert rep.feasible and rep.violations == ()
    t = np.linspace(plan.t0, plan.tf, 200001)
    f = plan.flag(t)
    margin = motor.Km * f.rho - np.abs(motor.J * f.ddtheta + motor.B * f.dtheta)
    assert rep.torque_margin == pytest.approx(margin.min(), rel=1e-9)
    assert rep.worst_time == pytest.approx(t[np.argmin(margin)], abs=2e-7)
    assert rep.peak_voltage == pytest.approx(3.36, rel=1e-12)  # R * 0.4 A at rest
    assert rep.min_rho == 0.4


def test_too_fast_a_move_is_refused_with_time_and_margin(motor):
    with pytest.raises(fs.InfeasiblePlanError, match=r"exceeds Km rho\* by .* N m at t=0\.0") as err:
        fs.point_to_point(motor, 0.0, 0.05, 0.4, 0.4, 0.02, 0.022)
    rep = err.value.report
    assert not rep.feasible and rep.torque_margin < 0 and 0.02 < rep.worst_time < 0.022
    assert rep.torque_ratio > 1
    assert isinstance(err.value, ValueError)


def test_voltage_and_current_limits(motor):
    with pytest.raises(fs.InfeasiblePlanError, match="exceeds v_max=3 V"):
        fs.point_to_point(motor, 0.0, 0.02, 0.4, 0.4, v_max=3.0)
    with pytest.raises(fs.InfeasiblePlanError, match="exceeds i_max=0.3 A"):
        fs.point_to_point(motor, 0.0, 0.02, 0.4, 0.4, i_max=0.3)
    assert fs.point_to_point(motor, 0.0, 0.02, 0.4, 0.4, v_max=24.0, i_max=0.5) == fs.PAPER_PLAN


def test_a_known_load_moves_the_margin(motor, plan):
    free = fs.check_feasibility(plan, motor)
    loaded = fs.check_feasibility(plan, motor, load_torque=1e-3)
    assert loaded.torque_margin < free.torque_margin
    with pytest.raises(fs.InfeasiblePlanError):
        fs.check_feasibility(plan, motor, load_torque=0.03).raise_if_infeasible()


def test_bad_sample_count(motor, plan):
    with pytest.raises(ValueError, match="n=2"):
        fs.check_feasibility(plan, motor, n=2)
