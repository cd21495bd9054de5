"""A plan the drive can follow: limits from the motor and the drive, the check on the drive, the back-off."""
import json
import math

import pytest

from flatstep.model.motor import MotorParams
from flatstep.plan.limits import COMMUTATION_ANGLE, HOLD_FRACTION, MotorLimits
from flatstep.plan.time_optimal import time_optimal
from flatstep.studies.backoff import plan_for_drive
from flatstep.studies.verify import ADVICE, drive_loop, plant_corners, verify_plan

RATE, COUNTS, V_BUS = 20000.0, 4000, 24.0
#: A common NEMA 17: 1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m holding, 68 g cm^2, 1.8 deg.
NEMA17 = MotorParams(R=1.65, L=2.8e-3, Km=0.44 / (math.sqrt(2) * 1.68), J=68e-7, B=1e-4, Nr=50)


def test_for_drive_rules():
    lim = MotorLimits.for_drive(NEMA17, v_bus=V_BUS, i_max=1.68, control_rate=RATE, encoder_counts=COUNTS)
    assert lim.i_hold == pytest.approx(HOLD_FRACTION * 1.68)
    assert lim.speed_corner == pytest.approx(1.65 / (50 * 2.8e-3))
    assert lim.v_use == pytest.approx(0.9 / 1.1)
    assert lim.speed_max == pytest.approx(COMMUTATION_ANGLE * RATE / 50)  # 60 rad/s: the commutation cap binds
    q = 2 * math.pi / COUNTS
    assert lim.torque_angle_max == pytest.approx(math.asin(0.9 * 0.9 / 1.1) - 50 * q / 2)
    # a faster drive allows a faster rotor; more uncertainty less bus
    assert MotorLimits.for_drive(NEMA17, v_bus=V_BUS, i_max=1.68, control_rate=40e3).speed_max == pytest.approx(120.0)
    assert MotorLimits.for_drive(NEMA17, v_bus=V_BUS, i_max=1.68, control_rate=RATE, uncertainty=0.2).v_use < lim.v_use


@pytest.mark.parametrize("kw, match", [(dict(uncertainty=0.6), "uncertainty=0.6"),
                                       (dict(encoder_counts=100), "encoder_counts=100"),
                                       (dict(control_rate=-1.0), "control_rate"),
                                       (dict(i_max=0.0), "i_max")])
def test_for_drive_refuses(kw, match):
    args = dict(v_bus=V_BUS, i_max=1.68, control_rate=RATE) | kw
    with pytest.raises(ValueError, match=match):
        MotorLimits.for_drive(NEMA17, **args)


def test_plant_corners():
    corners = plant_corners(NEMA17, 0.1)
    assert len(corners) == 17 and corners[0] == ({}, NEMA17)
    kms = sorted({round(m.Km / NEMA17.Km, 9) for _, m in corners[1:]})
    assert kms == [0.9, 1.1]
    assert len(plant_corners(NEMA17, 0.0)) == 1
    with pytest.raises(ValueError, match="uncertainty"):
        plant_corners(NEMA17, 0.5)


@pytest.mark.parametrize("motor, i_max, kept", [(NEMA17, 1.68, True), (MotorParams.preset("nema17"), 1.0, True),
                                                (MotorParams.preset("paper"), 1.0, None)])
def test_fastest_revolution_verified(motor, i_max, kept):
    """One revolution, as fast as the derived limits allow: verified means every plant ends ok (quick study).

    ``kept``: the motor is verified (True), or either verified or refused naming what binds (None: the paper's
    motor faults in the periods just after its move ends on every plant, which no slower plan cures).
    """
    loop = drive_loop(V_BUS, RATE, COUNTS)
    lim = MotorLimits.for_drive(motor, v_bus=V_BUS, i_max=i_max, control_rate=RATE, encoder_counts=COUNTS)
    plan, final, verdict = plan_for_drive(lambda lm: time_optimal(2 * math.pi, motor, lm, t0=0.005), motor, lim, loop)
    assert len(verdict.cases) == 17 and 1 <= len(verdict.rounds) <= 4
    if kept or plan is not None:
        assert plan is not None and verdict.verified and verdict.status == "ok"
        assert all(c.status == "ok" for c in verdict.cases)
        assert verdict.worst_error < math.pi / 100  # well within a full step
        assert final.speed_max <= lim.speed_max
    else:
        assert not verdict.verified and verdict.binds in ADVICE
        assert all(r["status"] != "ok" for r in verdict.rounds)


def test_documented_limits_are_refused_with_what_binds():
    """The defaults (tuned to the presets) lose this motor's move on the drive; the check says so and why."""
    lim = MotorLimits(v_bus=V_BUS, i_max=1.68)
    plan = time_optimal(3.0, NEMA17, lim, t0=0.005)
    verdict = verify_plan(plan, NEMA17, drive_loop(V_BUS, RATE, COUNTS), limits=lim)
    assert not verdict.verified and verdict.status in ("lost", "fault")
    assert verdict.binds in ADVICE and verdict.advice == ADVICE[verdict.binds]
    assert verdict.as_dict()["cases"][0]["plant"] == "nominal"


