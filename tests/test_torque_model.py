"""The torque model both flatness laws share (detent, Coulomb friction, known load) and the paper's law with it."""
import numpy as np
import pytest

import flatstep as fs
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.flat_dq import state_to_dq
from flatstep.model.plant import PlantEffects
from flatstep.model.torque_model import TorqueModel

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
TORQUES = TorqueModel(detent_torque=1e-3, detent_phase=0.3, coulomb_torque=2e-4, coulomb_speed=0.5, load=1e-5,
                      load_step=3e-5, load_t0=0.01, load_tf=0.03)
NOISY = Sensors(current_noise=5e-3, seed=2, current_offset=(2e-3, -1e-3), encoder_offset=0.25)


@pytest.mark.parametrize("kwargs, match", [
    (dict(detent_torque=-1e-3), "detent_torque=-0.001 N m must be >= 0"),
    (dict(detent_harmonic=0), "detent_harmonic=0 must be a positive integer"),
    (dict(coulomb_speed=0.0), "coulomb_speed=0.0 rad/s must be > 0"),
    (dict(load=float("nan")), "load=nan is not finite"),
    (dict(load_t0=0.5, load_tf=0.5), "load_tf=0.5 s must be greater than load_t0=0.5 s"),
])
def test_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        TorqueModel(**kwargs)


def test_rate_is_the_time_derivative_along_a_motion():
    t = np.linspace(0.0, 0.04, 4001)
    theta, omega, acc = 0.02 * np.sin(90 * t), 1.8 * np.cos(90 * t), -162 * np.sin(90 * t)
    E = TORQUES.torque(t, theta, omega, 50)
    rate = TORQUES.torque_rate(t, theta, omega, acc, 50)
    np.testing.assert_allclose(np.gradient(E, t)[1:-1], rate[1:-1], rtol=0, atol=2e-3 * np.max(np.abs(rate)))


def test_of_plant_knows_the_plants_torques(motor):
    plant = fs.Plant(motor, PlantEffects(detent_torque=1e-3, detent_harmonic=2, coulomb_torque=2e-4), load=1e-5)
    tm = TorqueModel.of_plant(plant)
    x = np.array([0.1, 0.3, 2.0, 0.013])
    # the plant's true acceleration is the model's with the known torques
    expected = (fs.model.motor.torque(x, motor) - motor.B * x[2] - tm.torque(0.0, x[3], x[2], motor.Nr)) / motor.J
    assert plant.acceleration(x) == pytest.approx(expected, rel=1e-12)
    assert TorqueModel.of_plant(fs.Plant(motor)) == TorqueModel()
    with pytest.raises(ValueError, match="is a function"):
        TorqueModel.of_plant(fs.Plant(motor, load=lambda t: 0 * t))


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_the_papers_law_with_torques_imposes_the_sliding_dynamics(motor, plan, measurement):
    """With the extended model exact, the paper's law gives rho' = Gamma1 and theta''' = Gamma2."""
    rng = np.random.default_rng(5)
    n = 40
    t = rng.uniform(0.0, 0.06, n)
    x, _ = fs.flat_to_state(plan.flag(t), motor)
    x = x + np.array([0.02, -0.02, 0.5, 1e-3])[:, None] * rng.normal(size=(4, n))
    g = fs.SMCGains(W1=70.0, W2=300.0, eps1=0.01, eps2=0.2, xi=0.7, wn=40.0)
    ctrl = fs.FlatnessSMC(motor, plan, g, measurement, torques=TORQUES)
    plain = fs.FlatnessSMC(motor, plan, g, "model")
    acc = (fs.model.motor.torque(x, motor) - motor.B * x[2] - TORQUES.torque(t, x[3], x[2], motor.Nr)) / motor.J
    v = ctrl.voltages(t, x, acc)
    got = state_to_dq(x, v, motor, TORQUES, t)  # theta''' under the extended model, in any coordinates
    ref = plan.flag(t)
    s1, s2 = ctrl.sliding_variables(t, x, acc)
    ds2 = (got.dddtheta - ref.dddtheta) + g.alpha2 * (got.ddtheta - ref.ddtheta) + g.alpha1 * (got.dtheta - ref.dtheta)
    np.testing.assert_allclose(ds2, -g.W2 * s2 / (np.abs(s2) + g.eps2), rtol=1e-7, atol=1e-5)
    di = fs.rhs(0.0, x, v, motor)[:2]  # the phase currents' rates of eq. (1)
    rho_dot = (x[0] * di[0] + x[1] * di[1]) / np.hypot(x[0], x[1])
    np.testing.assert_allclose(rho_dot, ref.drho - g.W1 * s1 / (np.abs(s1) + g.eps1), rtol=1e-9, atol=1e-9)
    assert np.max(np.abs(plain.voltages(t, x) - v)) > 1e-3  # the torques change the law


