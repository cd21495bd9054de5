from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flatstep.studies.excitation import excite
from flatstep.studies.identify import identify
from flatstep.studies.identify_accuracy import preset_plant
from flatstep.studies.identify_coverage import cases, recording
from flatstep.studies.record import Recording
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture(scope="module")
def nema():
    return preset_plant(load_scenario(EXAMPLES / "nema17-20khz.toml")[0])


@pytest.fixture(scope="module")
def nema_recording(nema):
    return excite(nema, seed=3, current_noise=0.005)


def test_a_log_with_the_voltage_one_period_late_is_refused(nema_recording):
    result = identify(nema_recording)
    assert not result.flags and result.settings["alignment_rms"]["0"] == min(result.settings["alignment_rms"].values())
    cols = nema_recording.columns()
    late = Recording(**{**cols, "va": np.roll(cols["va"], 1), "vb": np.roll(cols["vb"], 1)}, source="late.csv")
    with pytest.raises(ValueError, match=r"late.csv: the voltage columns are shifted: the equations fit best with "
                                         r"'va', 'vb' read 1 period\(s\) later"):
        identify(late)


def test_a_dead_time_drive_is_flagged(nema):
    drive = replace(nema.loop.drive, pwm="switched", f_pwm=20000.0, dead_time=1e-6)  # 2 v_bus f_pwm t_d = 0.96 V
    rec = excite(replace(nema, loop=replace(nema.loop, drive=drive)), seed=3, current_noise=0.005)
    result = identify(rec)
    assert result.estimates["R"] > 1.2 * nema.motor.R  # what the dead time does to R
    (flag,) = result.flags
    vd = float(flag.split("a voltage of ")[1].split(" V")[0])
    assert vd == pytest.approx(0.96, rel=0.1) and "dead time" in flag


def test_an_unmodelled_detent_and_coulomb_friction_are_flagged():
    rec = excite(load_scenario(EXAMPLES / "nema17-cogging.toml")[0], seed=0, current_noise=0.005)
    flags = identify(rec).flags
    assert len(flags) == 2 and "give --detent" in flags[0] and "give --coulomb" in flags[1]
    assert float(flags[0].split("about ")[1].split(" N m")[0]) == pytest.approx(0.015, rel=0.1)
    assert identify(rec, detent=True, coulomb=True).flags == ()


def test_a_current_at_the_adc_full_scale_is_left_out():
    rec, plant = recording(cases(24)[23])  # a 4 rad move that saturates the bus and the +-2 A ADC
    assert np.max(np.abs(rec.ia)) == 2.0
    result = identify(rec, Nr=plant.motor.Nr)
    assert result.settings["clipped_samples"] > 100
    lo, hi = result.interval("R")
    assert lo <= plant.motor.R <= hi and abs(result.estimates["R"] / plant.motor.R - 1) < 0.005


def test_the_command_line_warns_of_a_left_out_effect_and_exits_2(cli, tmp_path):
    run = cli(["identify", "--excite", str(EXAMPLES / "nema17-cogging.toml"), "--record", "cog.csv", "--noise",
               "0.005", "--out", "motor.toml"], cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    warnings = [line for line in run.stderr.splitlines() if line.startswith("flatstep: warning: ")]
    assert len(warnings) == 2 and "give --detent" in warnings[0] and "give --coulomb" in warnings[1]
    toml = (tmp_path / "motor.toml").read_text()
    assert toml.count("# flagged: ") == 2 and "[motor]" in toml  # written, with the flags, for the user to judge
    clean = cli(["identify", "cog.csv", "--detent", "--coulomb"], cwd=tmp_path)
    assert clean.returncode == 0 and "detent_torque" in clean.stdout and not clean.stderr


def test_a_coarser_encoder_widens_the_electrical_intervals_through_its_steps(nema_recording):
    from flatstep.studies.identify_ls import fit
    from flatstep.studies.identify_quantization import electrical_quantization
    from flatstep.studies.identify_terms import electrical_blocks, filtered, kept_rows, moving_samples

    def km_variance(rec):
        moving = moving_samples(rec, 100.0)
        _, rows = filtered(rec, 200.0)
        keep = kept_rows(np.zeros(rec.t.size, dtype=bool), rows, rows.start)
        blocks, names, _, sos, rows = electrical_blocks(rec, 50, 200.0, True, moving, keep)
        result = fit(blocks, names, lags=8, source="s", hint="h")
        var = electrical_quantization(rec.theta, (rec.ia, rec.ib), 50, rec.period, sos, rows, keep, moving, blocks,
                                      result.values, result.gram)
        return var[2] / result.values[2] ** 2

    q = 2 * np.pi / 1024  # 16 times the 14-bit encoder's count
    coarse = replace(nema_recording, theta=q * np.round(nema_recording.theta / q))
    fine, rough = km_variance(nema_recording), km_variance(coarse)
    assert 0 < fine < 1e-6 and rough > 10 * fine  # (3e-4)^2 of Km at 14 bits; the steps' share grows with them
