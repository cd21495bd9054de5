import math
import re
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli import main
from flatstep.loop.sensors import Sensors
from flatstep.model.motor import PRESETS
from flatstep.model.plant import Plant, PlantEffects
from flatstep.studies.excitation import excite
from flatstep.studies.identify import identify
from flatstep.studies.identify_accuracy import TARGETS, accuracy, accuracy_table, meets_targets, preset_plant
from flatstep.studies.identify_ls import fit
from flatstep.studies.record import COLUMNS, Recording, read_recording, recording_from_result, write_recording
from flatstep.studies.scenario_file import load_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SCENARIOS = {"paper": EXAMPLES / "drive-20khz-14bit.toml", "nema17": EXAMPLES / "nema17-20khz.toml"}


def scenario(preset):
    """The example drive of ``preset``, simulating the preset motor itself."""
    return preset_plant(load_scenario(SCENARIOS[preset])[0])


@pytest.fixture(scope="module")
def nema_recording():
    return excite(scenario("nema17"), seed=3, current_noise=0.005)


def test_recording_round_trip_and_sensor_readings(tmp_path, nema_recording):
    rec = nema_recording
    assert rec.t.size == 20001 and rec.period == pytest.approx(5e-5) and rec.duration == pytest.approx(1.0)
    sensors = scenario("nema17").loop.sensors
    counts = rec.theta / sensors.angle_step
    assert np.max(np.abs(counts - np.round(counts))) < 1e-6  # the encoder's count centres
    codes = rec.ia / sensors.current_step
    assert np.max(np.abs(codes - np.round(codes))) < 1e-6  # the ADC's codes
    assert np.ptp(rec.theta) > 10 * math.pi / 100  # the rotor moved over several full steps
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    assert path.read_text().splitlines()[0] == ",".join(COLUMNS)
    back = read_recording(path)
    for name in COLUMNS:
        np.testing.assert_allclose(getattr(back, name), getattr(rec, name), rtol=1e-11, atol=1e-14)


@pytest.mark.parametrize("edit, message", [
    (lambda lines: [lines[0].replace("ib,", "")] + [",".join(r.split(",")[:4] + r.split(",")[5:]) for r in lines[1:]],
     r"missing column\(s\) \['ib'\]"),
    (lambda lines: lines[:5] + [",".join(lines[5].split(",")[:3] + ["nan"] + lines[5].split(",")[4:])] + lines[6:],
     r"column 'ia' has a non-finite value nan in data row 5"),
    (lambda lines: lines[:150], r"149 rows is too short; a recording needs at least 200 rows"),
    (lambda lines: lines[:9] + lines[10:], r"column 't' must increase by a constant step; rows 8 -> 9"),
    (lambda lines: lines[:3] + ["0.1,a,b,c,d,e"] + lines[4:], r"not a CSV file of numbers"),
])
def test_bad_recordings_are_refused_naming_file_and_column(tmp_path, nema_recording, edit, message):
    path = tmp_path / "bad.csv"
    write_recording(path, nema_recording)
    path.write_text("\n".join(edit(path.read_text().splitlines())) + "\n")
    with pytest.raises(ValueError, match=message) as err:
        read_recording(path)
    assert str(path) in str(err.value)


def test_a_rotor_at_rest_is_not_exciting_enough():
    t = np.arange(4000) * 5e-5
    ia = 0.4 + 0.1 * np.sin(2 * np.pi * 30 * t)  # the current changes, the rotor does not move
    rec = Recording(t=t, va=8.4 * ia, vb=np.zeros_like(t), ia=ia, ib=np.zeros_like(t), theta=np.zeros_like(t),
                    source="rest.csv")
    with pytest.raises(ValueError, match=r"rest.csv: the recording does not excite \['Km'\].*not exciting enough"):
        identify(rec)


