"""``flatstep plan FILE.toml`` (flatstep.cli.plan, flatstep.plan.plan_file) on every example plan file."""
import json
import sys
from pathlib import Path

import pytest

from flatstep.cli.main import main
from flatstep.plan.plan_file import load_plan_file

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
    assert main(["plan", str(path), "--out", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "plan.json").read_text())
    assert (tmp_path / "plan.png").stat().st_size > 10_000
    assert report["total_duration"] == pytest.approx(report["tf"] - report["t0"])
    assert sum(s["duration"] for s in report["steps"]) == pytest.approx(report["total_duration"], rel=1e-9)
    moves = [s for s in report["steps"] if s["step"].startswith("move")]
    waypoints = tomllib.loads(path.read_text())["plan"]["waypoints"]
    assert len(moves) == len(waypoints) - 1  # every move found, in order
    assert [s["step"] for s in moves] == [f"move {i} -> {i + 1}" for i in range(len(moves))]
    if "margins" in report:
        assert report["feasible"] and report["margins"]["worst"] <= 1.0
    out = capsys.readouterr().out
    assert "move 0 -> 1" in out and "plan.json" in out


def test_ten_waypoints_run_on_the_drive(tmp_path):
    path = next(p for p in EXAMPLES if "ten" in p.stem)
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
])
def test_bad_plan_files_are_refused(tmp_path, capsys, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["plan", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err or "preset" in err
    with pytest.raises(ValueError, match=match):
        load_plan_file(path)
