"""The direct-collocation yardstick (flatstep.bench.collocation): an analytic case, the model, the options, errors."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

pytest.importorskip("casadi")

from flatstep.bench.collocation import grid_converged, minimum_time  # noqa: E402
from flatstep.model.motor import PRESETS, MotorParams, rhs  # noqa: E402
from flatstep.plan.limits import MotorLimits  # noqa: E402

NEMA17 = PRESETS["nema17"]
LIMITS24 = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.025, v_use=0.84, torque_angle_max=1.1)


def test_pure_inertia_is_the_analytic_bang_bang():
    # no friction, an inductance and resistance too small to matter on a large bus: the current limit alone,
    # full torque Km i_max one way then the other, t = 2 sqrt(theta J / (Km i_max)); the current's steps at the
    # ends and the switch fall on grid intervals, an error of about 1/grid that falls with the grid
    motor = MotorParams(R=1e-3, L=1e-6, Km=0.2, J=1e-5, B=0.0, Nr=50)
    limits = MotorLimits(v_bus=1000.0, i_max=2.0, i_hold=0.1, v_use=1.0)
    for distance in (0.5, 3.0):
        exact = 2.0 * math.sqrt(distance * motor.J / (motor.Km * limits.i_max))
        errors = []
        for grid in (100, 400):
            move = minimum_time(distance, motor, limits, field_weakening=False, grid=grid)
            assert move.status == "Solve_Succeeded"
            errors.append(move.tf / exact - 1.0)
            assert 0.0 <= errors[-1] < 1.5 / grid
            assert move.peaks()["speed_peak"] == pytest.approx(distance / exact * 2.0, rel=1.5 / grid)
        assert errors[1] < 0.3 * errors[0]


def test_the_solution_obeys_eq_1_in_the_a_b_frame():
    # the phase voltages of the solution, applied to flatstep's own a-b model, move the rotor the distance
    move = minimum_time(0.3, NEMA17, LIMITS24, grid=400)
    phi = NEMA17.Nr * move.theta
    ia = move.i_d * np.cos(phi) - move.i_q * np.sin(phi)
    ib = move.i_d * np.sin(phi) + move.i_q * np.cos(phi)

    def f(t, x):
        v = [np.interp(t, move.t, move.v_a), np.interp(t, move.t, move.v_b)]
        return rhs(t, x, v, NEMA17)

    run = solve_ivp(f, (0.0, move.tf), [ia[0], ib[0], 0.0, 0.0], rtol=1e-9, atol=1e-12, t_eval=move.t, max_step=2e-5)
    assert run.success
    assert np.max(np.abs(run.y[3] - move.theta)) < 2e-3 * 0.3
    assert np.max(np.abs(run.y[0] - ia)) < 0.02 and np.max(np.abs(run.y[1] - ib)) < 0.02
    peaks = move.peaks()
    assert peaks["voltage"] == pytest.approx(1.0, abs=1e-6) and peaks["current"] <= 1.0 + 1e-6


def test_field_weakening_and_the_phase_limit_only_help():
    free = minimum_time(1.0, NEMA17, LIMITS24, grid=150)
    fixed = minimum_time(1.0, NEMA17, LIMITS24, field_weakening=False, grid=150)
    phase = minimum_time(0.3, NEMA17, LIMITS24, voltage="phase", grid=150)
    vector = minimum_time(0.3, NEMA17, LIMITS24, grid=phase.grid)
    assert free.tf < 0.85 * fixed.tf  # the characteristic current Km / (Nr L) = 0.57 A is below i_max
    assert free.peaks()["i_d_min"] < -0.3 and np.max(np.abs(fixed.i_d)) < 1e-9
    assert phase.grid >= 16 * 50 * 0.3 / (2 * math.pi)  # refined to the electrical turns
    assert phase.tf < vector.tf
    assert np.max(np.abs([phase.v_a, phase.v_b])) <= phase.v_limit * (1 + 1e-6)


def test_a_negative_move_mirrors_the_positive_one():
    up, down = minimum_time(0.5, NEMA17, LIMITS24, grid=120), minimum_time(-0.5, NEMA17, LIMITS24, grid=120)
    assert down.tf == pytest.approx(up.tf, rel=1e-6)
    assert np.allclose(down.theta, -up.theta, atol=1e-6) and np.allclose(down.i_q, -up.i_q, atol=1e-5)
    assert np.allclose(down.i_d, up.i_d, atol=1e-5)


def test_caps_and_grid_convergence():
    capped = MotorLimits(v_bus=24.0, i_max=1.0, v_use=0.84, speed_max=40.0)
    c = grid_converged(1.0, NEMA17, capped, grids=(60, 120))
    assert c.change < 5e-3
    assert c.fine.peaks()["speed_peak"] <= 40.0 * (1 + 1e-6)
    assert c.fine.tf > 1.0 / 40.0


@pytest.mark.parametrize("kwargs, match", [
    (dict(voltage="square"), "voltage"),
    (dict(grid=2), "grid"),
    (dict(grid=1.5), "grid"),
    (dict(load=float("nan")), "load"),
    (dict(effects="detent"), "effects"),
])
def test_bad_options_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        minimum_time(1.0, NEMA17, LIMITS24, **kwargs)


def test_bad_problems_are_refused():
    with pytest.raises(ValueError, match="distance"):
        minimum_time(0.0, NEMA17, LIMITS24)
    with pytest.raises(ValueError, match="jerk_max"):
        minimum_time(1.0, NEMA17, MotorLimits(v_bus=24.0, i_max=1.0, jerk_max=1e6))
    with pytest.raises(ValueError, match="above i_max"):
        minimum_time(1.0, NEMA17, LIMITS24, load=0.5)
    with pytest.raises(ValueError, match="finer"):
        grid_converged(1.0, NEMA17, LIMITS24, grids=(100, 50))
