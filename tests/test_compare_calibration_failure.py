"""``flatstep compare --calibrate-each``: from a scenario without [feedforward], and a failed calibration is a row."""
import json
from pathlib import Path

import pytest

import flatstep.studies.compare as compare_module
from flatstep.studies.compare import CALIBRATION_FAILED

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
ARGS = ["--controllers", "cascade,cascade_ff", "--calibrate-each", "--quiet", "--json"]


@pytest.fixture
def bare(tmp_path):
    """The NEMA 17 move with Km off by +-10 % (two plants) and no [feedforward] table at all."""
    text = (EXAMPLES / "compare-nema17-fast.toml").read_text()
    text = text[:text.index("# What the")].replace('parameters = ["R", "L", "Km", "J", "B"]', 'parameters = ["Km"]')
    assert "feedforward" not in text
    (tmp_path / "bare.toml").write_text(text)
    return tmp_path


def _failing(monkeypatch, where):
    """Make the calibration of the plants whose name contains ``where`` lose its move."""
    real = compare_module.calibrate_unit

    def calibrate(scenario, **kw):
        if where in scenario.name:
            raise ValueError(f"scenario {scenario.name!r}: the calibration move 1 of 2 (cascade) ended with status "
                             "'lost'")
        return real(scenario, **kw)

    monkeypatch.setattr(compare_module, "calibrate_unit", calibrate)


def test_calibrate_each_needs_no_feedforward_table(cli, bare):
    run = cli(["compare", "bare.toml", *ARGS], cwd=bare)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["controllers"]["cascade_ff"]["status"] == "ok"
    assert [c["Km"] > 0 for c in report["robustness"]["calibrations"]] == [True, True]
    assert report["robustness"]["worst"]["cascade_ff"]["statuses"]["ok"] == 2


def test_calibrate_each_with_clean(cli):
    run = cli(["compare", EXAMPLES / "compare-nema17-fast.toml", "--clean", "--no-robustness", *ARGS])
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["controllers"]["cascade_ff"]["status"] == "ok"


def test_a_plant_whose_calibration_fails_gets_that_status_and_the_rest_runs(cli, bare, monkeypatch):
    _failing(monkeypatch, "/calibration[Km+0.1]")
    run = cli(["compare", "bare.toml", *ARGS], cwd=bare)
    assert run.returncode == 5, run.stderr  # a row without a result (docs/comparison.md)
    report = json.loads(run.stdout)
    assert report["controllers"]["cascade_ff"]["status"] == "ok"  # the scenario's own plant calibrated fine
    worst = report["robustness"]["worst"]
    assert worst["cascade"]["statuses"]["ok"] == 2 and worst["cascade"]["failed"] == 0
    assert worst["cascade_ff"]["statuses"]["ok"] == 1 and worst["cascade_ff"]["failed"] == 1
    assert worst["cascade_ff"]["statuses"][CALIBRATION_FAILED] == 1
    assert worst["cascade_ff"]["failures"][0].startswith("calibration failed: scenario")
    assert worst["cascade_ff"]["metrics"]["move_max"] > 0  # the worst over the plant that ran
    calibrations = report["robustness"]["calibrations"]
    assert "error" in calibrations[0] and "Km+0.1" in calibrations[0]["plant"] and calibrations[1]["Km"] > 0


def test_the_scenario_plant_calibration_failing_is_a_row_too(cli, bare, monkeypatch):
    _failing(monkeypatch, "compare-nema17-fast")  # every calibration, the scenario's own first
    run = cli(["compare", "bare.toml", "--controllers", "cascade,cascade_ff", "--calibrate-each", "--quiet",
               "--no-robustness"], cwd=bare)
    assert run.returncode == 5, run.stderr
    assert "cascade + anti-cogging calibration_failed" in run.stdout and "cascaded PID (FOC) ok" in run.stdout
    assert "cascade + anti-cogging: did not run: calibration failed" in run.stderr
    assert "Traceback" not in run.stderr
