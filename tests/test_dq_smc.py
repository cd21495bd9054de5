"""The d-q flatness + sliding-mode law: its sliding dynamics, its C twin (step and closed loop), its registration."""
import json
from dataclasses import replace

import numpy as np
import pytest

import flatstep as fs
from flatstep.core.structs import _in, _out, controller_struct, ffi, lib
from flatstep.control.tuning import LABELS, make_controller
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.flat_dq import DQFlag, dq_to_state, park, state_to_dq
from flatstep.model.plant import PlantEffects
from flatstep.model.torque_model import TorqueModel
from flatstep.studies.compare import scenario_kinds
from flatstep.studies.scenario_file import load_scenario

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
COUNT = 2 * np.pi / 16384
TORQUES = TorqueModel(detent_torque=1e-3, detent_phase=0.3, coulomb_torque=2e-4, coulomb_speed=0.5, load=1e-5,
                      load_step=3e-5, load_t0=0.01, load_tf=0.03)
NOISY = Sensors(current_noise=5e-3, seed=2, current_offset=(2e-3, -1e-3), encoder_offset=0.25)


def true_acc(x, motor, torques, t):
    i_q = park(x[0], x[1], motor.Nr * x[3])[1]
    return (motor.Km * i_q - motor.B * x[2] - torques.torque(t, x[3], x[2], motor.Nr)) / motor.J


def test_the_d_current_plan_and_its_rate(plan):
    """i_d*' is the time derivative of i_d* (central differences), weakening included; weakening acts at speed."""
    d_current = fs.DCurrentPlan(0.1, -0.2, 0.01, 0.05, weakening=0.05, weakening_speed=0.8)
    t = np.linspace(0.0, 0.06, 60001)
    ref = plan.flag(t)
    i_d, di_d = d_current.flag(t, ref.dtheta, ref.ddtheta)
    fast = ref.dtheta > 0.8
    # away from the kinks (the speed crossing 0.8 rad/s, the ends of the change), where i_d*' jumps
    smooth = np.convolve(np.diff(fast.astype(int), prepend=0) != 0, np.ones(5), "same") == 0
    smooth &= (np.abs(t - 0.01) > 1e-5) & (np.abs(t - 0.05) > 1e-5)
    np.testing.assert_allclose(np.gradient(i_d, t)[smooth], di_d[smooth], rtol=0, atol=1e-3 * np.max(np.abs(di_d)))
    plain = fs.DCurrentPlan(0.1, -0.2, 0.01, 0.05).flag(t)[0]
    assert np.all(i_d[~fast] == plain[~fast]) and np.all(i_d[fast] < plain[fast]) and fast.sum() > 1000
    with pytest.raises(ValueError, match="weakening=-0.1 A s/rad must be >= 0"):
        fs.DCurrentPlan(weakening=-0.1)


def test_refuses_what_it_cannot_do(motor, plan):
    with pytest.raises(ValueError, match="measurement='perfect'"):
        fs.DQFlatnessSMC(motor, plan, measurement="perfect")
    with pytest.raises(ValueError, match="hold_damping=0.7"):
        fs.DQFlatnessSMC(motor, plan, fs.SMCGains(hold_damping=0.7))
    with pytest.raises(ValueError, match="needs the acceleration"):
        fs.DQFlatnessSMC(motor, plan).voltages(0.03, plan.x0(50))
    with pytest.raises(ValueError, match="is not a TorqueModel"):
        fs.DQFlatnessSMC(motor, plan, torques=PlantEffects())
    with pytest.raises(ValueError, match="tf=0.0 s must be greater than t0=0.0"):
        fs.DCurrentPlan(0.0, -0.1, 0.0, 0.0)


