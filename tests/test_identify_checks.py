"""What the data cannot support is refused or flagged: units, ranges, the current noise's share, the residual."""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import flatstep.studies.identify as identify_module
from flatstep.studies.excitation import excite
from flatstep.studies.identify import identify
from flatstep.studies.identify_checks import (MAX_NOISE_SHARE, MAX_RESISTANCE_RATIO, TYPICAL, atypical,
                                              check_noise_share, check_resistance)
from flatstep.studies.identify_accuracy import preset_plant
from flatstep.studies.record import write_recording
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture(scope="module")
def rec():
    return excite(preset_plant(load_scenario(EXAMPLES / "nema17-20khz.toml")[0]), seed=3, current_noise=0.005)


def test_a_clean_recording_has_no_flags_and_a_small_noise_share(rec):
    result = identify(rec)
    assert result.flags == ()
    assert max(result.settings["noise_share"].values()) < 0.01 * MAX_NOISE_SHARE
    assert result.residual_rms["mechanical"] > 0


def test_voltages_in_hundreds_of_mv_are_flagged(cli, rec, tmp_path):
    """x300 stays inside every range (Km 80 V s/rad < 100) but not inside what stepping motors have."""
    write_recording(tmp_path / "mv.csv", replace(rec, va=300 * rec.va, vb=300 * rec.vb))
    run = cli(["identify", "mv.csv", "--json", "--out", "motor.toml"], cwd=tmp_path)
    assert run.returncode == 2, run.stderr  # printed and written with its flags, but not as fine
    flags = json.loads(run.stdout)["flags"]
    assert any(f.startswith("Km = 80.") and "are the voltages in mV?" in f for f in flags), flags
    assert any(f.startswith("R = 12") for f in flags), flags
    assert "flatstep: warning: mv.csv: Km = 80." in run.stderr
    assert "# flagged: Km = 80." in (tmp_path / "motor.toml").read_text()


def test_atypical_values_name_the_likely_unit():
    low, high = TYPICAL["R"]
    typical = {k: (lo * hi) ** 0.5 for k, (lo, hi) in TYPICAL.items()}
    assert atypical(typical) == ()
    assert "are the currents in mA" in atypical({**typical, "R": low / 2})[0]
    assert "are the voltages in mV" in atypical({**typical, "R": high * 2})[0]
    assert "are the currents in mA" in atypical({**typical, "J": TYPICAL["J"][1] * 2})[0]


def test_a_negative_km_has_a_positive_residual_and_is_refused(rec, monkeypatch):
    """theta's zero half an electrical period off flips Km's sign; the residual rms stays an rms."""
    half = replace(rec, theta=rec.theta + np.pi / 50)
    with pytest.raises(ValueError, match=r"Km = -0.26\d* V s/rad is below the range.*half an electrical period"):
        identify(half)
    monkeypatch.setattr(identify_module, "check_estimates", lambda *args: None)
    result = identify(half)
    assert result.estimates["Km"] < 0
    assert result.residual_rms["mechanical"] > 0
    assert result.residual_rms["mechanical"] == pytest.approx(identify(rec).residual_rms["mechanical"], rel=1e-6)


def test_the_noise_share_is_measured_and_refused_above_its_limit(rec):
    rng = np.random.default_rng(1)
    noisy = replace(rec, ia=rec.ia + rng.normal(0, 2.0, rec.ia.size), ib=rec.ib + rng.normal(0, 2.0, rec.ib.size))
    with pytest.raises(ValueError, match=r"the current noise makes up \d+% of the power of the filtered [RL]"):
        identify(noisy)
    check_noise_share({"R": 0.01, "L": MAX_NOISE_SHARE}, "x")
    with pytest.raises(ValueError, match="x: the current noise makes up 30% of the power of the filtered R"):
        check_noise_share({"R": 0.3, "L": 0.1}, "x")


def test_a_resistance_far_from_the_raw_ratio_is_refused(rec):
    R = identify(rec).estimates["R"]
    check_resistance(rec, R)
    with pytest.raises(ValueError, match=r"are the voltages in mV.*'va', 'vb' the applied voltages"):
        check_resistance(rec, R / (2 * MAX_RESISTANCE_RATIO))
    with pytest.raises(ValueError, match="are the currents in mA"):
        check_resistance(rec, R * 2 * MAX_RESISTANCE_RATIO)


def test_outputs_flatstep_wrote_may_be_replaced(cli, rec, tmp_path):
    write_recording(tmp_path / "rec.csv", rec)
    (tmp_path / "motor.toml").write_text("")  # empty: flatstep's to fill
    for _ in range(2):  # the second run replaces the table the first one wrote
        run = cli(["identify", "rec.csv", "--out", "motor.toml"], cwd=tmp_path)
        assert run.returncode == 0, run.stderr
    assert (tmp_path / "motor.toml").read_text().startswith("# identified from rec.csv")
