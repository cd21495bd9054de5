import numpy as np
import pytest

import flatstep as fs
from flatstep.model.motor import torque


def true_acc(x, motor, load=0.0):
    return (torque(x, motor) - motor.B * x[2] - load) / motor.J


def test_gains_defaults_are_the_papers():
    g = fs.SMCGains()
    assert (g.W1, g.W2, g.eps1, g.eps2, g.xi, g.wn) == (100, 100, 0.005, 0.005, 0.8, 10)
    assert g.alpha1 == 100 and g.alpha2 == pytest.approx(16)


@pytest.mark.parametrize("kwargs, match", [
    (dict(W1=0.0), "W1=0.0"), (dict(W2=-1.0), "W2=-1.0"), (dict(eps1=0.0), "eps1=0.0"),
    (dict(eps2=float("nan")), "eps2=nan"), (dict(xi=0.0), "xi=0.0"), (dict(wn=-10.0), "wn=-10.0"),
    (dict(hold_damping=0.0), "hold_damping=0.0"), (dict(hold_damping=float("inf")), "hold_damping=inf"),
])
def test_gains_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.SMCGains(**kwargs)


def test_bad_measurement_mode(motor, plan):
    with pytest.raises(ValueError, match="measurement='perfect'"):
        fs.FlatnessSMC(motor, plan, measurement="perfect")
    with pytest.raises(ValueError, match="needs the acceleration"):
        fs.FlatnessSMC(motor, plan).voltages(0.03, plan.x0(50))


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_on_the_plan_the_law_is_the_feedforward(motor, plan, measurement):
    t = np.linspace(0.0, 0.06, 121)
    x, v_ff = fs.flat_to_state(plan.flag(t), motor)
    ctrl = fs.FlatnessSMC(motor, plan, measurement=measurement)
    np.testing.assert_allclose(ctrl.voltages(t, x, true_acc(x, motor)), v_ff, rtol=1e-12, atol=1e-12)
    s1, s2 = ctrl.sliding_variables(t, x, true_acc(x, motor))
    assert np.max(np.abs(s1)) < 1e-14 and np.max(np.abs(s2)) < 1e-9


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_off_the_plan_the_law_imposes_the_sliding_dynamics(motor, plan, measurement):
    """With the exact model, the voltages give rho' = Gamma1 and theta''' = Gamma2 (eqs. 12-14), i.e.
    s1' = -W1 s1/(|s1|+eps1) and s2' = -W2 s2/(|s2|+eps2) exactly."""
    rng = np.random.default_rng(5)
    n = 40
    t = rng.uniform(0.0, 0.06, n)
    x, _ = fs.flat_to_state(plan.flag(t), motor)
    x = x + np.array([0.02, -0.02, 0.5, 1e-3])[:, None] * rng.normal(size=(4, n))
    g = fs.SMCGains(W1=70.0, W2=300.0, eps1=0.01, eps2=0.2, xi=0.7, wn=40.0)
    ctrl = fs.FlatnessSMC(motor, plan, g, measurement=measurement)
    v = ctrl.voltages(t, x, true_acc(x, motor))
    got = fs.state_to_flat(x, v, motor)
    ref = plan.flag(t)
    s1, s2 = ctrl.sliding_variables(t, x, true_acc(x, motor))
    e, de, dde = got.theta - ref.theta, got.dtheta - ref.dtheta, got.ddtheta - ref.ddtheta
    ds1 = got.drho - ref.drho
    ds2 = got.dddtheta - ref.dddtheta + g.alpha2 * dde + g.alpha1 * de
    np.testing.assert_allclose(ds1, -g.W1 * s1 / (np.abs(s1) + g.eps1), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ds2, -g.W2 * s2 / (np.abs(s2) + g.eps2), rtol=1e-7, atol=1e-6)
    assert np.all(np.abs(s2) > 1e-3)  # the check is not vacuous


def test_model_mode_is_biased_by_an_unknown_load(motor, plan):
    x = plan.x0(motor.Nr)
    ideal = fs.FlatnessSMC(motor, plan, measurement="ideal")
    model = fs.FlatnessSMC(motor, plan, measurement="model")
    s_ideal = ideal.sliding_variables(0.0, x, true_acc(x, motor, 1e-5))[1]
    s_model = model.sliding_variables(0.0, x, true_acc(x, motor, 1e-5))[1]
    assert s_ideal == pytest.approx(-1e-5 / motor.J, rel=1e-12)  # the ideal mode sees the load's deceleration
    assert s_model == pytest.approx(0.0, abs=1e-12)  # the model mode cannot


