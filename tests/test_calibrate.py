import math
from dataclasses import replace
from pathlib import Path

import pytest

from flatstep.cli import main
from flatstep.model.plant import PlantEffects
from flatstep.model.torque_model import TorqueModel
from flatstep.studies.calibrate import calibrate, calibration_moves, merged_scenario
from flatstep.studies.calibrate_accuracy import TARGETS, accuracy, accuracy_table, calibration_errors, meets_targets
from flatstep.studies.robustness import perturbed
from flatstep.studies.scenario import Scenario
from flatstep.studies.scenario_file import Robustness, load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
NEMA = EXAMPLES / "compare-nema17-fast.toml"
PAPER = EXAMPLES / "compare-paper-20khz.toml"


def _plant(path, errors, detent, coulomb):
    """The file's scenario on one perturbed plant with the given detent and Coulomb friction, its table wrong."""
    sc, _ = load_scenario(path)
    sc = perturbed(sc, [errors])[0]
    effects = replace(sc.simulated_plant.effects, detent_torque=detent, coulomb_torque=coulomb)
    wrong = TorqueModel(detent_torque=5 * detent, coulomb_torque=3 * coulomb)  # the move must not read the table
    return replace(sc, plant=replace(sc.simulated_plant, effects=effects), torques=wrong)


@pytest.mark.parametrize("path, errors, detent, coulomb", [
    (NEMA, {"R": 0.1, "L": -0.1, "Km": -0.1, "J": 0.1, "B": -0.1}, 0.011, 0.006),
    (PAPER, {"R": -0.1, "L": 0.1, "Km": 0.1, "J": -0.1, "B": 0.1}, 1.3e-3, 1.5e-4),
])
def test_calibration_recovers_a_perturbed_plant_within_the_targets(path, errors, detent, coulomb):
    sc = _plant(path, errors, detent, coulomb)
    cal = calibrate(sc)
    err = calibration_errors(cal, sc.simulated_plant)
    assert abs(err["detent_torque"]) <= TARGETS["detent_torque"]
    assert abs(err["detent_phase"]) <= TARGETS["detent_phase"]
    assert abs(err["coulomb_torque"]) <= TARGETS["coulomb_torque"]
    assert abs(err["Km"]) <= 0.02  # the back EMF's Km, not the nominal one 10 % off
    assert abs(cal.torques.detent_torque / detent - 1) == pytest.approx(abs(err["detent_torque"]))
    assert cal.torques.load == pytest.approx(sc.simulated_plant.constant_load, rel=0.1)
    assert cal.std["detent_torque"] < 0.01 * detent
    assert cal.settings["controller"] == "cascade" and cal.settings["samples"] > 20000


def test_calibration_reads_the_sensors_not_the_plant_state():
    sc = _plant(NEMA, {"Km": 0.0}, 0.015, 0.004)
    rec, peak = calibration_moves(sc)
    count = 2 * math.pi / 16384
    steps = (rec.theta - rec.theta[0]) / count
    assert abs(steps - steps.round()).max() < 1e-6  # the encoder's counts
    assert peak == pytest.approx(0.25 * 0.25 * 0.3 * 20000 / (4 * 50))  # detent at omega_n / 4
    assert abs(rec.theta[-1] - rec.theta[0]) < 3 * count  # there and back


def test_merged_table_is_read_by_the_scenario_file(tmp_path):
    sc = _plant(PAPER, {"Km": 0.0}, 1e-3, 2e-4)
    cal = calibrate(sc, periods=12)
    text = PAPER.read_text()
    merged = merged_scenario(text, cal)
    assert merged.count("[feedforward]") == 1 and "What the \"_ff\" controller types know" not in merged
    assert "[robustness]" in merged and 'parameters = ["R", "L", "Km", "J", "B"]' in merged
    out = tmp_path / "calibrated.toml"
    out.write_text(merged)
    loaded, study = load_scenario(out)
    assert study is not None and loaded.plan == sc.plan
    for key in ("detent_torque", "detent_phase", "coulomb_torque", "load"):
        assert getattr(loaded.torques, key) == pytest.approx(getattr(cal.torques, key), rel=1e-5, abs=1e-12)
    bare = "\n".join(line for line in text.splitlines() if not line.startswith(("[feedforward]", "detent", "coulomb",
                                                                                "load =")))
    appended = tmp_path / "appended.toml"
    appended.write_text(merged_scenario(bare, cal))
    assert load_scenario(appended)[0].torques == loaded.torques


