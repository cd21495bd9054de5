"""The sampled drive loop: the Python reference against the C engine, and what each part of the drive does."""
import numpy as np
import pytest

import flatstep as fs
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
COUNT = 2 * np.pi / 16384


def loop(substeps=10, **parts):
    """The drive loop at 20 kHz with these parts (10 RK4 substeps unless given)."""
    return fs.DriveLoop(control_period=TS, substeps=substeps, **parts)


@pytest.mark.parametrize("measurement, load", [("ideal", 0.0), ("model", 1e-5)])
def test_reference_loop_matches_the_c_sampled_engine(motor, plan, measurement, load):
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, measurement=measurement)
    plant = fs.Plant(motor.replace(L=0.011, Km=0.048), load=load)
    kw = dict(loop=loop(substeps=4), t_end=0.04)
    py = fs.simulate(plant, plan, ctrl, engine="python", **kw)
    c = fs.simulate(plant, plan, ctrl, engine="c", **kw)
    np.testing.assert_allclose(py.t, c.t, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(py.theta, c.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.array([py.va, py.vb]), np.array([c.va, c.vb]), rtol=0, atol=1e-9)


def test_bus_saturation_bounds_the_applied_voltage(motor, plan):
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(W1=6000, W2=3e5, eps1=0.5, eps2=50, xi=0.9, wn=1500),
                          measurement="model")
    free = fs.simulate(motor, plan, ctrl, loop=loop(), engine="python", x0=[0.1, 0.0, 0.0, 0.0])
    capped = fs.simulate(motor, plan, ctrl, loop=loop(drive=Drive(v_bus=12.0)), x0=[0.1, 0.0, 0.0, 0.0])
    assert np.max(np.abs([free.va, free.vb])) > 12.0
    assert np.max(np.abs([capped.va, capped.vb])) <= 12.0 + 1e-12


def test_papers_gains_lose_the_move_at_20_khz_and_designed_gains_hold_it(motor, plan):
    """The paper's gains tuned for continuous time: W/eps = 2e4 1/s, i.e. W Ts / eps = 1 at 20 kHz."""
    plant, kw = fs.Plant(motor, load=1e-5), dict(loop=loop(drive=Drive(), sensors=Sensors(),
                                                          observer=Observer(bandwidth=1500.0, load_states=2)))
    paper = fs.simulate(plant, plan, fs.FlatnessSMC(motor, plan, fs.SMCGains(), "observer"), **kw)
    designed = fs.simulate(plant, plan, fs.FlatnessSMC(motor, plan, DESIGNED, "observer"), **kw)
    assert paper.summary()["max_abs_theta_error"] > 10 * COUNT
    s = designed.summary()
    assert s["max_abs_theta_error_move"] < COUNT and max(s["max_abs_va"], s["max_abs_vb"]) <= 24.0


def test_observer_removes_the_model_mode_bias_under_load(motor, plan):
    plant = fs.Plant(motor, load=2e-5)
    exact = dict(drive=Drive(), sensors=Sensors(encoder_counts=None, current_bits=None))
    naive = fs.simulate(plant, plan, fs.FlatnessSMC(motor, plan, DESIGNED, "model"), loop=loop(**exact), t_end=0.08)
    observed = fs.simulate(plant, plan, fs.FlatnessSMC(motor, plan, DESIGNED, "observer"), t_end=0.08,
                           loop=loop(observer=Observer(bandwidth=1500.0, load_states=1), **exact))
    # the model mode sees theta'' = tau/J at rest; inside the boundary layer (lambda2 = W2/eps2) the law
    # settles where Gamma2 = -B theta''/J, i.e. s2 = (eps2/W2)(B tau/J^2 - alpha2 tau/J), e = (s2 - tau/J)/alpha1
    a = 2e-5 / motor.J
    s2 = DESIGNED.eps2 / DESIGNED.W2 * (motor.B / motor.J * a - DESIGNED.alpha2 * a)
    bias = (s2 - a) / DESIGNED.alpha1
    assert naive.summary()["final_theta_error"] == pytest.approx(bias, rel=0.02)
    assert abs(observed.summary()["final_theta_error"]) < abs(bias) / 100


