"""``flatstep plan FILE.toml`` (flatstep.cli.plan, flatstep.studies.scenario_plan) on every example file."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli.main import main
from flatstep.model.motor import MotorParams
from flatstep.plan.sequence import runs
from flatstep.studies.scenario_file import read_scenario_file
from flatstep.studies.scenario_plan import _waypoint

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("plans/*.toml"))


def test_there_are_examples_of_every_kind():
    planners = {tomllib.loads(p.read_text())["plan"]["planner"] for p in EXAMPLES}
    assert {"time_optimal", "hermite", "scurve", "spline"} <= planners


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_plan_runs_on_every_example(path, tmp_path, capsys):
    assert main(["plan", str(path), "--out", str(tmp_path), "--no-verify"]) == 0
    report = json.loads((tmp_path / "plan.json").read_text())
    assert (tmp_path / "plan.png").stat().st_size > 10_000
    assert report["total_duration"] == pytest.approx(report["tf"] - report["t0"])
    assert sum(s["duration"] for s in report["steps"]) == pytest.approx(report["total_duration"], rel=1e-9)
    moves = [s for s in report["steps"] if s["step"].startswith("move")]
    sec = tomllib.loads(path.read_text())["plan"]
    waypoints = [_waypoint(path.name, i, w) for i, w in enumerate(sec["waypoints"])]
    # every move found, in order: one per waypoint, or one per run of them with through = true
    ends = runs(waypoints) if sec.get("through") else [(i, i + 1) for i in range(len(waypoints) - 1)]
    assert [s["step"].split(" (")[0] for s in moves] == [f"move {i} -> {j}" for i, j in ends]
    if "margins" in report:
        assert report["feasible"] and report["margins"]["worst"] <= 1.0
    out = capsys.readouterr().out
    assert f"move {ends[0][0]} -> {ends[0][1]}" in out and "plan.json" in out


def test_ten_waypoints_run_on_the_drive(tmp_path):
    path = next(p for p in EXAMPLES if p.stem == "ten-waypoints")
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate"]) == 0
    report = json.loads((tmp_path / "plan.json").read_text())
    tr = report["tracking"]
    assert len([s for s in report["steps"] if s["step"].startswith("move")]) == 9
    assert tr["max_abs_theta_error"] < 0.1 * tr["full_step"] and not tr["lost_step"]
    assert tr["peak_phase_voltage"] <= tr["v_bus"] and tr["controller_faults"] == 0


MOTOR = '[motor]\npreset = "nema17"\n'
DRIVE = "[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n"
TO = '[plan]\nplanner = "time_optimal"\nwaypoints = [0.0, 1.0]\n'


@pytest.mark.parametrize("text, match", [
    (MOTOR + TO, "the time_optimal planner plans against the motor's limits: give \\[limits\\]"),
    (MOTOR + '[plan]\nplanner = "bezier"\nwaypoints = [0.0, 1.0]\n', "planner='bezier'"),
    ('[plan]\nspeed = 3\n', "unknown key"),
    (MOTOR + DRIVE.replace("24.0", "-1") + "[limits]\ni_max = 1\n" + TO, "v_bus"),
    (MOTOR + '[plan]\nplanner = "psi"\nwaypoints = [0.0, 1.0]\n', "neither durations nor caps"),
    ('[motor]\npreset = "nema23"\n' + TO, "preset='nema23' is unknown"),
    (MOTOR + '[plan]\nplanner = "psi"\n', "the psi planner needs waypoints"),
    (MOTOR + DRIVE + "[limits]\ni_max = 1\n[plan]\nplanner = \"time_optimal\"\nwaypoints = ["
     + ", ".join(str(i % 2) for i in range(1002)) + "]\n",
     "1002 waypoint\\(s\\) are 1001 moves; a sequence has 1 to 1000"),
])
def test_bad_plan_files_are_refused(tmp_path, capsys, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["plan", str(path), "--out", str(tmp_path)]) == 2
    assert "bad.toml" in capsys.readouterr().err
    with pytest.raises(ValueError, match=match):
        read_scenario_file(path)


# ``flatstep simulate FILE.toml`` on a waypoint plan: its scenario on its drive, as ``plan --simulate`` runs it

SHORT = (MOTOR + DRIVE + "[sensors]\nencoder_counts = 16384\n[controller]\ndesign = true\n"
         "[limits]\ni_max = 1.0\ni_run = 0.1\nv_use = 0.87\n"
         '[plan]\nplanner = "time_optimal"\nt0 = 0.005\nwaypoints = [0.0, 1.0]\n')


def test_simulate_runs_the_ten_waypoints_end_to_end(tmp_path, capsys):
    path = next(p for p in EXAMPLES if p.stem == "ten-waypoints")
    assert main(["simulate", str(path), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "move 8 -> 9" in out and out.strip().endswith("status: ok")
    summary = json.loads((tmp_path / "summary.json").read_text())
    full_step = 2 * np.pi / (4 * MotorParams.preset("nema17").Nr)
    assert summary["status"] == "ok" and summary["controller_faults"] == 0
    assert abs(summary["theta_final"] - 6.5) < 0.1 * full_step  # the last waypoint
    assert summary["max_abs_theta_error"] < 0.1 * full_step
    assert max(summary["max_abs_va"], summary["max_abs_vb"]) <= 24.0  # the file's bus
    assert (tmp_path / "run.png").stat().st_size > 10_000 and (tmp_path / "run.csv").stat().st_size > 10_000


def test_simulate_a_plan_reports_a_lost_move(tmp_path, capsys):
    path = tmp_path / "short.toml"
    path.write_text(SHORT)
    assert main(["simulate", str(path), "--x0", "0", "0", "0", "0.5"]) == 3  # starts 0.5 rad off the plan
    captured = capsys.readouterr()
    assert captured.out.strip().endswith("status: lost") and "lost its move" in captured.err


def test_simulate_json_matches_the_plan_command(tmp_path, capsys):
    path = tmp_path / "short.toml"
    path.write_text("t_end = 0.3\n" + SHORT)
    assert main(["simulate", str(path), "--json", "--no-verify"]) == 0
    summary = json.loads(capsys.readouterr().out)  # JSON alone
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate", "--no-verify"]) == 0
    tracking = json.loads((tmp_path / "plan.json").read_text())["tracking"]
    assert tracking["control_rate"] == 20000.0
    assert summary["max_abs_theta_error"] == pytest.approx(tracking["max_abs_theta_error"], rel=1e-12)
    assert summary["theta_final"] == pytest.approx(1.0, abs=1e-3)


def test_simulate_runs_the_plan_that_plan_reports_feasible(tmp_path, capsys):
    """Checked on the drive by both commands: simulate runs the plan (backed off or not) that plan verified."""
    path = tmp_path / "short.toml"
    path.write_text("t_end = 0.3\n" + SHORT)
    assert main(["simulate", str(path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate"]) == 0
    report = json.loads((tmp_path / "plan.json").read_text())
    assert report["verify"]["verified"] and report["tracking"]["status"] == summary["status"] == "ok"
    assert summary["max_abs_theta_error"] == pytest.approx(report["tracking"]["max_abs_theta_error"], rel=1e-12)


@pytest.mark.parametrize("text, where", [
    (MOTOR + '[limits]\nv_bus = -1\ni_max = 1\n' + TO, "bad.toml:limits.v_bus: v_bus is an old name"),
    (MOTOR + DRIVE + '[limits]\ni_max = "1"\n' + TO, "bad.toml:limits.i_max"),
    (SHORT.replace("control_rate = 20000.0", "control_rate = -5"), "bad.toml:drive.control_rate"),
    (SHORT + '[simulate]\nt_after = 0.01\n', "bad.toml:simulate: simulate is an old name"),
    ("t_end = nan\n" + SHORT, "bad.toml:t_end"),
    (SHORT.replace('preset = "nema17"', 'preset = "nema17"\nR = -2.0'), "bad.toml:motor.R"),
    (MOTOR + '[plan]\nplanner = "psi"\ndurations = [0.05]\nwaypoints = [0.0, 1.0]\n[controller]\ntype = "pid"\n',
     "bad.toml:controller.type"),
    (MOTOR + DRIVE + '[limits]\ni_max = 1\n[plan]\nplanner = "psi"\nrho = 0.5\ndurations = [0.005]\n'
     'waypoints = [0.0, 5.0]\n', "bad.toml: the plan exceeds its limits (voltage"),
])
def test_simulate_refuses_a_bad_plan_file(tmp_path, capsys, text, where):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err
    assert where in err and "Traceback" not in err


def test_every_example_is_one_format():
    """Scenario and waypoint examples load through the one loader; the planner is what tells them apart."""
    scenarios = sorted((Path(__file__).parents[1] / "examples").glob("*.toml"))
    assert scenarios and all(read_scenario_file(p).planner == "rest_to_rest" for p in scenarios)
    assert {read_scenario_file(p).planner for p in EXAMPLES} == {"time_optimal", "hermite", "scurve", "spline"}


SCENARIOS = sorted((Path(__file__).parents[1] / "examples").glob("*.toml"))


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_plan_shows_every_scenario_example(path, tmp_path, capsys):
    from flatstep.plan.feasibility import check_feasibility
    from flatstep.studies.scenario_file import load_scenario

    assert main(["plan", str(path), "--out", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "plan.json").read_text())
    assert (tmp_path / "plan.png").stat().st_size > 10_000
    scenario, _ = load_scenario(path)
    plan, drive = scenario.plan, scenario.loop.drive if scenario.loop is not None else None
    assert report["steps"] == [dict(step=f"move {plan.theta1:g} -> {plan.theta2:g}", start=plan.t0,
                                    duration=pytest.approx(plan.tf - plan.t0))]
    load = scenario.plant.constant_load if scenario.plant is not None else 0.0
    check = check_feasibility(plan, scenario.motor, load_torque=load, v_max=drive.v_bus if drive else None)
    assert report["feasible"] and report["scenario"]["check"]["peak_voltage"] == pytest.approx(check.peak_voltage)
    assert report["scenario"]["v_bus"] == (drive.v_bus if drive else None)
    out = capsys.readouterr().out
    assert f"{check.torque_ratio:.3f} of Km rho*" in out and "plan.json" in out


def test_plan_simulates_the_papers_move_and_reports_an_infeasible_one(tmp_path, capsys):
    path = next(p for p in SCENARIOS if p.stem == "paper-fig1")
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate"]) == 0
    tracking = json.loads((tmp_path / "plan.json").read_text())["tracking"]
    assert tracking["control_rate"] is None and tracking["status"] == "ok" and not tracking["lost_step"]
    assert "in continuous time: max" in capsys.readouterr().out
    fast = tmp_path / "fast.toml"  # the paper's move in 0.1 ms: its torque demand passes Km rho*
    assert "tf = 0.04\n" in path.read_text()
    fast.write_text(path.read_text().replace("tf = 0.04\n", "tf = 0.0201\n"))
    assert main(["plan", str(fast), "--out", str(tmp_path)]) == 2
    out = capsys.readouterr().out
    assert "infeasible: torque demand exceeds Km rho*" in out and "no plan.png" in out
    assert not json.loads((tmp_path / "plan.json").read_text())["feasible"]


def test_the_papers_move_under_limits_shows_its_margins(cli, tmp_path):
    """rest_to_rest with [limits]: the margins of a waypoint plan, on the [drive] bus."""
    path = tmp_path / "r2r.toml"
    path.write_text("t_end = 0.1\n" + MOTOR + DRIVE + "[limits]\ni_max = 1.5\n[plan]\ntheta2 = 0.5\nrho1 = 1.0\n"
                    "rho2 = 1.0\nt0 = 0.01\ntf = 0.07\n[controller]\ndesign = true\n")  # the check runs this law
    run = cli(["plan", path, "--out", tmp_path / "o"])
    assert run.returncode == 0, run.stderr
    report = json.loads((tmp_path / "o" / "plan.json").read_text())
    assert report["limits"]["v_bus"] == 24.0 and report["limits"]["i_max"] == 1.5
    assert report["margins"]["current"] == pytest.approx(1.0 / 1.5) and report["feasible"]
    path.write_text(path.read_text().replace("i_max = 1.5", "i_max = 0.9\ni_hold = 0.2"))
    run = cli(["simulate", path])
    assert run.returncode == 2 and "r2r.toml: the plan exceeds its limits (current)" in run.stderr


def test_compare_on_a_waypoint_plan_runs_every_type(cli, tmp_path):
    path = next(p for p in EXAMPLES if p.stem == "spline")
    from flatstep.control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES
    from flatstep.studies.compare import scenario_kinds

    kinds = set(scenario_kinds(read_scenario_file(path).scenario))
    assert kinds == set(CONTROLLER_TYPES) - set(FEEDFORWARD_TYPES)  # no [feedforward]: the types without it
    run = cli(["compare", path, "--controllers", "cascade,smc"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "cascaded PID (FOC)" in run.stdout and "flatness + SMC" in run.stdout