def run(law, motor, plan, torques, measurement="observer", effects=None, engine="c", t_end=0.06):
    perturbed = motor.replace(R=1.1 * motor.R, L=0.9 * motor.L, Km=0.9 * motor.Km, J=1.1 * motor.J, B=0.9 * motor.B)
    observer = Observer(1500.0, 2) if measurement == "observer" else None
    loop = fs.DriveLoop(TS, sensors=NOISY, observer=observer, drive=Drive(v_bus=24.0))
    ctrl = law(motor, plan, DESIGNED, measurement, torques=torques)
    return fs.simulate(fs.Plant(perturbed, effects=effects, load=1e-5), plan, ctrl, loop=loop, engine=engine,
                       t_end=t_end)


@pytest.mark.parametrize("law", [fs.FlatnessSMC, fs.DQFlatnessSMC])
def test_torques_off_reduce_to_todays_law_exactly(motor, plan, law):
    """Every amplitude 0 (other fields set): the run is the plain law's bit for bit, on both engines."""
    off = TorqueModel(detent_harmonic=2, detent_phase=0.3, coulomb_speed=2.0, load_t0=0.5, load_tf=0.7)
    effects = PlantEffects(detent_torque=1e-3)
    for measurement in ("observer", "model"):
        for engine in ("c", "python"):
            a, b = (run(law, motor, plan, tm, measurement, effects, engine, t_end=0.04) for tm in (TorqueModel(), off))
            assert np.array_equal(a.theta, b.theta) and np.array_equal(a.va, b.va) and np.array_equal(a.vb, b.vb)


def test_the_papers_law_with_torques_c_matches_python(motor, plan):
    effects = PlantEffects(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5)
    tm = TorqueModel.of_plant(fs.Plant(motor, effects=effects, load=1e-5))
    c, py = (run(fs.FlatnessSMC, motor, plan, tm, "observer", effects, engine) for engine in ("c", "python"))
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    c, py = (run(fs.FlatnessSMC, motor, plan, tm, "model", effects, engine) for engine in ("c", "python"))
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)


@pytest.mark.parametrize("law", [fs.FlatnessSMC, fs.DQFlatnessSMC])
def test_knowing_the_torques_cuts_the_error(motor, plan, law):
    """A strong detent (5e-3 N m, a quarter of Km rho) on the paper's move: the law that knows it tracks better."""
    effects = PlantEffects(detent_torque=5e-3, coulomb_torque=2e-4, coulomb_speed=0.5)
    tm = TorqueModel.of_plant(fs.Plant(motor, effects=effects, load=1e-5))
    blind, known = (run(law, motor, plan, t, "observer", effects).summary()["max_abs_theta_error_move"]
                    for t in (TorqueModel(load=1e-5), tm))
    assert known < 0.7 * blind, (known, blind)


def test_cascade_anti_cogging_on_both_engines(motor, plan):
    """The cascade's iq* carries E / Km: C and Python agree, torques off are the plain cascade bit for bit, and the
    known detent cuts its error."""
    effects = PlantEffects(detent_torque=5e-3, coulomb_torque=2e-4, coulomb_speed=0.5)
    plant = fs.Plant(motor, effects=effects, load=1e-5)
    # no quantization: at rest the cascade hunts across the sensors' steps, where the engines' last-bit
    # differences would read different counts
    loop = fs.DriveLoop(TS, sensors=Sensors(encoder_counts=None, current_bits=None, current_noise=5e-3, seed=2),
                        observer=Observer(1500.0, 2), drive=Drive(v_bus=24.0))
    off = TorqueModel(detent_harmonic=2, detent_phase=0.3, coulomb_speed=2.0)

    def run_cascade(torques, engine="c", kind="cascade_ff"):
        ctrl = fs.make_controller(kind, motor, plan, control_period=TS, measurement="observer", v_limit=24.0,
                                  torques=torques)
        return fs.simulate(plant, plan, ctrl, loop=loop, engine=engine)
    known = TorqueModel.of_plant(plant)
    for kind in ("cascade_ff", "cascade_model"):
        c, py = run_cascade(known, kind=kind), run_cascade(known, "python", kind)
        np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
        np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    model = run_cascade(known, kind="cascade_model")
    c = run_cascade(known)
    assert np.max(np.abs(model.theta - c.theta)) > 1e-7  # the observer that knows the torques changes the run
    plain = fs.simulate(plant, plan, fs.make_controller("cascade", motor, plan, control_period=TS,
                                                        measurement="observer", v_limit=24.0), loop=loop)
    assert np.array_equal(run_cascade(off).theta, plain.theta)
    err = [r.summary()["max_abs_theta_error_move"] for r in (c, plain)]
    assert err[0] < 0.7 * err[1], err
