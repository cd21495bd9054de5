"""Every controller and every plant effect on the C engine against the Python references, closed loop.

The sampled loop: C ``sampled_run`` against :func:`flatstep.loop.reference.run_reference` on both comparison
scenarios (20 kHz drive, 14-bit encoder, 12-bit ADC, load, detent, Coulomb friction, the file's perturbed plant),
for every controller, within 1e-9 rad (measured: 1e-12 rad or better). The encoder quantizes, so a rounding
difference could move a reading across a count edge and the runs would then differ by a count; no run here
comes within rounding of an edge (tests/test_core_drive.py explains the odds), and a flip would fail loudly.
The continuous loop: C ``continuous_run`` against scipy's DOP853 for the static laws, with the plant effects.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCENARIOS = ("compare-paper-20khz.toml", "compare-nema17-fast.toml")


@pytest.mark.parametrize("kind", fs.CONTROLLER_TYPES)
@pytest.mark.parametrize("name", SCENARIOS)
def test_sampled_loop_matches_the_reference(name, kind):
    scenario, _ = load_scenario(EXAMPLES / name)
    sc = replace(scenario, controller_type=kind)
    assert sc.simulated_plant.effects is not None and sc.loop.sensors is not None
    c, py = sc.run("c"), sc.run("python")
    assert c.meta["engine"] == "c" and py.meta["engine"] == "python"
    np.testing.assert_array_equal(c.t, py.t)
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-8)
    np.testing.assert_allclose(c.meta["measured"]["theta"], py.meta["measured"]["theta"], rtol=0, atol=1e-9)
    assert c.meta["controller_faults"] == py.meta["controller_faults"] == 0


@pytest.mark.parametrize("kind", ["microstep", "cascade"])
def test_iron_loss_and_every_effect_match_the_reference(kind):
    """Iron loss (not in the comparison files) with detent and Coulomb friction, ideal sensors."""
    motor = fs.MotorParams.preset("nema17")
    plan = fs.RestToRest(0.0, 0.3, 1.0, 1.0, 0.005, 0.035)
    effects = fs.PlantEffects(detent_torque=0.015, coulomb_torque=0.004, coulomb_speed=0.05,
                              magnetizing_resistance=40.0, detent_harmonic=4)
    plant = fs.Plant(motor.replace(R=1.1 * motor.R), effects, load=0.01)
    ctrl = fs.make_controller(kind, motor, plan, control_period=5e-5, measurement="model", v_limit=24.0)
    loop = fs.DriveLoop(5e-5, 4, drive=fs.Drive(v_bus=24.0))
    c = fs.simulate(plant, plan, ctrl, loop=loop, t_end=0.05)
    py = fs.simulate(plant, plan, ctrl, loop=loop, t_end=0.05, engine="python")
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-8)
    without = fs.simulate(fs.Plant(plant.motor, load=0.01), plan, ctrl, loop=loop, t_end=0.05)
    assert np.max(np.abs(without.theta - c.theta)) > 1e-4  # the effects act


@pytest.mark.parametrize("kind", ["smc", "exact_linearization"])
def test_continuous_loop_runs_static_laws_with_effects(kind, motor, plan):
    """C continuous_run against scipy's DOP853 at the same tolerances, detent and Coulomb friction on."""
    gains = fs.SMCGains(W1=300.0, W2=300.0)
    ctrl = fs.make_controller(kind, motor, plan, control_period=5e-5, measurement="ideal", smc_gains=gains)
    plant = fs.Plant(motor, fs.PlantEffects(detent_torque=2e-4, coulomb_torque=1e-4, coulomb_speed=1.0), load=1e-5)
    solver = fs.Continuous(method="DOP853", rtol=1e-10, atol=1e-12, dt_out=1e-4, max_wall_time=300.0)
    c = fs.simulate(plant, plan, ctrl, solver=solver)
    ref = fs.simulate(plant, plan, ctrl, solver=solver, engine="scipy")
    assert c.meta["engine"] == "c" and ref.meta["engine"] == "scipy"
    np.testing.assert_allclose(c.theta, ref.theta, rtol=0, atol=1e-9)
    # Both solvers meet the tolerance, not each other bit for bit: the exact linearization's current loop
    # (L pd = 60 V/A) turns their 4e-6 A difference on the fast start-up transient into 2e-4 V (it shrinks
    # with rtol: 1.2e-5 V at 1e-12).
    np.testing.assert_allclose([c.va, c.vb], [ref.va, ref.vb], rtol=0, atol=5e-4)


@pytest.mark.parametrize("kind", ["microstep", "cascade"])
def test_laws_with_state_refuse_continuous_time(kind, motor, plan):
    ctrl = fs.make_controller(kind, motor, plan, control_period=5e-5, measurement="model")
    for engine in ("c", "scipy"):
        with pytest.raises(ValueError, match="once per control period"):
            fs.simulate(motor, plan, ctrl, engine=engine)


@pytest.mark.parametrize("hold", [1.0, 0.4])
def test_the_cascade_in_the_plan_frame_matches_the_reference(hold):
    """The cascade's plan_frame option (its currents in the plan's frame, a share of rho* held on d), C and Python."""
    scenario, _ = load_scenario(EXAMPLES / "compare-paper-20khz.toml")
    sc = replace(scenario, controller_type="cascade+feedforward+observer_torques+voltage_feedforward+plan_frame",
                 law_gains={"cascade": {"d_hold": hold}})
    ctrl = sc.controller()
    assert ctrl.gains.plan_frame and ctrl.gains.d_hold == hold
    c, py = sc.run("c"), sc.run("python")
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-8)
    t = c.t >= sc.plan.t0
    assert np.max(np.hypot(c.ia, c.ib)[t]) > 0.9 * hold * sc.plan.rho1  # the share of rho* is held