@pytest.mark.parametrize("kwargs, match", [
    (dict(loop=loop(observer=Observer())), "needs measurement='observer'"),
    (dict(loop=loop(observer=Observer()), engine="python"), "needs measurement='observer'"),
    (dict(engine="python"), "engine='python' does not run continuous control"),
])
def test_inconsistent_loops_are_refused(motor, plan, kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.simulate(motor, plan, fs.FlatnessSMC(motor, plan), **kwargs)


@pytest.mark.parametrize("engine", ["c", "python"])
def test_ideal_mode_with_sensors_is_refused(motor, plan, engine):
    with pytest.raises(ValueError, match="use measurement='model'"):
        fs.simulate(motor, plan, fs.FlatnessSMC(motor, plan), loop=loop(sensors=Sensors()), engine=engine)


@pytest.mark.parametrize("kwargs, match", [
    (dict(control_period=-1e-4), r"control_period=-0.0001 s is out of range: .*valid: \[1e-08, 1000\] s"),
    (dict(control_period=0.0), r"control_period=0.0 s is out of range"),
    (dict(substeps=0), r"substeps=0 must be an integer in \[1, 100000\] \(RK4 steps per control period\)"),
    (dict(substeps=2.5), r"substeps=2.5 must be an integer in \[1, 100000\]"),
    (dict(compute_delay="yes"), r"compute_delay='yes' must be true or false"),
    (dict(drive=24.0), r"DriveLoop.drive=24.0 is not a Drive"),
    (dict(sensors=Observer()), r"DriveLoop.sensors=Observer\(.*\) is not a Sensors"),
    (dict(observer=Sensors()), r"DriveLoop.observer=Sensors\(.*\) is not a Observer"),
])
def test_bad_drive_loops_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.DriveLoop(**kwargs)


def test_drive_loop_at_a_rate_and_as_dict():
    lp = fs.DriveLoop.at(20e3, substeps=2, sensors=Sensors(delay=1))
    assert lp.control_period == pytest.approx(5e-5) and lp.substeps == 2 and lp.drive is None
    d = lp.as_dict()
    assert d["sensors"] == Sensors(delay=1).as_dict() and "drive" not in d and "observer" not in d
    assert (d["control_period"], d["substeps"], d["compute_delay"]) == (lp.control_period, 2, False)
    with pytest.raises(ValueError, match=r"rate=0.0 Hz is out of range: .*valid: \[0.001, 1e\+08\] Hz"):
        fs.DriveLoop.at(0.0)


def test_delays_noise_and_switching_cost_accuracy_but_keep_the_move(motor, plan):
    plant, base = fs.Plant(motor, load=1e-5), dict(drive=Drive(), observer=Observer(bandwidth=1500.0))
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "observer")

    def run(engine="c", **parts):
        return fs.simulate(plant, plan, ctrl, loop=loop(**{**base, **parts}), engine=engine)

    clean = run(sensors=Sensors()).summary()
    noisy = run(sensors=Sensors(current_noise=5e-3, seed=2)).summary()
    again = run(sensors=Sensors(current_noise=5e-3, seed=2)).summary()
    other = run(sensors=Sensors(current_noise=5e-3, seed=3)).summary()
    assert noisy == again and noisy != other  # seeded noise: reproducible, and the seed matters
    assert noisy["max_abs_theta_error"] != clean["max_abs_theta_error"] and noisy["max_abs_theta_error"] < 2 * COUNT
    delayed = run(sensors=Sensors(delay=1)).summary()
    assert delayed["max_abs_theta_error"] != clean["max_abs_theta_error"]
    switched = run("python", sensors=Sensors(), drive=Drive(pwm="switched"))
    assert switched.summary()["max_abs_theta_error_move"] < 2 * COUNT
    assert np.max(np.abs([switched.va, switched.vb])) <= 24.0


def test_compute_delay_needs_smaller_gains(motor, plan):
    """One period of computation delay with lambda Ts = 0.3 still works; the paper's lambda Ts = 1 does not."""
    from flatstep.loop.design import design_gains

    d = design_gains(motor, plan, compute_delay=True)
    lp = loop(drive=Drive(), sensors=Sensors(), observer=d.observer, compute_delay=True)
    ok = fs.simulate(fs.Plant(motor, load=1e-5), plan, fs.FlatnessSMC(motor, plan, d.gains, "observer"),
                     loop=lp).summary()
    assert ok["max_abs_theta_error_move"] < 2 * COUNT
