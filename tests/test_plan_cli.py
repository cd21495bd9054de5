"""``flatstep plan FILE.toml`` (flatstep.cli.plan, flatstep.plan.plan_file) on every example plan file."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli.main import main
from flatstep.model.motor import MotorParams
from flatstep.plan.plan_file import _waypoint, is_plan_file, load_plan_file, runs

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


@pytest.mark.parametrize("text, match", [
    ('[plan]\nwaypoints = [0.0, 1.0]\n', "needs a \\[limits\\] section"),
    ('[plan]\nplanner = "bezier"\nwaypoints = [0.0, 1.0]\n', "planner='bezier'"),
    ('[plan]\nspeed = 3\n', "unknown key"),
    ('[limits]\nv_bus = -1\ni_max = 1\n[plan]\nwaypoints = [0.0, 1.0]\n', "v_bus"),
    ('[plan]\nplanner = "psi"\nwaypoints = [0.0, 1.0]\n', "neither durations nor caps"),
    ('[motor]\npreset = "nema23"\n[plan]\nwaypoints = [0.0, 1.0]\n', "unknown motor preset"),
    ('[plan]\nplanner = "psi"\n', "waypoints must be a list"),
    ('[limits]\nv_bus = 24\ni_max = 1\n[plan]\nwaypoints = [' + ", ".join(str(i % 2) for i in range(1002)) + "]\n",
     "1001 time-optimal moves, above the limit of 1000"),
])
def test_bad_plan_files_are_refused(tmp_path, capsys, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["plan", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err or "preset" in err
    with pytest.raises(ValueError, match=match):
        load_plan_file(path)


# ``flatstep simulate PLAN.toml``: the waypoint plan on the drive, through the same path as ``plan --simulate``

SHORT = "[limits]\nv_bus = 24.0\ni_max = 1.0\ni_run = 0.1\nv_use = 0.87\n[plan]\nt0 = 0.005\nwaypoints = [0.0, 1.0]\n"


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
    path.write_text(SHORT + "[simulate]\ncontrol_rate = 20000\nt_after = 0.01\n")
    assert main(["simulate", str(path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)  # JSON alone
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate", "--no-verify"]) == 0
    tracking = json.loads((tmp_path / "plan.json").read_text())["tracking"]
    assert tracking["control_rate"] == 20000.0
    assert summary["max_abs_theta_error"] == pytest.approx(tracking["max_abs_theta_error"], rel=1e-12)
    assert summary["theta_final"] == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("text, where", [
    ('[limits]\nv_bus = -1\ni_max = 1\n[plan]\nwaypoints = [0.0, 1.0]\n', "bad.toml:limits.v_bus"),
    ('[limits]\nv_bus = 24\ni_max = "1"\n[plan]\nwaypoints = [0.0, 1.0]\n', "bad.toml:limits.i_max"),
    (SHORT + '[simulate]\ncontrol_rate = -5\n', "bad.toml:simulate.control_rate"),
    (SHORT + '[simulate]\nt_after = nan\n', "bad.toml:simulate.t_after"),
    (SHORT + '[simulate]\nrate = 5\n', "unknown key(s) ['rate'] in [simulate]"),
    (SHORT + '[motor]\nR = -2.0\n', "bad.toml:motor.R"),
    ('[plan]\nplanner = "psi"\ndurations = [0.05]\nwaypoints = [0.0, 1.0]\n', "bad.toml:limits: a plan runs"),
    ('[limits]\nv_bus = 24\ni_max = 1\n[plan]\nplanner = "psi"\nrho = 0.5\ndurations = [0.005]\n'
     'waypoints = [0.0, 5.0]\n', "bad.toml: the plan exceeds its limits (voltage"),
])
def test_simulate_refuses_a_bad_plan_file(tmp_path, capsys, text, where):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err
    assert where in err and "Traceback" not in err


def test_plan_files_and_scenario_files_are_told_apart():
    scenarios = sorted((Path(__file__).parents[1] / "examples").glob("*.toml"))
    assert scenarios and not any(is_plan_file(p) for p in scenarios)
    assert all(is_plan_file(p) for p in EXAMPLES)
    assert not is_plan_file(Path(__file__).parents[1] / "no-such-file.toml")


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


def test_plan_on_a_scenario_refuses_simulate_and_reports_an_infeasible_move(tmp_path, capsys):
    path = next(p for p in SCENARIOS if p.stem == "paper-fig1")
    assert main(["plan", str(path), "--out", str(tmp_path), "--simulate"]) == 2
    assert "flatstep simulate" in capsys.readouterr().err
    fast = tmp_path / "fast.toml"  # the paper's move in 0.1 ms: its torque demand passes Km rho*
    assert "tf = 0.04\n" in path.read_text()
    fast.write_text(path.read_text().replace("tf = 0.04\n", "tf = 0.0201\n"))
    assert main(["plan", str(fast), "--out", str(tmp_path)]) == 2
    out = capsys.readouterr().out
    assert "infeasible: torque demand exceeds Km rho*" in out and "no plan.png" in out
    assert not json.loads((tmp_path / "plan.json").read_text())["feasible"]
