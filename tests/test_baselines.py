"""Baseline controllers: microstepping, cascaded FOC, exact linearization, on the same sampled loop."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flatstep as fs
from flatstep.control import (
    CONTROLLER_TYPES,
    CascadeFOC,
    CascadeGains,
    ExactLinearization,
    LinearizationGains,
    MicrostepGains,
    Microstepping,
    make_controller,
)
from flatstep.control.loops import PIGains, bus_scale, inverse_park, park, pi_integrate
from flatstep.control.tuning import SMC_TYPES

TS = 5e-5
SLOW = fs.RestToRest(0.0, 0.02, 0.4, 0.4, t0=0.005, tf=0.045)


def loop(Ts=TS, substeps=10, **parts):
    return fs.DriveLoop(control_period=Ts, substeps=substeps, **parts)


@pytest.mark.parametrize("kind", CONTROLLER_TYPES)
def test_every_controller_tracks_a_slow_move_with_exact_sensors(motor, kind):
    ctrl = make_controller(kind, motor, SLOW, control_period=TS, measurement="ideal", v_limit=24.0,
                           smc_gains=fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500),
                           torques=fs.TorqueModel(load=0.0))
    r = fs.simulate(motor, SLOW, ctrl, loop=loop(substeps=4), t_end=0.05)
    assert r.meta["controller"] == type(ctrl).__name__ and r.meta["engine"] == "c"
    err = np.max(np.abs(r.theta_error[r.t >= SLOW.t0]))
    # microstepping lags by the load angle J theta''/(Km Nr rho) and rings; the closed loops follow closely
    bound = 2e-3 if kind == "microstep" else 2e-5
    assert err < bound and abs(r.theta[-1] - SLOW.theta2) < bound
    if kind not in SMC_TYPES:  # the sliding laws report their s1, s2
        assert r.s1 is None and "s1" not in r.series()


def test_microstepping_lags_by_the_load_angle(motor):
    """A constant load tau at rest: Km rho sin(Nr e) = -tau, with no position feedback to remove it (the
    rotor rings at sqrt(Km Nr rho / J) = 527 rad/s, damped only by B/2J = 14 1/s: wait 0.3 s)."""
    hold = fs.RestToRest(0.0, 0.0, 0.4, 0.4, t0=0.25, tf=0.3)  # no move: a hold at theta = 0
    ctrl = Microstepping(motor, hold, MicrostepGains(6000.0), control_period=2 * TS)
    r = fs.simulate(fs.Plant(motor, load=2e-3), hold, ctrl, loop=loop(2 * TS), t_end=0.3)
    e = np.arcsin(-2e-3 / (motor.Km * 0.4)) / motor.Nr
    assert r.theta_error[-1] == pytest.approx(e, rel=0.03)
    assert np.min(r.theta_error) < 1.5 * e  # it overshot: an undamped second-order response


def test_park_round_trip_and_torque_axis(motor):
    rng = np.random.default_rng(1)
    ia, ib, th = rng.normal(size=(3, 50))
    d, q = park(ia, ib, motor.Nr * th)
    np.testing.assert_allclose(inverse_park(d, q, motor.Nr * th), [ia, ib], atol=1e-14)
    np.testing.assert_allclose(motor.Km * q, fs.model.motor.torque(np.array([ia, ib, 0 * ia, th]), motor), atol=1e-14)


def test_pi_anti_windup_holds_the_integral_while_the_bus_limits(motor):
    g = PIGains.current_loop(motor, 6000.0)
    assert (g.kp, g.ki) == pytest.approx((motor.L * 6000.0, motor.R * 6000.0))
    assert pi_integrate(g, 0.5, 1.0, TS, hold=True) == 1.0
    assert pi_integrate(g, 0.5, 1.0, TS, hold=False) == pytest.approx(1.0 + g.ki * TS * 0.5)
    assert bus_scale([30.0, -12.0], 24.0) == pytest.approx(0.8) and bus_scale([3.0, 1.0], 24.0) == 1.0
    # a current step the bus cannot deliver at once: the microstepping integrals stay put while it saturates
    ctrl = Microstepping(motor, SLOW, MicrostepGains(6000.0, feedforward=False), control_period=TS, v_limit=4.0)
    state = ctrl.initial_state()
    v, new = ctrl.step(state, np.array([-0.4, 0.0, 0.0, 0.0, 0.0]), 0.0)
    assert np.max(np.abs(v)) > 4.0 and np.array_equal(new, state)
    v, new = ctrl.step(state, np.array([0.399, 0.0, 0.0, 0.0, 0.0]), 0.0)
    assert np.max(np.abs(v)) < 4.0 and not np.array_equal(new, state)


def test_cascade_gains_place_the_poles_w_w_w_over_4():
    g = CascadeGains(current_bandwidth=6000.0, position_bandwidth=1500.0)
    poly = [1.0, g.k_omega, g.k_omega * g.k_theta + g.ki_omega, g.ki_omega * g.k_theta]
    np.testing.assert_allclose(np.sort(np.roots(poly).real), [-1500.0, -1500.0, -375.0], rtol=1e-4)


def test_cascade_windup_is_bounded_under_a_low_bus(motor):
    """A 3 V bus cannot hold the fast plan; with the integrators held the loop recovers after the move."""
    ctrl = CascadeFOC(motor, SLOW, CascadeGains(6000.0, 1500.0), control_period=TS, measurement="ideal", v_limit=3.0)
    r = fs.simulate(motor, SLOW, ctrl, loop=loop(drive=fs.Drive(v_bus=3.0)), t_end=0.06)
    assert np.max(np.abs([r.va, r.vb])) == pytest.approx(3.0)  # the bus did limit
    assert abs(r.theta_error[-1]) < 1e-5


def test_exact_linearization_error_obeys_the_placed_poles(motor):
    """With the exact model and exact measurements the angle error is the linear ODE
    e''' + k2 e'' + k1 e' + k0 e = 0 (fine sampling: the poles are 100x below 1/Ts)."""
    Ts = 1e-5
    gains = LinearizationGains(wn=300.0, xi=0.9, p3=1000.0, pd=1000.0)
    hold = fs.RestToRest(0.0, 0.0, 0.4, 0.4, t0=0.003, tf=0.004)  # no move: the error decays on its own
    ctrl = ExactLinearization(motor, hold, gains, measurement="ideal")
    x0 = np.array([*hold.x0(motor.Nr)[:2], 0.0, 2e-4])  # the rotor 2e-4 rad off, at rest
    r = fs.simulate(motor, hold, ctrl, loop=loop(Ts, 2), t_end=0.004, x0=x0, engine="python")
    e0 = [2e-4, 0.0, float(fs.model.motor.torque(x0, motor) - 0.0) / motor.J]
    k0, k1, k2 = gains.k
    lin = solve_ivp(lambda t, z: [z[1], z[2], -k2 * z[2] - k1 * z[1] - k0 * z[0]], (0, r.t[-1]), e0,
                    t_eval=r.t, rtol=1e-10, atol=1e-14)
    assert np.max(np.abs(r.theta_error - lin.y[0])) < 0.02 * np.max(np.abs(lin.y[0]))
    i_d = park(r.ia, r.ib, motor.Nr * r.theta)[0]
    np.testing.assert_allclose(i_d[r.t <= 2e-3], 0.4 * np.exp(-gains.pd * r.t[r.t <= 2e-3]), atol=0.01 * 0.4)


@pytest.mark.parametrize("build, match", [
    (lambda m: make_controller("pid", m, SLOW, control_period=TS, measurement="ideal"), "controller type='pid' is unknown"),
    (lambda m: make_controller("cascade", m, SLOW, control_period=None, measurement="ideal"), "tuned from the control period"),
    (lambda m: CascadeGains(6000.0, -1.0), "position_bandwidth=-1.0"),
    (lambda m: MicrostepGains(0.0), "current_bandwidth=0.0"),
    (lambda m: LinearizationGains(300.0, 0.0, 1e3, 1e3), "xi=0.0"),
    (lambda m: Microstepping(m, SLOW, MicrostepGains(1e3), control_period=TS, measurement="x"), "measurement='x'"),
    (lambda m: make_controller("microstep", m, SLOW, control_period=TS, measurement="ideal", bandwidth_scale=0),
     "bandwidth_scale=0"),
])
def test_bad_baseline_settings_are_refused(motor, build, match):
    with pytest.raises(ValueError, match=match):
        build(motor)


@pytest.mark.parametrize("kind", ["microstep", "cascade"])
def test_baselines_with_integrators_need_the_sampled_loop(motor, kind):
    ctrl = make_controller(kind, motor, SLOW, control_period=TS, measurement="ideal")
    for engine in ("c", "scipy"):
        with pytest.raises(ValueError, match=r"has state updated once per control period: .*give loop=DriveLoop"):
            fs.simulate(motor, SLOW, ctrl, engine=engine)


@pytest.mark.parametrize("kind", ["microstep", "cascade", "exact_linearization"])
def test_baselines_run_on_the_c_loop_as_on_the_reference(motor, kind):
    """Every baseline on C ``sampled_run``, with a bus that saturates, noisy sensors and a plant effect, against
    the Python reference loop: the same states to rounding."""
    ctrl = make_controller(kind, motor, SLOW, control_period=TS, measurement="model", v_limit=3.5)
    plant = fs.Plant(motor.replace(R=1.1 * motor.R), fs.PlantEffects(detent_torque=1e-4), load=1e-5)
    lp = loop(substeps=4, drive=fs.Drive(v_bus=3.5), sensors=fs.Sensors(current_noise=2e-3, seed=1))
    c, py = (fs.simulate(plant, SLOW, ctrl, loop=lp, engine=e, t_end=0.05) for e in ("c", "python"))
    assert c.meta["engine"] == "c" and py.meta["engine"] == "python"
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-10)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-8)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-6)
    assert np.max(np.abs([c.va, c.vb])) == pytest.approx(3.5)  # the bus did limit
    assert abs(c.theta[-1] - SLOW.theta2) < 5e-3  # and the move was made (microstepping: less the load angle)


def test_exact_linearization_runs_in_continuous_time(motor):
    """It has no state, so it runs inside the plant's right-hand side too, on both continuous engines."""
    gains = LinearizationGains(wn=300.0, xi=0.9, p3=1000.0, pd=1000.0)
    ctrl = ExactLinearization(motor, SLOW, gains, measurement="ideal")
    c = fs.simulate(motor, SLOW, ctrl, t_end=0.05)
    ref = fs.simulate(motor, SLOW, ctrl, engine="scipy", solver=fs.Continuous("LSODA"), t_end=0.05)
    assert c.meta["engine"] == "c" and np.max(np.abs(c.theta_error)) < 1e-8
    assert np.max(np.abs(c.theta - ref.theta)) < 1e-8