def test_accuracy_over_two_random_plants():
    sc, _ = load_scenario(NEMA)
    rows = accuracy(sc, Robustness(samples=2, seed=1), periods=12)
    assert len(rows) == 2 and all(meets_targets(rows).values())
    assert set(meets_targets(rows)) == set(TARGETS)
    table = accuracy_table(rows).splitlines()
    assert len(table) == 2 + 2 + 1 and table[-2].startswith("worst")


def _without(what):
    sc, _ = load_scenario(NEMA)
    if what == "drive":
        return Scenario("bare")
    return replace(sc, loop=replace(sc.loop, sensors=None, observer=None), measurement="model")


@pytest.mark.parametrize("what, message", [("drive", "no drive loop"), ("sensors", r"no \[sensors\]")])
def test_a_scenario_that_cannot_calibrate_is_refused(what, message):
    with pytest.raises(ValueError, match=message):
        calibrate(_without(what))


@pytest.mark.parametrize("kwargs, message", [
    ({"controller": "dq_smc_ff"}, "cannot run a calibration"), ({"periods": 0}, "periods"),
    ({"peak_speed": -1.0}, "peak_speed"), ({"coulomb_speed": 0.0}, "coulomb_speed"),
    ({"detent_harmonic": 2.5}, "detent_harmonic"),
])
def test_bad_settings_are_refused(kwargs, message):
    sc, _ = load_scenario(NEMA)
    with pytest.raises(ValueError, match=message):
        calibrate(sc, **kwargs)


def test_a_plant_without_detent_has_no_detent_error_column():
    sc, _ = load_scenario(NEMA)
    sc = replace(sc, plant=replace(sc.simulated_plant, effects=PlantEffects(coulomb_torque=0.004)))
    cal = calibrate(sc, periods=12)
    err = calibration_errors(cal, sc.simulated_plant)
    assert "detent_torque" not in err and "detent_phase" not in err
    assert cal.torques.detent_torque < 0.02 * 0.015  # nothing where the plant has nothing
    assert abs(err["coulomb_torque"]) <= TARGETS["coulomb_torque"]


def test_cli_calibrate_writes_a_table_compare_reads(tmp_path, capsys):
    table, merged = tmp_path / "ff.toml", tmp_path / "merged.toml"
    assert main(["calibrate", str(NEMA), "--out", str(table), "--merge", str(merged)]) == 0
    out = capsys.readouterr().out
    assert "[feedforward]" in out and f"wrote {table}" in out
    assert table.read_text() in merged.read_text()
    assert abs(load_scenario(merged)[0].torques.detent_torque / 0.015 - 1) < TARGETS["detent_torque"]


def test_cli_refuses_bad_inputs(tmp_path, capsys):
    assert main(["calibrate", str(EXAMPLES / "paper-fig1.toml")]) == 2
    assert "no drive loop" in capsys.readouterr().err
    assert main(["calibrate", str(NEMA), "--accuracy", "--out", str(tmp_path / "x.toml")]) == 2
    assert "writes no table" in capsys.readouterr().err
    assert main(["calibrate", str(tmp_path / "missing.toml")]) == 2
    assert "no such scenario file" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["compare-nema17-fast", "compare-paper-20khz"])
def test_the_calibrated_examples_are_what_calibrate_writes(name):
    source = EXAMPLES / f"{name}.toml"
    cal = calibrate(load_scenario(source)[0])
    calibrated = EXAMPLES / f"{name}-calibrated.toml"
    text, fresh = calibrated.read_text(), merged_scenario(source.read_text(), cal)
    assert text.split("[feedforward]")[0] == fresh.split("[feedforward]")[0]
    scenario, _ = load_scenario(calibrated)
    fresh_table = cal.torques.as_dict()
    for kind in ("dq_smc_ff", "cascade_ff"):  # the compare rows read the calibrated table
        read = replace(scenario, controller_type=kind).controller().torques.as_dict()
        assert set(read) == set(fresh_table)
        for key, value in read.items():
            # within 3 standard deviations of calibrate's own estimate (the fit's last digits move with the
            # numerical libraries' versions); keys calibrate does not estimate are equal
            tol = 3 * cal.std[key] if key in cal.std else 1e-12
            assert abs(value - fresh_table[key]) <= tol, (kind, key, value, fresh_table[key], tol)
