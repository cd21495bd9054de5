"""The flat feedforward of any plan (flatstep.control.feedforward) and the cascade's voltage feedforward."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep.control.feedforward import reference
from flatstep.control.spec import ControllerSpec
from flatstep.model.motor import rhs
from flatstep.model.torque_model import TorqueModel
from flatstep.plan.d_current import DCurrentPlan

MOTOR = fs.MotorParams.preset("nema17")
PLAN = fs.RestToRest(0.0, 2.0, 1.0, 1.0, 0.005, 0.045)
TORQUES = TorqueModel(detent_torque=0.01, coulomb_torque=0.004, coulomb_speed=0.5, load=0.02)
T = np.linspace(0.0, 0.05, 401)
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("torques", [TorqueModel(), TORQUES])
def test_the_reference_satisfies_the_model_exactly(torques):
    """The phase-frame reference state and voltages make eq. (1) give the reference's own rates."""
    ref = reference(PLAN, MOTOR, T, torques=torques)
    load = torques.torque(T, ref.theta, ref.omega, MOTOR.Nr)
    dx = rhs(T, ref.state, ref.voltages, MOTOR)  # no load: E enters the acceleration below
    np.testing.assert_allclose(dx[:2], ref.current_rates, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref.current_rates)))
    np.testing.assert_allclose(dx[2] - load / MOTOR.J, ref.acceleration, rtol=1e-9, atol=1e-6)
    assert np.max(np.abs(ref.acceleration)) > 100.0
    np.testing.assert_allclose(ref.torque, MOTOR.J * ref.acceleration + MOTOR.B * ref.omega + load, rtol=1e-12)
    assert np.max(np.abs(ref.known_torque - load)) == 0.0


def test_the_current_rates_are_the_currents_derivative_and_the_frames_agree():
    d_current = DCurrentPlan(i_d1=0.2, i_d2=-0.1, t0=0.005, tf=0.045)
    ab = reference(PLAN, MOTOR, T, torques=TORQUES, d_current=d_current)
    dq = reference(PLAN, MOTOR, T, torques=TORQUES, frame="dq", d_current=d_current)
    h = 1e-7
    step = reference(PLAN, MOTOR, T + h, torques=TORQUES, d_current=d_current)
    back = reference(PLAN, MOTOR, T - h, torques=TORQUES, d_current=d_current)
    inside = (T > 0.006) & (T < 0.044)
    np.testing.assert_allclose(((step.currents - back.currents) / (2 * h))[:, inside], ab.current_rates[:, inside],
                               rtol=1e-4, atol=1e-3)
    p = MOTOR.Nr * ab.theta
    np.testing.assert_allclose(fs.control.loops.park(*ab.currents, p), dq.currents, atol=1e-12)
    np.testing.assert_allclose(fs.control.loops.park(*ab.voltages, p), dq.voltages, atol=1e-9)
    assert np.allclose(dq.currents[0], d_current.flag(T)[0]) and np.max(np.abs(dq.currents[1])) > 0.1


@pytest.mark.parametrize("kw, match", [(dict(frame="xy"), "frame='xy' is unknown"),
                                       (dict(torques=0.1), "torques=0.1 is not a TorqueModel")])
def test_bad_arguments_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        reference(PLAN, MOTOR, T, **kw)


def build(kind, **kw):
    return fs.make_controller(kind, MOTOR, PLAN, control_period=5e-5, measurement="model", v_limit=24.0,
                              torques=TORQUES, **kw)


def test_the_voltage_feedforward_adds_the_planned_q_current_voltage():
    off, on = build("cascade_ff"), build("cascade+feedforward+voltage_feedforward")
    assert on.gains.voltage_feedforward and not off.gains.voltage_feedforward
    y, t = np.array([0.3, -0.2, 40.0, 0.7, 0.0]), 0.02
    (v0, s0), (v1, s1) = off.step(None, y, t), on.step(None, y, t)
    ref = reference(PLAN, MOTOR, t, torques=TORQUES, frame="dq")
    dv = fs.control.loops.park(*(v1 - v0), MOTOR.Nr * y[3])
    expected = MOTOR.R * ref.currents[1] + MOTOR.L * ref.current_rates[1]
    assert abs(dv[0]) < 1e-12 and dv[1] == pytest.approx(float(expected), rel=1e-12) and abs(expected) > 0.1
    np.testing.assert_array_equal(s0, s1)


