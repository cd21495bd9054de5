"""The loss-aware rho*(t) of the paper's law: the reference, the law on it, its C twin, its scenario keys."""
import math

import numpy as np
import pytest

import flatstep as fs
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.torque_model import TorqueModel
from flatstep.plan.loss_aware import LossAwareRho
from flatstep.studies.scenario_file import load_scenario

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
TORQUES = TorqueModel(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5, load=1e-5)


@pytest.mark.parametrize("kwargs, match", [
    (dict(margin=math.pi / 2, rho_hold=0.1), "margin=1.57.* must be in \\[0, pi/2\\)"),
    (dict(margin=-0.1, rho_hold=0.1), "margin=-0.1"),
    (dict(rho_hold=0.0), "rho_hold=0.0 A is out of range"),
])
def test_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LossAwareRho(**kwargs)


def test_the_reference_keeps_its_margin_and_is_smooth(motor, plan):
    la = LossAwareRho(margin=0.6, rho_hold=0.05)
    t = np.linspace(0.0, 0.06, 60001)
    ref = plan.flag(t)
    rho, drho = la.reference(ref, t, motor, TORQUES)
    A = motor.J * ref.ddtheta + motor.B * ref.dtheta + TORQUES.torque(t, ref.theta, ref.dtheta, motor.Nr)
    assert np.all(rho >= 0.05) and np.all(np.abs(A) / (motor.Km * rho) < math.cos(0.6))
    assert np.max(np.abs(A) / (motor.Km * rho)) > 0.75 * math.cos(0.6)  # near the margin where the move is fast
    np.testing.assert_allclose(np.gradient(rho, t)[1:-1], drho[1:-1], rtol=0, atol=1e-3 * np.max(np.abs(drho)))


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_on_its_reference_the_law_is_the_feedforward(motor, plan, measurement):
    la = LossAwareRho(margin=0.6, rho_hold=0.05)
    t = np.linspace(0.0, 0.06, 121)
    ref = plan.flag(t)
    rho, drho = la.reference(ref, t, motor, TorqueModel())
    x, v_ff = fs.flat_to_state(ref._replace(rho=rho, drho=drho), motor)
    ctrl = fs.FlatnessSMC(motor, plan, measurement=measurement, loss_aware=la)
    acc = (fs.model.motor.torque(x, motor) - motor.B * x[2]) / motor.J
    np.testing.assert_allclose(ctrl.voltages(t, x, acc), v_ff, rtol=1e-10, atol=1e-10)
    s1, _ = ctrl.sliding_variables(t, x, acc)
    assert np.max(np.abs(s1)) < 1e-14 and np.ptp(np.hypot(x[0], x[1])) > 0.02  # rho* does change


def test_c_matches_python_and_cuts_the_copper(motor, plan):
    effects = fs.PlantEffects(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5)
    plant = fs.Plant(motor, effects=effects, load=1e-5)
    loop = fs.DriveLoop(TS, sensors=Sensors(encoder_counts=None, current_bits=None, current_noise=5e-3, seed=2),
                        observer=Observer(1500.0, 2), drive=Drive(v_bus=24.0))
    la = LossAwareRho(margin=0.7854, rho_hold=0.2)
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "observer", torques=TorqueModel.of_plant(plant), loss_aware=la)
    c, py = (fs.simulate(plant, plan, ctrl, loop=loop, engine=e) for e in ("c", "python"))
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    held = fs.simulate(plant, plan, fs.FlatnessSMC(motor, plan, DESIGNED, "observer"), loop=loop)
    loss = [np.trapezoid(r.ia**2 + r.ib**2, r.t) for r in (c, held)]
    assert loss[0] < 0.5 * loss[1] and c.summary()["max_abs_theta_error_move"] < 2 * 2 * np.pi / 16384


def test_scenario_keys(tmp_path):
    path = tmp_path / "la.toml"
    path.write_text('[controller]\ntype = "smc_la"\ndesign = true\nrho_margin = 0.7\nrho_hold = 0.2\n'
                    '[drive]\ncontrol_rate = 20000.0\n')
    scenario, _ = load_scenario(path)
    assert scenario.controller().loss_aware == LossAwareRho(rho_hold=0.2, margin=0.7)
    assert fs.make_controller("smc_la", scenario.motor, scenario.plan, control_period=TS,
                              measurement="ideal").loss_aware == LossAwareRho(rho_hold=0.2, margin=math.pi / 4)
    assert fs.make_controller("smc", scenario.motor, scenario.plan, control_period=TS,
                              measurement="ideal").loss_aware is None
    path.write_text('[controller]\ntype = "smc_la"\nrho_hold = -1.0\n')
    with pytest.raises(ValueError, match=r"la.toml:controller.rho_hold: rho_hold=-1.0 A is out of range"):
        load_scenario(path)
