"""A run's status (engine/result.py): lost moves and controller faults never pass as "ok", on every path."""
from dataclasses import replace

import numpy as np
import pytest

import flatstep as fs
from flatstep.engine.result import arrival_error, full_step

DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
DRIVE = fs.DriveLoop(5e-5, drive=fs.Drive(v_bus=24.0))


def test_full_step_is_a_quarter_of_an_electrical_period():
    assert full_step(50) == pytest.approx(2 * np.pi / 200)  # 1.8 degrees on a 200-step motor


def test_a_tracked_move_is_ok(motor, plan):
    r = fs.simulate(fs.Plant(motor, load=1e-5), plan, fs.FlatnessSMC(motor, plan, DESIGNED, "model"), loop=DRIVE)
    s = r.summary()
    assert (r.status, s["status"], s["lost_at"], s["controller_faults"]) == ("ok", "ok", None, 0)


def test_a_lost_move_says_so_with_its_time(motor, plan):
    """The paper's gains on a 20 kHz drive lose the move (docs/drive.md): the status says when."""
    r = fs.simulate(fs.Plant(motor, load=1e-5), plan, fs.FlatnessSMC(motor, plan, fs.SMCGains(), "model"),
                    loop=DRIVE)
    s = r.summary()
    assert s["status"] == "lost" and plan.t0 <= s["lost_at"] <= r.t[-1]
    k = np.flatnonzero(r.t == s["lost_at"])[0]
    limit = np.where(r.t >= plan.tf, arrival_error(motor.Nr, plan.theta1, plan.theta2), full_step(motor.Nr))
    assert abs(r.theta_error[k]) > limit[k] and np.all(np.abs(r.theta_error[:k]) <= limit[:k])


def test_faults_are_counted(motor, plan):
    """Zero currents at the start are outside the law's domain (rho = 0): 0 V, counted, status "fault" or
    worse, never "ok"."""
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "model")
    r = fs.simulate(motor, plan, ctrl, loop=DRIVE, x0=np.zeros(4), t_end=0.04)
    s = r.summary()
    assert s["controller_faults"] > 0 and s["status"] in ("fault", "lost")
    assert r.meta["first_fault_time"] == 0.0


@pytest.mark.parametrize("gains, status", [(DESIGNED, "ok"), (fs.SMCGains(), "lost")])
def test_batch_rows_carry_the_status_on_both_paths(gains, status):
    base = fs.Scenario(loop=DRIVE, measurement="model", gains=gains,
                       plant=fs.Plant(fs.MotorParams.preset("paper"), load=1e-5))
    runs = fs.scenario_grid(base, controller_type=["smc"])
    in_c = fs.run_batch(runs, workers=1, progress=False)
    per_run = fs.run_batch(runs, workers=1, progress=False, keep=("t",))
    assert in_c[0]["status"] == per_run[0]["status"] == status
    assert in_c[0]["lost_at"] == per_run[0]["lost_at"]
    assert in_c[0]["controller_faults"] == per_run[0]["controller_faults"] == 0


def test_a_result_without_a_plant_refuses_to_guess(motor, plan):
    r = fs.simulate(motor, plan, t_end=0.04)
    with pytest.raises(ValueError, match="full step"):
        replace(r, meta={}).status


@pytest.mark.parametrize("theta1, theta2, expected", [(0.0, 0.5, np.pi / 100), (0.0, 0.02, 0.01), (0.1, 0.1, np.pi / 100),
                                                      (0.3, 0.29, 0.005)])
def test_arrival_error_is_a_full_step_or_half_the_move(theta1, theta2, expected):
    assert arrival_error(50, theta1, theta2) == pytest.approx(expected)


def test_a_move_that_recovers_before_tf_is_not_lost(motor, plan):
    """Half the move off at tf, at the target by the end (the detent hold pulls it there): late, not lost."""
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(hold_damping=0.7))
    r = fs.simulate(fs.Plant(motor, load=1e-4), plan, ctrl, t_end=0.1)
    move = (r.t >= plan.t0) & (r.t < plan.tf)
    assert np.max(np.abs(r.theta_error[move])) > arrival_error(motor.Nr, plan.theta1, plan.theta2)
    assert r.status == "ok"
