"""Scenario files: the examples load and run, the paper's files are its scenarios, bad files name the key."""
from pathlib import Path

import pytest

import flatstep as fs
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_loads_and_runs(path):
    """Every example file loads, and its run ends within 2 mrad of the planned angle."""
    scenario, _ = load_scenario(path)
    s = scenario.run().summary()
    assert abs(s["theta_final"] - scenario.plan.theta2) < 2e-3


def test_paper_files_are_the_papers_scenarios():
    """The paper's Fig. 2 file is the paper's scenario: the same gains, plant, plan, motor and measurement."""
    fig2, study = load_scenario(EXAMPLES[0].parent / "paper-fig2.toml")
    ref = fs.PAPER_SCENARIOS["fig2"]
    assert (fig2.gains, fig2.simulated_plant, fig2.plan, fig2.motor, fig2.measurement) == (
        ref.gains, ref.simulated_plant, ref.plan, ref.motor, ref.measurement)
    assert fig2.simulated_plant.load == 1e-5
    assert study is None and fig2.control_period is None and fig2.loop is None


def test_realistic_drive_file():
    """The 20 kHz, 14-bit drive file gives its drive, sensors, observer, perturbed plant and study."""
    s, study = load_scenario(EXAMPLES[0].parent / "drive-20khz-14bit.toml")
    loop, plant = s.loop, s.simulated_plant
    assert s.control_period == loop.control_period == pytest.approx(5e-5) and loop.drive.v_bus == 24.0
    assert loop.sensors.encoder_counts == 16384 and loop.sensors.current_bits == 12
    assert s.measurement == "observer" and loop.observer is not None
    assert plant.motor.Km == pytest.approx(0.9 * s.motor.Km) and plant.motor.J == pytest.approx(1.1 * s.motor.J)
    assert study.samples == 0 and study.parameters == ("R", "L", "Km", "J", "B")


def test_the_count_edges_and_the_torque_ramp_from_a_file(tmp_path):
    """A file's edge_timing and torque_ramp reach the loop and change the run."""
    text = (EXAMPLES[0].parent / "compare-nema17-fast-weakening.toml").read_text()
    text = text.replace("[sensors]\n", "[sensors]\nedge_timing = true\n").replace(
        "[load]\n", "[observer]\ntorque_ramp = true\n\n[load]\n")
    s, _ = load_scenario(write(tmp_path, text))
    assert s.loop.sensors.edge_timing and s.loop.observer.torque_ramp
    assert s.loop.observer.bandwidth > 0 and s.measurement == "observer"  # the design's observer, the ramp added
    run = s.run()
    assert run.status == "ok"
    plain, _ = load_scenario(EXAMPLES[0].parent / "compare-nema17-fast-weakening.toml")
    assert not plain.loop.sensors.edge_timing and not plain.loop.observer.torque_ramp
    assert abs(run.theta[-1] - plain.run().theta[-1]) > 0  # the options reach the C loop


def write(tmp_path, text):
    """Write ``text`` to s.toml in ``tmp_path`` and return its path."""
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, match", [
    ("nmae = 'x'", r"unknown key\(s\) \['nmae'\] in the top level"),
    ("[motor]\nR = -1.0", r":motor.R: R=-1.0"),
    ("[motor]\npreset = 'nema99'", "preset='nema99' is unknown"),
    ("[plan]\ntheta3 = 1.0", r"unknown key\(s\) \['theta3'\] in \[plan\]"),
    ("[plan]\nrho1 = 0.0", r":plan.rho1: rho1=0.0"),
    ("[controller]\nW1 = 0", r":controller.W1: W1=0.0"),
    ("[controller]\nhold_damping = -0.7", r":controller.hold_damping: hold_damping=-0.7"),
    ("[sensors]\nencoder_counts = 16384", "control_rate is needed"),
    ("[drive]\ncontrol_rate = -5.0", "control_rate=-5.0"),
    ("[drive]\ncontrol_rate = 2e4\nv_bus = 0", r":drive.v_bus: v_bus=0"),
    ("[drive]\ncontrol_rate = 2e4\n[sensors]\ncurrent_bits = 1", "current_bits=1"),
    ("[plant]\nscale = { Nr = 2 }", "scale="),
    ("[robustness]\nparameters = ['R', 'Q']", r"robustness.parameters: parameters=\['R', 'Q'\] must be"),
    ("[robustness]\nrelative_error = 0.7", "relative_error=0.7"),
    ("[controller]\ndesign = true", "design = true needs"),
    ("t_end = = 1", "not valid TOML"),
])
def test_bad_files_name_the_key(tmp_path, text, match):
    """A bad file is refused with a ValueError naming the key at fault (or saying it is not valid TOML)."""
    with pytest.raises(ValueError, match=match):
        load_scenario(write(tmp_path, text))


def test_missing_file():
    """A file that does not exist is refused, saying so."""
    with pytest.raises(ValueError, match="no such scenario file"):
        load_scenario("nowhere.toml")