MOVE = """name = "one revolution"
[motor]
R = 1.65
L = 2.8e-3
Km = 0.18518
J = 6.8e-6
Nr = 50
[limits]
i_max = 1.68
{extra}
[plan]
planner = "time_optimal"
t0 = 0.005
waypoints = [0.0, 6.2832]
[drive]
control_rate = 20000.0
v_bus = 24.0
[sensors]
encoder_counts = 16384
{controller}"""
DESIGNED = "[controller]\ntype = \"smc\"\ndesign = true\n"
DERIVED = "i_hold = 0.504\nspeed_corner = 11.79\ntorque_angle_max = 0.8181\nv_use = 0.8182\nspeed_max = 60.0"


def test_cli_json_verified(cli, tmp_path):
    (tmp_path / "move.toml").write_text(MOVE.format(extra=DERIVED, controller=DESIGNED))
    run = cli(["plan", "move.toml", "--json"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["duration"] == pytest.approx(report["tf"] - report["t0"]) and report["duration"] > 0.1
    assert report["verify"]["verified"] and len(report["verify"]["cases"]) == 17
    assert {c["status"] for c in report["verify"]["cases"]} == {"ok"}
    assert "verified on the drive" in run.stderr
    # the check ran the file's own law on its drive: the designed sliding law through its observer
    assert report["verify"]["controller"] == "smc (the file's gains, observer measurement)"
    assert report["verify"]["plants"] == "17 plants (nominal and +-10 % on R, L, Km, J)"
    assert report["verify"]["worst_error"] == max(c["max_abs_theta_error"] for c in report["verify"]["cases"])
    # and 'flatstep simulate' runs that plan with that law: it ends ok
    sim = cli(["simulate", "move.toml"], cwd=tmp_path)
    assert sim.returncode == 0 and "status: ok" in sim.stdout, sim.stdout + sim.stderr


def test_cli_checks_the_files_controller(cli, tmp_path):
    """The paper's law on its default gains: the drive loses the move and the refusal says to design."""
    (tmp_path / "move.toml").write_text(MOVE.format(extra=DERIVED, controller='[controller]\ntype = "smc"\n'))
    run = cli(["plan", "move.toml", "--json"], cwd=tmp_path)
    report = json.loads(run.stdout)
    assert run.returncode == 2 and not report["feasible"] and not report["verify"]["verified"]
    assert report["verify"]["controller"] == "smc (default gains, model measurement)"
    assert "[controller] design = true" in report["verify"]["advice"] and "binds" in run.stderr
    sim = cli(["simulate", "move.toml"], cwd=tmp_path)  # simulate refuses what plan refuses, before any run
    assert sim.returncode == 2 and "design = true" in sim.stderr


def test_cli_uncertainty_from_limits(cli, tmp_path):
    """[limits] uncertainty sets the corners the check runs (0: the plant only); out of range is bad input."""
    (tmp_path / "move.toml").write_text(MOVE.format(extra=DERIVED + "\nuncertainty = 0.0", controller=DESIGNED))
    report = json.loads(cli(["plan", "move.toml", "--json"], cwd=tmp_path).stdout)
    assert report["verify"]["plants"] == "1 plant (nominal)" and len(report["verify"]["cases"]) == 1
    assert report["verify"]["uncertainty"] == 0.0 and report["limits"]["uncertainty"] == 0.0
    (tmp_path / "bad.toml").write_text(MOVE.format(extra="uncertainty = 0.6", controller=DESIGNED))
    bad = cli(["plan", "bad.toml"], cwd=tmp_path)
    assert bad.returncode == 2 and "limits.uncertainty" in bad.stderr and "0.6" in bad.stderr


def test_cli_refuses_or_backs_off_and_no_verify(cli, tmp_path):
    (tmp_path / "move.toml").write_text(MOVE.format(extra="", controller=DESIGNED))
    run = cli(["plan", "move.toml", "--json"], cwd=tmp_path)
    report = json.loads(run.stdout)
    v = report["verify"]
    if run.returncode == 0:  # backed off to a plan every plant keeps
        assert v["verified"] and v["backed_off"] and v["rounds"][0]["status"] != "ok"
    else:
        assert run.returncode == 2 and not v["verified"] and v["binds"] in ADVICE and "binds" in run.stderr
    skipped = cli(["plan", "move.toml", "--no-verify"], cwd=tmp_path)
    assert skipped.returncode == 0 and "not verified on the drive (--no-verify)" in skipped.stdout


def test_cli_without_controller_runs_the_default_law(cli, tmp_path):
    """Without [controller] a file with a drive runs the default law, the cascade with the flat voltage feedforward."""
    (tmp_path / "move.toml").write_text(MOVE.format(extra=DERIVED, controller=""))
    run = cli(["plan", "move.toml", "--json"], cwd=tmp_path)
    report = json.loads(run.stdout)
    assert report["verify"]["controller"].startswith("cascade+voltage_feedforward")
    assert run.returncode == 0 and report["verify"]["verified"], run.stderr
