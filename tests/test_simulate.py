import numpy as np
import pytest

import flatstep as fs
from flatstep.studies.scenario import PAPER_SCENARIOS
from flatstep.engine.simulate import CONTINUOUS_ENGINES

THETA_COUNT = 2 * np.pi / 16384


@pytest.mark.parametrize("engine", CONTINUOUS_ENGINES)
def test_fig1_ideal_closed_loop_tracks_to_1e_8(engine):
    r = PAPER_SCENARIOS["fig1"].run(engine=engine)
    s = r.summary()
    assert s["max_abs_theta_error"] <= 1e-8
    assert s["max_abs_rho_error"] <= 1e-8
    assert s["theta_final"] == pytest.approx(0.02, abs=1e-8)
    assert r.t[0] == 0.0 and r.t[-1] == pytest.approx(0.06)
    # the voltages stay those of the feedforward
    np.testing.assert_allclose(r.va, r.va_ref, atol=1e-6)


def test_fig1_with_radau_agrees():
    r = PAPER_SCENARIOS["fig1"].run(engine="scipy", method="Radau")
    assert r.summary()["max_abs_theta_error"] <= 1e-8


@pytest.mark.parametrize("engine", CONTINUOUS_ENGINES)
def test_fig2_ends_close_to_theta2(engine):
    s = PAPER_SCENARIOS["fig2"].run(engine=engine).summary()
    # measured 4.57e-4 rad short of theta2 at 0.06 s: the theta error dynamics (wn = 10 rad/s) are slower
    # than the horizon; see docs/paper-notes.md
    assert abs(s["theta_final"] - 0.02) < 1e-3
    assert s["max_abs_rho_error"] < 1e-8
    assert abs(s["omega_final"]) < 1e-2


def test_fig2_error_decays_on_a_longer_horizon():
    scenario = PAPER_SCENARIOS["fig2"]
    short = scenario.run(engine="scipy").summary()["final_theta_error"]
    long = fs.simulate(scenario.motor, scenario.plan, scenario.controller(), load=1e-5, t_end=0.5,
                       engine="scipy").summary()["final_theta_error"]
    assert abs(long) < abs(short) / 20


def test_model_measurement_under_load_is_biased():
    fig2 = PAPER_SCENARIOS["fig2"]
    model = fs.Scenario("m", gains=fig2.gains, load_torque=1e-5, measurement="model")
    e_model = model.run(engine="scipy").summary()["final_theta_error"]
    e_ideal = fig2.run(engine="scipy").summary()["final_theta_error"]
    assert e_model < 0 and abs(e_model) > 5 * abs(e_ideal)


def test_without_load_model_and_ideal_modes_agree():
    a = fs.Scenario("a", measurement="model").run(engine="scipy")
    b = PAPER_SCENARIOS["fig1"].run(engine="scipy")
    np.testing.assert_allclose(a.theta, b.theta, atol=1e-9)


def test_time_varying_load_and_start_off_equilibrium(motor, plan):
    r = fs.simulate(motor, plan, load=lambda t: 1e-5 * (t > 0.03), x0=[0.41, 0.0, 0.0, 0.0], engine="scipy")
    assert abs(r.rho_error[r.t > 0.001]).max() < 1e-6  # s1 reaches its boundary layer in 0.01 / W1 s
    assert abs(r.theta[-1] - 0.02) < 2e-3


def test_papers_gains_lose_the_move_after_a_small_initial_angle_error(motor, plan):
    """With W2 = 100 the reaching phase of s2 is slow: an angle error of 1e-4 rad at rest means an
    acceleration error of Km Nr rho 1e-4 / J = 28 rad/s^2 in s2, which takes 0.28 s to remove; meanwhile
    the angle error grows (docs/paper-notes.md)."""
    r = fs.simulate(motor, plan, x0=[0.4, 0.0, 0.0, 1e-4], engine="scipy")
    assert abs(r.theta_error[-1]) > 0.01


@pytest.mark.parametrize("kwargs, match", [
    (dict(engine="matlab"), "engine='matlab'"), (dict(method="Euler"), "method='Euler'"),
    (dict(t_end=0.0), "t_end=0.0"), (dict(dt_out=-1.0), "dt_out=-1.0"), (dict(x0=[0.4, 0.0]), "x0="),
    (dict(x0=[np.nan, 0, 0, 0]), "x0="), (dict(load=np.nan), "load_torque=nan"), (dict(rtol=0.0), "rtol=0.0"),
])
def test_bad_simulation_inputs(motor, plan, kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.simulate(motor, plan, **kwargs)


def test_result_series_and_csv(tmp_path):
    r = PAPER_SCENARIOS["fig1"].run(engine="scipy", dt_out=1e-4)
    r.to_csv(tmp_path / "run.csv")
    data = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    np.testing.assert_allclose(data["theta_error"], r.theta_error, rtol=1e-15, atol=0)
    assert len(data) == 601