def test_model_mode_acceleration_is_the_motor_models(motor, plan):
    """One formula in one place: the model mode reads flatstep.model.motor.acceleration, bit for bit."""
    rng = np.random.default_rng(7)
    for m in (motor, fs.MotorParams.preset("nema17")):
        ctrl = fs.FlatnessSMC(m, plan, measurement="model")
        x = rng.normal(size=(4, 500)) * np.array([[0.5], [0.5], [50.0], [3.0]])
        assert np.array_equal(ctrl.acceleration(x), fs.model.motor.acceleration(x, m))
        assert np.array_equal(ctrl.acceleration(x[:, 0]), fs.model.motor.acceleration(x[:, 0], m))
    ideal = fs.FlatnessSMC(motor, plan, measurement="ideal")
    assert ideal.acceleration(x, 3.0) == 3.0


def test_step_interface(motor, plan):
    ctrl = fs.FlatnessSMC(motor, plan, measurement="model")
    x = plan.x0(motor.Nr)
    v, state = ctrl.step(None, x, 0.01)
    assert state is None
    np.testing.assert_allclose(v, motor.R * x[:2], rtol=1e-12, atol=1e-14)
    v2, _ = fs.FlatnessSMC(motor, plan).step(None, [*x, 0.0], 0.01)
    np.testing.assert_allclose(v2, v, rtol=1e-14)


HOLD = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500, hold_damping=0.7)


def test_hold_rests_on_the_detent_of_theta2(motor, plan):
    ctrl = fs.FlatnessSMC(motor, plan, HOLD, "model")
    i_star = ctrl.hold_currents(0.0)
    assert np.hypot(*i_star) == pytest.approx(plan.rho2, rel=1e-14)
    assert torque([*i_star, 0.0, plan.theta2], motor) == pytest.approx(0.0, abs=1e-15)  # no torque on theta2...
    # ...and a restoring one beside it: the stiffness of the detent, Km rho2 Nr
    dth = 1e-6
    assert torque([*i_star, 0.0, plan.theta2 + dth], motor) / dth == pytest.approx(
        -motor.Km * plan.rho2 * motor.Nr, rel=1e-5)
    x = np.array([*i_star, 0.0, plan.theta2])
    np.testing.assert_allclose(ctrl.step(None, x, plan.tf)[0], motor.R * i_star, rtol=1e-12)  # the static voltages


def test_hold_damps_the_speed(motor, plan):
    ctrl = fs.FlatnessSMC(motor, plan, HOLD, "model")
    K = motor.Km * plan.rho2 * motor.Nr
    for omega in (1e-3, -2e-3):
        i_star = ctrl.hold_currents(omega)
        assert torque([*i_star, omega, plan.theta2], motor) == pytest.approx(
            -2 * 0.7 * np.sqrt(K * motor.J) * omega, rel=1e-6)
    big = ctrl.hold_currents(1e6)  # the damping torque clipped at the largest the current can make
    assert torque([*big, 0.0, plan.theta2], motor) == pytest.approx(-motor.Km * plan.rho2, rel=1e-12)


def test_hold_starts_at_tf_and_drives_the_currents_there(motor, plan):
    plain = fs.FlatnessSMC(motor, plan, fs.SMCGains(**{**HOLD.as_dict(), "hold_damping": None}), "model")
    hold = fs.FlatnessSMC(motor, plan, HOLD, "model")
    x = np.array([0.1, -0.3, 0.5, plan.theta2 + 1e-3])
    t = np.array([plan.t0, 0.5 * (plan.t0 + plan.tf), np.nextafter(plan.tf, 0)])
    X = np.repeat(x[:, None], 3, axis=1)
    np.testing.assert_array_equal(hold.voltages(t, X), plain.voltages(t, X))  # the law until tf
    v = hold.voltages(np.array([plan.tf, 1.0]), np.repeat(x[:, None], 2, axis=1))
    lam = HOLD.W1 / HOLD.eps1
    i_star = hold.hold_currents(x[2])
    emf = motor.Km * x[2] * np.array([-np.sin(motor.Nr * x[3]), np.cos(motor.Nr * x[3])])
    expected = motor.R * i_star + motor.L * lam * (i_star - x[:2]) + emf
    np.testing.assert_allclose(v, np.repeat(expected[:, None], 2, axis=1), rtol=1e-12)