@pytest.mark.parametrize("measurement", ["ideal", "model"])
@pytest.mark.parametrize("torques", [TorqueModel(), TORQUES], ids=["eq1", "torques"])
def test_on_the_plan_the_law_is_the_feedforward(motor, plan, measurement, torques):
    t = np.linspace(0.0, 0.06, 121)
    ref = plan.flag(t)
    d_current = fs.DCurrentPlan(0.0, -0.2, 0.02, 0.04, weakening=0.05, weakening_speed=0.8)
    i_d, di_d = d_current.flag(t, ref.dtheta, ref.ddtheta)
    x, v_ff = dq_to_state(DQFlag(ref.theta, ref.dtheta, ref.ddtheta, ref.dddtheta, i_d, di_d), motor, torques, t)
    ctrl = fs.DQFlatnessSMC(motor, plan, measurement=measurement, d_current=d_current, torques=torques)
    np.testing.assert_allclose(ctrl.voltages(t, x, true_acc(x, motor, torques, t)), v_ff, rtol=1e-11, atol=1e-11)
    s1, s2 = ctrl.sliding_variables(t, x, true_acc(x, motor, torques, t))
    assert np.max(np.abs(s1)) < 1e-14 and np.max(np.abs(s2)) < 1e-8


@pytest.mark.parametrize("measurement", ["ideal", "model"])
@pytest.mark.parametrize("torques", [TorqueModel(), TORQUES], ids=["eq1", "torques"])
def test_off_the_plan_the_law_imposes_the_sliding_dynamics(motor, plan, measurement, torques):
    """With the exact model: i_d' = Gamma1 and theta''' = Gamma2, so s1' = -W1 s1/(|s1|+eps1) and
    s2' = -W2 s2/(|s2|+eps2)."""
    rng = np.random.default_rng(5)
    n = 40
    t = rng.uniform(0.0, 0.06, n)
    x, _ = fs.flat_to_state(plan.flag(t), motor)
    x = x + np.array([0.02, -0.02, 0.5, 1e-3])[:, None] * rng.normal(size=(4, n))
    g = fs.SMCGains(W1=70.0, W2=300.0, eps1=0.01, eps2=0.2, xi=0.7, wn=40.0)
    ctrl = fs.DQFlatnessSMC(motor, plan, g, measurement=measurement, torques=torques)
    acc = true_acc(x, motor, torques, t)
    got = state_to_dq(x, ctrl.voltages(t, x, acc), motor, torques, t)
    ref = plan.flag(t)
    s1, s2 = ctrl.sliding_variables(t, x, acc)
    ds2 = (got.dddtheta - ref.dddtheta) + g.alpha2 * (got.ddtheta - ref.ddtheta) + g.alpha1 * (got.dtheta - ref.dtheta)
    np.testing.assert_allclose(got.di_d, -g.W1 * s1 / (np.abs(s1) + g.eps1), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ds2, -g.W2 * s2 / (np.abs(s2) + g.eps2), rtol=1e-7, atol=1e-5)
    assert np.max(np.abs(s2)) > 1.0  # off the plan indeed


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_c_step_matches_python(motor, plan, measurement):
    rng = np.random.default_rng(9)
    n = 200
    t = rng.uniform(0.0, 0.06, n)
    y = np.array([rng.normal(0, 0.4, n), rng.normal(0, 0.4, n), rng.normal(0, 3, n), rng.normal(0, 0.02, n),
                  rng.normal(0, 500, n)])
    d_current = fs.DCurrentPlan(0.1, -0.2, 0.01, 0.05, weakening=0.05, weakening_speed=0.8)
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, measurement, d_current=d_current, torques=TORQUES)
    bound = controller_struct(ctrl)
    v_c, v = np.empty(2), np.empty((2, n))
    for k in range(n):
        yk = np.ascontiguousarray(y[:, k])
        status = lib.dq_smc_step(bound.state, t[k], ffi.cast("double *", _in(yk)), ffi.cast("double *", _out(v_c)))
        assert status in (lib.CTRL_OK, lib.CTRL_SATURATED)
        v[:, k] = v_c
    v_py = ctrl.voltages(t, y[:4], y[4])
    inside = np.hypot(*v_py) < ctrl.c_v_limit
    assert inside.sum() > 100
    np.testing.assert_allclose(v[:, inside], v_py[:, inside], rtol=1e-12, atol=1e-12 * np.max(np.abs(v_py)))