def test_one_move_is_not_exciting_enough():
    sc = replace(scenario("nema17"), t_end=1.0)  # one 25 ms move, then rest
    rec = recording_from_result(sc.run(), source="one-move.csv")
    # at a constant current norm L di/dt has the back-emf's shape: only Km + Nr i_d L is determined
    with pytest.raises(ValueError, match=r"one-move.csv: Km and L cannot be separated in this recording \(variance "
                                         r"inflation [\d.e+]+ > 300.*only Km \+ ([\d.]+) L = .*change the current norm"
                       ) as err:
        identify(rec)
    c = float(re.search(r"only Km \+ ([\d.]+) L", str(err.value)).group(1))
    assert c == pytest.approx(50 * 1.0, rel=0.05)  # Nr i_d: the hold's 1 A on the d axis


def test_collinear_regressors_are_named():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(500)
    X = np.column_stack([x, 2 * x + 1e-9 * rng.standard_normal(500), rng.standard_normal(500)])
    with pytest.raises(ValueError, match=r"ill-conditioned.*\['a', 'b'\] cannot be told apart"):
        fit([(X, x)], ["a", "b", "c"], lags=0, source="s", hint="h")


def test_covariance_allows_for_correlated_residuals():
    # AR(1) residuals with rho = 0.8 on a slowly varying regressor: the white-noise standard error is too small by
    # about sqrt((1 + rho) / (1 - rho)) = 3; the Bartlett window over 30 lags recovers most of it
    rng = np.random.default_rng(1)
    n, rho = 20000, 0.8
    e = np.zeros(n)
    w = rng.standard_normal(n)
    for k in range(1, n):
        e[k] = rho * e[k - 1] + w[k]
    x = np.sin(np.arange(n) * 2 * np.pi / 2000) + 0.5
    X = np.column_stack([x, np.ones(n)])
    white = fit([(X, 2 * x + e)], ["k", "c"], lags=0, source="s", hint="h")
    robust = fit([(X, 2 * x + e)], ["k", "c"], lags=30, source="s", hint="h")
    ratio = math.sqrt(robust.covariance[0, 0] / white.covariance[0, 0])
    assert 2.3 < ratio < 3.3
    assert abs(robust.values[0] - 2) < 4 * math.sqrt(robust.covariance[0, 0])


def test_bias_compensation_removes_the_attenuation_of_a_noisy_regressor():
    rng = np.random.default_rng(2)
    x = rng.standard_normal(20000)
    X = (x + 0.5 * rng.standard_normal(x.size))[:, None]  # the regressor measured with noise of variance 0.25
    plain = fit([(X, 2 * x)], ["k"], lags=0, source="s", hint="h")
    compensated = fit([(X, 2 * x)], ["k"], lags=0, source="s", hint="h", noise_gram=np.array([[x.size * 0.25]]))
    assert plain.values[0] == pytest.approx(2 / 1.25, rel=0.03)  # attenuated by var(x) / (var(x) + 0.25)
    assert compensated.values[0] == pytest.approx(2.0, rel=0.03)


def test_noise_compensation_on_a_noisy_drive():
    # 20 mA rms ADC noise on the paper's drive: plain least squares lowers L and raises Km
    sc = scenario("paper")
    recs = [excite(sc, seed=seed, current_noise=0.02) for seed in range(6)]
    plain = np.mean([identify(r, noise_compensation=False).errors(sc.motor)["Km"] for r in recs])
    compensated = np.mean([identify(r).errors(sc.motor)["Km"] for r in recs])
    assert plain > 0.01 and abs(compensated) < plain / 2


def test_exact_sensors_show_the_method_without_noise():
    sc = scenario("nema17")
    exact = replace(sc, loop=replace(sc.loop, sensors=replace(sc.loop.sensors, encoder_counts=None,
                                                              current_bits=None)))
    result = identify(excite(exact, seed=0))
    err = result.errors(sc.motor)
    assert max(abs(err[k]) for k in ("R", "L", "Km")) < 1e-3
    assert abs(err["J"]) < 5e-3 and abs(err["B"]) < 0.03
    assert result.estimates["load_torque"] == pytest.approx(1e-3, rel=0.02)


