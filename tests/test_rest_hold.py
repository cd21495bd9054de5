"""The detent hold with the known torques' load angle, and the ``smc_ff_hold`` row at rest on the paper's move.

docs/comparison.md ("At rest on the paper's move") and docs/drive.md (the hold) give the numbers these runs check.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep import core
from flatstep.control.tuning import LABELS, REST_HOLD_DAMPING
from flatstep.model.motor import torque
from flatstep.model.torque_model import NO_TORQUES
from flatstep.studies.compare import compare_worst
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HOLD = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500, hold_damping=0.7)
KNOWN = fs.TorqueModel(detent_torque=1e-3, detent_harmonic=4, coulomb_torque=2e-4, coulomb_speed=0.1, load=1e-5)
COUNT = 2 * np.pi / 16384


def test_hold_turns_the_current_by_the_known_load_angle(motor, plan):
    ctrl = fs.FlatnessSMC(motor, plan, HOLD, "model", torques=KNOWN)
    i_star = ctrl.hold_currents(0.0, plan.tf)
    assert np.hypot(*i_star) == pytest.approx(plan.rho2, rel=1e-14)
    E = KNOWN.torque(plan.tf, plan.theta2, 0.0, motor.Nr)  # the detent on theta2 and the load; no Coulomb at rest
    assert abs(E) > 5e-4
    assert torque([*i_star, 0.0, plan.theta2], motor) == pytest.approx(E, rel=1e-12)  # balances E on theta2...
    dth = 1e-6  # ...with the magnetic stiffness Km rho2 Nr cos(load angle) beside it
    stiffness = motor.Km * plan.rho2 * motor.Nr * np.sqrt(1 - (E / (motor.Km * plan.rho2)) ** 2)
    assert (torque([*i_star, 0.0, plan.theta2 + dth], motor) - E) / dth == pytest.approx(-stiffness, rel=1e-5)


def test_hold_follows_a_known_load_that_changes_in_time(motor, plan):
    step = fs.TorqueModel(load=1e-3, load_step=-2e-3, load_t0=plan.tf + 0.01, load_tf=plan.tf + 0.02)
    ctrl = fs.FlatnessSMC(motor, plan, HOLD, "model", torques=step)
    for t, load in ((plan.tf, 1e-3), (plan.tf + 0.03, -1e-3)):
        assert torque([*ctrl.hold_currents(0.0, t), 0.0, plan.theta2], motor) == pytest.approx(load, rel=1e-12)


@pytest.mark.parametrize("torques", [NO_TORQUES, fs.TorqueModel(detent_harmonic=3, coulomb_speed=0.5)],
                         ids=["none", "all zero"])
def test_hold_without_a_known_torque_is_the_detent_hold_bit_for_bit(motor, plan, torques):
    """No torque, or a model whose torque is 0: the hold of before, i* = rho2 (cos p, sin p) on Nr theta2."""
    omega = np.array([0.0, 1e-3, -0.2, 1e6])
    i_star = fs.FlatnessSMC(motor, plan, HOLD, "model", torques=torques).hold_currents(omega, plan.tf)
    s = np.clip(-2.0 * 0.7 * np.sqrt(motor.J * motor.Nr / (motor.Km * plan.rho2)) * omega, -1.0, 1.0)
    c = np.sqrt(1.0 - s * s)
    s2, c2 = np.sin(motor.Nr * plan.theta2), np.cos(motor.Nr * plan.theta2)
    np.testing.assert_array_equal(i_star, plan.rho2 * np.array([c2 * c - s2 * s, s2 * c + c2 * s]))
    x = np.array([[0.1, 0.2], [-0.3, 0.35], [0.5, -2.0], [plan.theta2 + 1e-3, plan.theta2 - 2e-4]])
    t = np.array([plan.tf, plan.tf + 0.01])
    v_none, _ = core.smc_voltages(fs.FlatnessSMC(motor, plan, HOLD, "model"), t, x, None, v_limit=1e6)
    v, _ = core.smc_voltages(fs.FlatnessSMC(motor, plan, HOLD, "model", torques=torques), t, x, None, v_limit=1e6)
    np.testing.assert_array_equal(v, v_none)


@pytest.mark.parametrize("torques", [NO_TORQUES, KNOWN, fs.TorqueModel(load=-3e-3, load_step=5e-3, load_t0=0.045,
                                                                       load_tf=0.05, detent_torque=2e-3, detent_phase=0.4)],
                         ids=["no torques", "paper file", "load change"])
def test_c_hold_matches_the_reference(motor, plan, torques):
    """smc_step's hold against FlatnessSMC.voltages, before and after tf, with the load angle of the torques."""
    ctrl = fs.FlatnessSMC(motor, plan, HOLD, "model", torques=torques)
    rng = np.random.default_rng(5)
    n = 400
    t = rng.uniform(plan.tf - 0.005, plan.tf + 0.02, n)
    x = np.array([rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-30, 30, n),
                  plan.theta2 + rng.uniform(-0.01, 0.01, n)])
    x[2, :20] = rng.uniform(-1e4, 1e4, 20)  # speeds where the damping torque is clipped
    v, status = core.smc_voltages(ctrl, t, x, None, v_limit=1e6)
    assert not status.any(), core.status_names(np.bitwise_or.reduce(status))
    held = t >= plan.tf
    assert 50 < held.sum() < n - 50
    ref = ctrl.voltages(t, x)
    np.testing.assert_allclose(v[:, held], ref[:, held], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(v[:, ~held], ref[:, ~held], rtol=1e-10)


def test_smc_ff_hold_is_smc_ff_with_the_hold(motor, plan):
    kw = dict(control_period=5e-5, measurement="observer", torques=KNOWN)
    hold = fs.make_controller("smc_ff_hold", motor, plan, smc_gains=replace(HOLD, hold_damping=None), **kw)
    assert hold.gains.hold_damping == REST_HOLD_DAMPING and hold.torques == KNOWN and hold.loss_aware is None
    assert fs.make_controller("smc_ff_hold", motor, plan, smc_gains=HOLD, **kw).gains.hold_damping == 0.7
    assert LABELS["smc_ff_hold"].startswith("flatness")
    with pytest.raises(ValueError, match="needs the torques"):
        fs.make_controller("smc_ff_hold", motor, plan, control_period=5e-5, measurement="observer")


def test_paper_move_rests_within_half_a_count_on_every_plant():
    """The 32 plants of compare-paper-20khz.toml: smc_ff hunts across the count edge beside theta* after the move;
    the same law with the hold from tf on settles into 1/2 count within 1 ms and stays, 1 count during the move."""
    scenario, study = load_scenario(EXAMPLES / "compare-paper-20khz.toml")
    half = COUNT / 2
    out = compare_worst(scenario, study, ["smc_ff", "smc_ff_hold"], band=half)
    hunt, hold = out["smc_ff"]["worst"], out["smc_ff_hold"]["worst"]
    assert out["smc_ff_hold"]["statuses"]["ok"] == 32
    assert hold["move_max"] == hunt["move_max"] <= COUNT  # the move is the law's, unchanged
    assert hold["settling_time"] is not None and hold["settling_time"] <= 1e-3
    assert hold["final"] <= 0.4 * COUNT
    assert hunt["settling_time"] is None or hunt["settling_time"] > 0.01


def test_the_hunting_at_rest_is_the_encoders():
    """The same 32 plants with an exact angle: the law alone rests within 0.1 count, so the half count it misses on
    the 14-bit encoder is the quantization's, not the law's."""
    scenario, study = load_scenario(EXAMPLES / "compare-paper-20khz.toml")
    loop = replace(scenario.loop, sensors=replace(scenario.loop.sensors, encoder_counts=None))
    out = compare_worst(replace(scenario, loop=loop), study, ["smc_la"], band=0.1 * COUNT)
    assert out["smc_la"]["worst"]["settling_time"] is not None and out["smc_la"]["worst"]["settling_time"] < 5e-3