RUNS = {  # name: (measurement, DriveLoop settings, plant effects, torque model)
    "14-bit, noise, load-ramp observer": ("observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)), None, None),
    "sensors, no observer": ("model", dict(sensors=NOISY), None, None),
    "bus saturation": ("observer", dict(sensors=Sensors(), observer=Observer(1500.0), drive=Drive(v_bus=2.5)),
                       None, None),
    "effects, torque model": ("observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)),
                              PlantEffects(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5), "plant"),
}


@pytest.mark.parametrize("name", RUNS)
def test_c_drive_loop_matches_the_reference(motor, plan, name):
    measurement, options, effects, torques = RUNS[name]
    perturbed = motor.replace(R=1.1 * motor.R, L=0.9 * motor.L, Km=0.9 * motor.Km, J=1.1 * motor.J, B=0.9 * motor.B)
    plant = fs.Plant(perturbed, effects=effects, load=1e-5)
    known = TorqueModel.of_plant(plant) if torques == "plant" else TorqueModel()
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, measurement, torques=known)
    loop = fs.DriveLoop(**{"control_period": TS, "substeps": 4, "drive": Drive(), **options})
    c = fs.simulate(plant, plan, ctrl, loop=loop, engine="c")
    py = fs.simulate(plant, plan, ctrl, loop=loop, engine="python")
    assert c.meta["engine"] == "c" and py.meta["engine"] == "python"
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    assert c.meta["controller_faults"] == py.meta["controller_faults"] == 0
    assert c.summary()["max_abs_theta_error_move"] < 3 * COUNT
    i_d = park(c.ia, c.ib, motor.Nr * c.theta)[0]
    assert np.max(np.abs(i_d[c.t >= plan.t0])) < 0.05  # every ampere in torque during the move


def test_continuous_run_on_both_engines(motor, plan):
    ctrl = fs.DQFlatnessSMC(motor, plan, fs.SMCGains(W1=300.0, W2=300.0), "ideal")
    c = fs.simulate(fs.Plant(motor, load=1e-5), plan, ctrl, engine="c")
    sp = fs.simulate(fs.Plant(motor, load=1e-5), plan, ctrl, engine="scipy")
    assert c.summary()["max_abs_theta_error_move"] < 1e-3
    np.testing.assert_allclose(c.theta, sp.theta, rtol=0, atol=1e-7)


def test_torques_off_reduce_to_the_plain_law_exactly(motor, plan):
    """A torque model with every amplitude 0 (other fields set) gives the plain law's run bit for bit."""
    off = TorqueModel(detent_harmonic=2, detent_phase=0.3, coulomb_speed=2.0, load_t0=0.5, load_tf=0.7)
    assert not off.active
    plant = fs.Plant(motor, effects=PlantEffects(detent_torque=1e-3), load=1e-5)
    for measurement, observer in (("observer", Observer(1500.0, 2)), ("model", None)):
        loop = fs.DriveLoop(TS, sensors=NOISY, observer=observer, drive=Drive(v_bus=24.0))
        runs = [fs.simulate(plant, plan, fs.DQFlatnessSMC(motor, plan, DESIGNED, measurement, torques=tm), loop=loop,
                            t_end=0.045) for tm in (TorqueModel(), off)]
        assert np.array_equal(runs[0].theta, runs[1].theta) and np.array_equal(runs[0].va, runs[1].va)


def test_registered_and_runnable_from_a_scenario_file(motor, plan, tmp_path):
    assert LABELS["dq_smc"].startswith("flatness")
    ctrl = make_controller("dq_smc", motor, plan, control_period=None, measurement="ideal", smc_gains=DESIGNED)
    assert isinstance(ctrl, fs.DQFlatnessSMC) and ctrl.gains == DESIGNED
    path = tmp_path / "dq.toml"
    path.write_text('[controller]\ntype = "dq_smc"\ndesign = true\n[drive]\ncontrol_rate = 20000.0\n'
                    '[sensors]\nencoder_counts = 16384\n[load]\ntorque = 1e-5\n')
    scenario, _ = load_scenario(path)
    r = scenario.run()
    assert isinstance(scenario.controller(), fs.DQFlatnessSMC) and r.status == "ok"
    assert r.summary()["max_abs_theta_error_move"] < 2 * COUNT
    path.write_text(path.read_text().replace("design = true\n", "design = true\nweakening = 0.05\n"
                                                                 "weakening_speed = 1.0\n"))
    weak = load_scenario(path)[0]
    assert weak.controller().d_current == fs.DCurrentPlan(weakening=0.05, weakening_speed=1.0)
    r = weak.run()
    assert np.min(park(r.ia, r.ib, motor.Nr * r.theta)[0]) < -0.03  # the field is weakened at speed