def test_the_option_names_and_its_laws():
    spec = ControllerSpec.parse("cascade_model+voltage_feedforward")
    assert spec == ControllerSpec("cascade", feedforward=True, observer_torques=True, voltage_feedforward=True)
    assert spec.label() == "cascaded PID (FOC), model obs.+v ff"
    with pytest.raises(ValueError, match="voltage_feedforward=true is not an option of law 'smc'"):
        ControllerSpec.parse("smc+voltage_feedforward")


def test_general_outer_gains_and_the_rule_as_default():
    rule = build("cascade").gains
    w = rule.position_bandwidth
    assert rule.loop_gains() == (w / 3, 2.25 * w, 0.75 * w**2)
    free = build("cascade", law_gains={"k_theta": 300.0, "ki_omega": 0.0})
    assert free.gains.loop_gains() == (300.0, 2.25 * w, 0.0)
    with pytest.raises(ValueError, match=r"k_omega=-1.0 must be > 0|k_omega=-1.0"):
        fs.CascadeGains(6000.0, 1500.0, k_omega=-1.0)
    with pytest.raises(ValueError, match="ki_omega=-1.0 1/s\\^2 must be >= 0"):
        fs.CascadeGains(6000.0, 1500.0, ki_omega=-1.0)
    with pytest.raises(ValueError, match=r"speed=1.0 is not a gain of this law \(CascadeGains\)"):
        build("cascade", law_gains={"speed": 1.0})
    with pytest.raises(ValueError, match="voltage_feedforward=True is not a gain of this law"):
        build("cascade", law_gains={"voltage_feedforward": True})  # the spec's option, not a gain


def test_the_current_loop_speed_is_a_gain_of_every_law():
    Ts = 5e-5
    assert build("cascade", lambda_ts=0.2).gains.current_bandwidth == pytest.approx(0.2 / Ts)
    assert build("microstep", lambda_ts=0.2).gains.current_bandwidth == pytest.approx(0.2 / Ts)
    assert build("exact_linearization", lambda_ts=0.2).gains.pd == pytest.approx(0.2 / Ts)
    for kind in ("smc", "dq_smc_i_ff"):
        g = build(kind, lambda_ts=0.2, smc_gains=fs.SMCGains(W1=50.0, W2=400.0)).gains
        assert g.W1 / g.eps1 == pytest.approx(0.2 / Ts) and g.W2 / g.eps2 == pytest.approx(0.2 / Ts)
    with pytest.raises(ValueError, match=r"lambda_ts=1.5 must be in \(0, 1\]"):
        build("cascade", lambda_ts=1.5)
    with pytest.raises(ValueError, match="control_rate"):
        fs.make_controller("smc", MOTOR, PLAN, control_period=None, measurement="ideal", lambda_ts=0.2)


FILE = "[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n[sensors]\nencoder_counts = 16384\n[controller]\n"


def test_a_scenario_file_gives_any_law_its_gains(tmp_path):
    from flatstep.studies.scenario_file import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(FILE + 'type = "cascade"\nvoltage_feedforward = true\n'.replace('type = "cascade"\n', 'law = "cascade"\n')
                    + "k_theta = 200.0\nlambda_ts = 0.25\n")
    sc = load_scenario(path)[0]
    ctrl = sc.controller()
    assert sc.controller_type == "cascade+voltage_feedforward" and ctrl.gains.k_theta == 200.0
    assert ctrl.gains.current_bandwidth == pytest.approx(0.25 * 20000.0) and ctrl.gains.voltage_feedforward
    assert replace(sc, controller_type="smc", lambda_ts=None).controller().gains == sc.gains  # cascade gains: its own
    path.write_text(FILE + 'type = "smc"\nk_theta = 200.0\n')
    with pytest.raises(ValueError, match=r"s.toml:controller.k_theta: k_theta is not a gain of law 'smc'"):
        load_scenario(path)
    path.write_text(FILE + 'type = "cascade"\nlambda_ts = 2.0\n')
    with pytest.raises(ValueError, match=r"s.toml:controller.lambda_ts: lambda_ts=2.0 must be in \(0, 1\]"):
        load_scenario(path)


