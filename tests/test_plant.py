"""Plant effects: detent torque, Coulomb friction, iron loss; the controllers' model does not see them."""
import numpy as np
import pytest

import flatstep as fs
from flatstep.model.plant import PlantEffects, plant_acceleration, plant_rhs

TS = 5e-5


def test_detent_torque_at_given_angles(motor):
    fx = PlantEffects(detent_torque=2e-3)
    step = 2 * np.pi / (4 * motor.Nr)  # one detent period
    theta = np.array([0.0, step / 4, step / 2, 3 * step / 4, step / 8])
    np.testing.assert_allclose(fx.torque(0.0 * theta, theta, motor),
                               [0.0, -2e-3, 0.0, 2e-3, -2e-3 * np.sin(np.pi / 4)], atol=1e-15)
    # restoring about the detent positions theta = k step: d torque / d theta < 0 there
    assert (fx.torque(0.0, 1e-6, motor) - fx.torque(0.0, -1e-6, motor)) < 0


def test_coulomb_friction_opposes_the_speed_and_saturates(motor):
    fx = PlantEffects(coulomb_torque=1e-3, coulomb_speed=0.01)
    omega = np.array([-5.0, -0.01, 0.0, 0.01, 5.0])
    tq = fx.torque(omega, 0.0 * omega, motor)
    np.testing.assert_allclose(tq, [1e-3, 1e-3 * np.tanh(1.0), 0.0, -1e-3 * np.tanh(1.0), -1e-3], rtol=1e-12)


def test_magnetizing_resistance_is_the_simscape_torque(motor):
    """Km (ib - eb/Rm) cos - Km (ia - ea/Rm) sin with ea = -Km w sin, eb = Km w cos equals Te - Km^2 w / Rm."""
    Rm = 50.0
    fx = PlantEffects(magnetizing_resistance=Rm)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(4, 20)) * np.array([[0.4], [0.4], [3.0], [0.05]])
    ia, ib, w, th = x
    s, c = np.sin(motor.Nr * th), np.cos(motor.Nr * th)
    ea, eb = -motor.Km * w * s, motor.Km * w * c
    simscape = motor.Km * (ib - eb / Rm) * c - motor.Km * (ia - ea / Rm) * s
    ours = fs.model.motor.torque(x, motor) + fx.torque(w, th, motor)
    np.testing.assert_allclose(ours, simscape, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fx.iron_loss_power(w, motor), (ea**2 + eb**2) / Rm, rtol=1e-12)


def test_energy_balance_with_iron_loss(motor):
    """Supplied electrical energy = copper + viscous + iron losses + stored (kinetic, magnetic) energy."""
    fx = PlantEffects(magnetizing_resistance=1.0)
    h, n = 1e-6, 4000
    x = np.array([0.0, 0.0, 0.0, 0.0])
    t = np.arange(n) * h
    v = np.array([3.0 * np.cos(400 * t), 3.0 * np.sin(400 * t)])
    xs = [x]
    for k in range(n - 1):  # RK4 with the input held per step, as the sampled loop does
        f = lambda y: plant_rhs(y, v[:, k], motor, 0.0, fx)  # noqa: E731
        k1 = f(x); k2 = f(x + h / 2 * k1); k3 = f(x + h / 2 * k2); k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        xs.append(x)
    X = np.array(xs).T
    ia, ib, w, _ = X
    trap = lambda f: float(np.sum((f[1:] + f[:-1]) / 2) * h)  # noqa: E731
    supplied = trap(v[0] * ia + v[1] * ib)
    lost = trap(motor.R * (ia**2 + ib**2) + motor.B * w**2 + fx.iron_loss_power(w, motor))
    stored = 0.5 * motor.J * w[-1] ** 2 + 0.5 * motor.L * (ia[-1] ** 2 + ib[-1] ** 2)
    assert supplied > 1e-4
    assert supplied == pytest.approx(lost + stored, rel=1e-4)
    assert trap(fx.iron_loss_power(w, motor)) > 5e-3 * supplied  # the iron loss is 50x the tolerance


@pytest.mark.parametrize("kwargs, match", [
    (dict(detent_torque=-1e-3), "detent_torque=-0.001"), (dict(coulomb_torque=float("nan")), "not finite"),
    (dict(coulomb_speed=0.0), "coulomb_speed=0.0"), (dict(magnetizing_resistance=-5.0), "magnetizing_resistance"),
])
def test_bad_effects_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PlantEffects(**kwargs)


def test_effects_act_on_the_plant_only(motor, plan):
    """The detent moves the sampled run's rest position; the ideal measurement reads the true acceleration."""
    fx = PlantEffects(detent_torque=1e-3)
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500), "ideal")
    kw = dict(loop=fs.DriveLoop(TS, substeps=4), engine="python", t_end=0.04)
    clean = fs.simulate(motor, plan, ctrl, **kw)
    detent = fs.simulate(fs.Plant(motor, fx), plan, ctrl, **kw)
    assert detent.meta["plant"]["effects"]["detent_torque"] == 1e-3 and clean.meta["plant"]["effects"] is None
    assert np.max(np.abs(detent.theta - clean.theta)) > 1e-7
    x = np.array([0.3, 0.1, 2.0, 0.004])
    expected = (fs.model.motor.torque(x, motor) - motor.B * 2.0 - 1e-3 * np.sin(4 * motor.Nr * 0.004)) / motor.J
    assert plant_acceleration(x, motor, 0.0, fx) == pytest.approx(expected, rel=1e-12)
    assert fs.Plant(motor, fx).acceleration(x) == pytest.approx(expected, rel=1e-12)


def test_effects_act_in_continuous_time_on_both_engines(motor, plan):
    """The C continuous loop and solve_ivp integrate the same plant with its effects."""
    plant = fs.Plant(motor, PlantEffects(detent_torque=1e-3, coulomb_torque=1e-4, magnetizing_resistance=40.0))
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(W1=300.0, W2=300.0))
    c = fs.simulate(plant, plan, ctrl)
    ref = fs.simulate(plant, plan, ctrl, engine="scipy", solver=fs.Continuous("LSODA"))
    clean = fs.simulate(motor, plan, ctrl)
    assert np.max(np.abs(c.theta - clean.theta)) > 1e-6  # the effects act
    assert np.max(np.abs(c.theta - ref.theta)) < 1e-8


def test_a_plant_is_a_motor_its_effects_and_its_load(motor):
    plant = fs.Plant(motor, PlantEffects(), load=2e-5)
    assert plant.effects is None and plant.constant_load == 2e-5  # all-zero effects are none
    assert plant.as_dict() == {"motor": motor.as_dict(), "effects": None, "load": 2e-5}
    x = np.array([0.3, 0.1, 2.0, 0.004])
    assert plant.acceleration(x) == pytest.approx(plant_acceleration(x, motor, 2e-5), rel=1e-15)
    ramp = fs.Plant(motor, load=lambda t: 1e-5 * t)
    assert ramp.constant_load is None
    assert ramp.acceleration(x, 2.0) == pytest.approx(plant_acceleration(x, motor, 2e-5), rel=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(motor="paper"), r"Plant.motor='paper' is not a MotorParams"),
    (dict(effects=1e-3), r"Plant.effects=0.001 is not a PlantEffects"),
    (dict(load=float("nan")), r"load=nan"),
    (dict(load=float("inf")), r"load=inf"),
])
def test_bad_plants_are_refused(motor, kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.Plant(**{"motor": motor, **kwargs})