def test_the_feedforward_types_need_a_torque_model(motor, plan):
    with pytest.raises(ValueError, match="controller type 'dq_smc_ff' needs the torques"):
        make_controller("dq_smc_ff", motor, plan, control_period=TS, measurement="ideal", smc_gains=DESIGNED)
    known = make_controller("smc_ff", motor, plan, control_period=TS, measurement="ideal", torques=TORQUES)
    plain = make_controller("smc", motor, plan, control_period=TS, measurement="ideal", torques=TORQUES)
    assert known.torques == TORQUES and plain.torques == TorqueModel()
    assert all(LABELS[k].startswith("flatness") for k in ("dq_smc", "smc_ff", "dq_smc_ff"))


def test_a_feedforward_table_feeds_the_ff_types(tmp_path):
    body = ('[controller]\ntype = "dq_smc_ff"\ndesign = true\n[drive]\ncontrol_rate = 20000.0\n'
            '[sensors]\nencoder_counts = 16384\n[plant]\ndetent_torque = 2e-3\n[load]\ntorque = 1e-5\n')
    path = tmp_path / "ff.toml"
    path.write_text(body + "[feedforward]\ndetent_torque = 2e-3\nload = 1e-5\ncoulomb_speed = 0.1\n")
    scenario, _ = load_scenario(path)
    assert scenario.torques == TorqueModel(detent_torque=2e-3, load=1e-5, coulomb_speed=0.1)
    assert scenario.controller().torques == scenario.torques and "dq_smc_ff" in scenario_kinds(scenario)
    known = scenario.run().summary()["max_abs_theta_error_move"]
    plain = replace(scenario, controller_type="dq_smc").run().summary()["max_abs_theta_error_move"]
    assert known < plain
    path.write_text(body)
    with pytest.raises(ValueError, match="'dq_smc_ff' needs the torques"):
        load_scenario(path)
    path.write_text(body.replace("dq_smc_ff", "dq_smc"))
    assert "dq_smc_ff" not in scenario_kinds(load_scenario(path)[0])
    path.write_text(body + "[feedforward]\ndetent_amplitude = 1e-3\n")
    with pytest.raises(ValueError, match=r"ff.toml: unknown key\(s\) \['detent_amplitude'\] in \[feedforward\]"):
        load_scenario(path)


def test_compare_prints_the_new_rows_in_the_same_json_shape(tmp_path, capsys):
    from flatstep.cli.main import main

    path = tmp_path / "cmp.toml"
    path.write_text('t_end = 0.05\n[controller]\ndesign = true\n[drive]\ncontrol_rate = 20000.0\n'
                    '[sensors]\nencoder_counts = 16384\n[plant]\ndetent_torque = 1e-3\n[load]\ntorque = 1e-5\n'
                    '[feedforward]\ndetent_torque = 1e-3\nload = 1e-5\n'
                    '[robustness]\nrelative_error = 0.1\nsamples = 2\n')
    kinds = "cascade,dq_smc,dq_smc_ff,smc_la_ff,cascade_ff"
    assert main(["compare", str(path), "--controllers", kinds, "--json", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    for kind in kinds.split(","):
        assert report["controllers"][kind]["label"] == LABELS[kind]
        worst = report["robustness"]["worst"][kind]["metrics"]
        assert all(worst[k] > 0 for k in ("move_max", "copper_loss", "peak_voltage"))
    # the d-q law holds no d current: a fraction of the cascade's copper
    assert report["controllers"]["dq_smc"]["metrics"]["copper_loss"] < report["controllers"]["cascade"]["metrics"][
        "copper_loss"]
