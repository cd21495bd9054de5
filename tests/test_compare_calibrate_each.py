"""The comparison with each unit calibrated: only the calibrated rows change, each plant gets its own table."""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli import main
from flatstep.studies.calibrate_accuracy import TARGETS, calibration_errors
from flatstep.studies.compare import KEEP, compare, compare_worst, unit_scenario
from flatstep.studies.robustness import perturbed, plant_errors
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).parent.parent / "examples"
KINDS = ("cascade", "microstep", "dq_smc_i_ff_km", "cascade_ff")


@pytest.fixture(scope="module")
def km_study():
    """The NEMA 17 move with only Km off (+-10 %): two plants whose back EMF differs by 20 %."""
    scenario, study = load_scenario(EXAMPLES / "compare-nema17-fast.toml")
    return scenario, replace(study, parameters=["Km"])


@pytest.fixture(scope="module")
def both(km_study):
    scenario, study = km_study
    return (compare_worst(scenario, study, KINDS, progress=False),
            compare_worst(scenario, study, KINDS, progress=False, calibrate="each"))


def test_only_the_rows_that_read_a_calibration_change(both):
    plain, each = both
    for kind in ("cascade", "microstep"):
        assert each[kind]["calibrations"] is None
        for a, b in zip(plain[kind]["rows"], each[kind]["rows"], strict=True):
            assert all(np.array_equal(a[f"series_{k}"], b[f"series_{k}"]) for k in KEEP), kind
        assert plain[kind]["worst"] == each[kind]["worst"]
    for kind in ("dq_smc_i_ff_km", "cascade_ff"):
        assert any(not np.array_equal(a["series_theta_error"], b["series_theta_error"])
                   for a, b in zip(plain[kind]["rows"], each[kind]["rows"], strict=True)), kind
    # one calibration per plant, shared by every type that reads it
    assert each["dq_smc_i_ff_km"]["calibrations"] is each["cascade_ff"]["calibrations"]
    assert len(each["cascade_ff"]["calibrations"]) == 2


def test_each_plant_gets_its_own_table(km_study, both):
    scenario, study = km_study
    units = both[1]["cascade_ff"]["calibrations"]
    plants = perturbed(scenario, plant_errors(study))
    kms = []
    for unit, plant_scenario in zip(units, plants, strict=True):
        plant = plant_scenario.simulated_plant
        err = calibration_errors(unit, plant)  # against this plant's own truth, as calibrate_accuracy does
        assert all(abs(err[k]) <= t for k, t in TARGETS.items()), (plant.motor.Km, err)
        assert abs(err["Km"]) < 5e-3, err
        run = unit_scenario(plant_scenario, unit)
        assert run.motor.Km == unit.estimates["Km"] and run.torques == unit.torques
        assert run.simulated_plant == plant and run.motor.R == scenario.motor.R
        kms.append(unit.estimates["Km"])
    assert kms[0] / kms[1] == pytest.approx(1.1 / 0.9, rel=1e-2)  # Km +10 % and -10 %: each found its own


def test_the_mode_is_refused_where_it_cannot_apply(km_study, tmp_path):
    scenario, study = km_study
    with pytest.raises(ValueError, match="calibrate='all'.*valid"):
        compare_worst(scenario, study, ["cascade_ff"], calibrate="all")
    with pytest.raises(ValueError, match=r"\['cascade', 'microstep'\] name none"):
        compare_worst(scenario, study, ["cascade", "microstep"], calibrate="each")
    no_sensors = replace(scenario, loop=replace(scenario.loop, sensors=None))
    with pytest.raises(ValueError, match=r"no \[sensors\]"):
        compare(no_sensors, ["cascade_ff"], calibrate="each")


def test_the_command_line_flag(km_study, tmp_path, capsys):
    text = (EXAMPLES / "compare-nema17-fast.toml").read_text()
    path = tmp_path / "km.toml"
    path.write_text(text.replace('parameters = ["R", "L", "Km", "J", "B"]', 'parameters = ["Km"]'))
    assert main(["compare", str(path), "--controllers", "cascade,cascade_ff", "--calibrate-each", "--json",
                 "--quiet"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["calibrate"] == "each" and rep["robustness"]["calibrate"] == "each"
    units = rep["robustness"]["calibrations"]
    assert len(units) == 2 and units[0]["Km"] > units[1]["Km"]
    assert all(u["feedforward"]["detent_torque"] == pytest.approx(0.015, rel=0.05) for u in units)
    assert main(["compare", str(path), "--controllers", "cascade", "--calibrate-each"]) == 2
    assert "--calibrate-each" in capsys.readouterr().err
    assert main(["compare", "--help"]) == 0
    assert "--calibrate-each" in capsys.readouterr().out


def test_the_calibration_horizon_is_what_the_moves_simulate(km_study):
    """The study limit counts each calibration by the time its moves simulate."""
    from flatstep.studies.calibrate import calibration_horizon, calibration_moves

    scenario, _ = km_study
    rec, _ = calibration_moves(scenario)
    period = scenario.loop.control_period
    assert calibration_horizon(scenario) == pytest.approx(rec.t[-1] - rec.t[0], abs=3 * period)