def test_on_the_reference_the_exact_linearization_with_the_torques_is_the_flat_feedforward():
    """At the reference state the law's voltages are the feedforward of the same torques (model mode)."""
    ctrl = build("exact_linearization+feedforward")
    ref = reference(PLAN, MOTOR, T, torques=TORQUES)
    np.testing.assert_allclose(ctrl.voltages(T, ref.state), ref.voltages, rtol=1e-9, atol=1e-9)
    assert ctrl.observer_torques == TORQUES
    without = build("exact_linearization").voltages(T, ref.state)
    assert np.max(np.abs(without - ref.voltages)) > 0.1  # the torques matter


def test_the_back_emf_of_the_microstepping_driver():
    off, on = build("microstep"), build("microstep+back_emf")
    y, t = np.array([0.3, -0.2, 40.0, 0.7, 0.0]), 0.02
    (v0, s0), (v1, s1) = off.step(None, y, t), on.step(None, y, t)
    f = PLAN.flag(t)
    expected = MOTOR.Km * f.dtheta * np.array([-np.sin(MOTOR.Nr * f.theta), np.cos(MOTOR.Nr * f.theta)])
    np.testing.assert_allclose(v1 - v0, expected, rtol=1e-12)
    assert np.max(np.abs(expected)) > 0.1 and on.gains.back_emf and not off.gains.back_emf
    np.testing.assert_array_equal(s0, s1)


def test_the_load_angle_of_the_microstepping_driver():
    """Leading by the load angle puts the torque the plan needs on the q axis of the planned angle."""
    ctrl = build("microstep+load_angle")
    f = PLAN.flag(T)
    i_d, i_q = fs.control.loops.park(*ctrl.current_reference(T), MOTOR.Nr * f.theta)
    torque = MOTOR.J * f.ddtheta + MOTOR.B * f.dtheta
    inside = np.abs(torque) < MOTOR.Km * f.rho
    np.testing.assert_allclose((MOTOR.Km * i_q)[inside], torque[inside], rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(i_q)) > 0.05 and np.all(np.hypot(i_d, i_q) == pytest.approx(f.rho))
    h = 1e-7
    numeric = (ctrl.current_reference(T + h) - ctrl.current_reference(T - h)) / (2 * h)
    mid = (T > 0.006) & (T < 0.044)
    np.testing.assert_allclose(numeric[:, mid], ctrl.current_reference(T, 1)[:, mid], rtol=1e-4, atol=1e-2)
    plain = build("microstep").current_reference(T)
    assert np.max(np.abs(plain - ctrl.current_reference(T))) > 0.05


@pytest.mark.parametrize("kind, law_gains", [
    ("cascade+voltage_feedforward", None),
    ("exact_linearization+feedforward", {"p3": 3000.0}),
    ("microstep+back_emf+load_angle", None),
    ("cascade+feedforward+observer_torques+voltage_feedforward", {"k_theta": 900.0, "k_omega": 2000.0,
                                                                  "ki_omega": 1e5}),
])
def test_the_c_twin_matches_the_reference_with_the_new_options(kind, law_gains):
    from flatstep.studies.scenario_file import load_scenario

    scenario, _ = load_scenario(EXAMPLES / "compare-paper-20khz.toml")
    gains = {ControllerSpec.parse(kind).law: law_gains} if law_gains else None
    sc = replace(scenario, controller_type=kind, law_gains=gains, lambda_ts=0.25, t_end=scenario.plan.tf)
    c, py = sc.run("c"), sc.run("python")
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-8)
    assert c.meta["controller_faults"] == py.meta["controller_faults"] == 0