@pytest.mark.parametrize("preset", ["paper", "nema17"])
def test_targets_on_two_seeds(preset):
    rows = accuracy([scenario(preset)], seeds=[0, 1], current_noise=0.005)
    for row in rows:
        for name, target in TARGETS.items():
            assert abs(row["errors"][name]) <= target, (row["seed"], name, row["errors"][name])
        assert row["seconds"] < 5.0
    assert meets_targets(rows)
    assert "max|B|" in accuracy_table(rows)


@pytest.mark.slow
def test_targets_on_ten_seeds_and_both_presets():
    rows = accuracy([scenario("paper"), scenario("nema17")], seeds=range(10), current_noise=0.005)
    print(accuracy_table(rows))
    assert len(rows) == 20 and meets_targets(rows)


def test_detent_and_coulomb_on_request():
    sc = scenario("nema17")
    effects = PlantEffects(detent_torque=0.015, coulomb_torque=0.003)  # the datasheet's cogging, some friction
    sc = replace(sc, plant=Plant(sc.motor, effects=effects, load=1e-3))
    rec = excite(sc, seed=1, current_noise=0.005)
    plain = identify(rec)
    full = identify(rec, detent=True, coulomb=True)
    assert abs(plain.errors(sc.motor)["B"]) > 1.0  # without the effects, the friction lands on B
    assert abs(full.errors(sc.motor)["B"]) < 0.2 and abs(full.errors(sc.motor)["J"]) < 0.05
    assert full.estimates["detent_torque"] == pytest.approx(0.015, rel=0.05)
    assert abs(full.estimates["detent_phase"]) < 0.1
    assert full.estimates["coulomb_torque"] == pytest.approx(0.003, rel=0.2)


def test_motor_table_loads_into_a_scenario(tmp_path, nema_recording):
    result = identify(nema_recording)
    doc = tomllib.loads(result.as_toml())
    assert set(doc) == {"motor"} and doc["motor"]["Nr"] == 50
    assert doc["motor"]["Km"] == pytest.approx(result.estimates["Km"], rel=1e-5)
    path = tmp_path / "identified.toml"
    path.write_text(result.as_toml() + "\n[plan]\ntheta2 = 0.05\nrho1 = 1.0\nrho2 = 1.0\n")
    motor = load_scenario(path)[0].motor
    for name in ("R", "L", "Km", "J", "B"):
        assert getattr(motor, name) == pytest.approx(getattr(PRESETS["nema17"], name), rel=TARGETS[name])


def test_cli_identify_prints_and_writes(tmp_path, capsys, nema_recording):
    data, out = tmp_path / "data.csv", tmp_path / "motor.toml"
    write_recording(data, nema_recording)
    assert main(["identify", str(data), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "95% interval" in text and "R " in text and f"wrote {out}" in text
    assert tomllib.loads(out.read_text())["motor"]["R"] == pytest.approx(4.10, rel=0.01)
    data.write_text("t,va,vb,ia,theta\n0,1,2,3,4\n")
    assert main(["identify", str(data)]) == 2
    err = capsys.readouterr().err
    assert str(data) in err and "missing column(s) ['ib']" in err


def test_cli_excite_records_and_identifies(tmp_path, capsys):
    data = tmp_path / "data.csv"
    assert main(["identify", "--excite", str(SCENARIOS["paper"]), "--record", str(data), "--noise", "0.005",
                 "--duration", "0.5", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert "10001 samples" in out and "error" in out
    assert read_recording(data).t.size == 10001


def test_simulate_record_writes_what_the_drive_measured(tmp_path, capsys):
    data = tmp_path / "run.csv"
    assert main(["simulate", str(SCENARIOS["paper"]), "--record", str(data)]) == 0
    rec = read_recording(data)
    assert rec.t.size == 1201 and rec.period == pytest.approx(5e-5)
    q = Sensors(encoder_counts=16384).angle_step
    assert np.max(np.abs(rec.theta / q - np.round(rec.theta / q))) < 1e-6
    assert rec.theta[-1] == pytest.approx(0.02, abs=2 * q)
    capsys.readouterr()
    assert main(["simulate", "--record", str(tmp_path / "none.csv")]) == 2
    assert "needs a sampled drive" in capsys.readouterr().err
