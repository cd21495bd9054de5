"""The journey on datasheet motors: 10 revolutions on 24 V, 20 kHz, 4000 counts; plan -> check -> simulate.

A plan ``flatstep plan`` reports verified must end ok when ``flatstep simulate`` runs it, with the same controller,
on the nominal plant and on every corner of +-10 % on R, L, Km and J; a refusal names what binds.
"""
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from drive_verified_plans import builtin_motors, file_motors, journey_file, study  # noqa: E402

from flatstep.studies.scenario_file import read_scenario_file  # noqa: E402

MOTORS = ROOT / "examples" / "motors"
#: A NEMA 14 (1.5 A), a NEMA 23 at 2.8 A and 0.7 ohm, and a NEMA 17 at 0.4 A and 30 ohm: the set's corners.
SAMPLE = ("ldo-35sth52-1504ah", "trinamic-qsh5718-41-28-055", "mosaic-42byg228")


def _assert_row(row):
    """A verified row kept its move on all 17 plants, in the check and in simulate; a refused one says what binds."""
    if row["status"] == "verified":
        assert row["bad"] == 0 and row["cases"] == 17 and row["duration"] > 0.5, row
        assert row["worst_error"] < 2 * math.pi / (4 * 50)  # within a full step
        assert row["simulate_runs"] == 17 and row["simulate_ok"] == 17, row["simulate_statuses"]
    else:
        assert row["binds"] and row["advice"], row


def test_journey_file_is_the_documented_journey(tmp_path):
    """The study's file: the datasheet [motor], limits for the drive, the time-optimal move, the drive, design."""
    name, table, i_max = file_motors([str(MOTORS / "trinamic-qsh5718-51-28-101.toml")])[0]
    assert i_max == pytest.approx(math.sqrt(2) * 2.8)
    path = tmp_path / "m.toml"
    path.write_text(journey_file(name, table, i_max))
    sf = read_scenario_file(path)
    assert sf.planner == "time_optimal" and sf.plan.theta2 - sf.plan.theta1 == pytest.approx(62.83)
    assert sf.control_rate == 20000.0 and sf.v_bus == 24.0 and sf.limits.speed_max == pytest.approx(60.0)
    assert sf.scenario.loop.sensors.encoder_counts == 4000 and sf.scenario.measurement == "observer"
    assert sf.motor.R == 0.83 and sf.motor.J == pytest.approx(275e-7)


def test_a_sample_runs_plan_then_simulate_on_every_corner():
    """Three datasheet motors through plan -> simulate on their 17 plants: every verified plan ends ok everywhere.

    Simulate runs the scenario the check returned (tests/test_verify.py runs 'flatstep simulate' itself on a plan
    'flatstep plan' verified; the slow study builds it as the command does, for every motor).
    """
    rows = study(file_motors([str(MOTORS / f"{m}.toml") for m in SAMPLE]), recheck=False)
    assert [r["status"] for r in rows] == ["verified"] * 3, rows
    for row in rows:
        _assert_row(row)
        assert row["controller"] == "smc (the file's gains, observer measurement)"


@pytest.mark.slow
def test_study_every_motor():
    """The study over every datasheet motor and the built-in three.

    No plan reported verified ends lost or faulted (in the check or in simulate on any corner); each refusal says
    what binds.
    """
    rows = study(file_motors(sorted(str(p) for p in MOTORS.glob("*.toml"))) + builtin_motors())
    for row in rows:
        _assert_row(row)
    assert sum(r["status"] == "verified" for r in rows) >= 20
