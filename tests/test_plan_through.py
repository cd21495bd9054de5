"""Time-optimal sequences through their via points (a plan file's ``through = true``)."""
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli.main import main
from flatstep.plan.limits import plan_margins
from flatstep.plan.plan_file import load_plan_file, runs
from flatstep.plan.waypoints import Waypoint

PLANS = Path(__file__).resolve().parents[1] / "examples" / "plans"
TEN = [Waypoint(0.0), Waypoint(2.0), Waypoint(5.0, dwell=0.02), Waypoint(4.0), Waypoint(10.0),
       Waypoint(0.5, dwell=0.01), Waypoint(1.0), Waypoint(-3.0), Waypoint(6.0), Waypoint(6.5)]


def test_a_run_ends_where_the_motion_reverses_dwells_or_ends():
    assert runs(TEN) == [(0, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 9)]
    assert runs([Waypoint(0.0), Waypoint(1.0)]) == [(0, 1)]
    assert runs([Waypoint(0.0), Waypoint(-1.0), Waypoint(-2.0), Waypoint(-1.5)]) == [(0, 2), (2, 3)]


def test_through_passes_the_via_points_at_speed_rests_elsewhere_and_is_faster():
    rest = load_plan_file(PLANS / "ten-waypoints.toml")
    through = load_plan_file(PLANS / "ten-waypoints-through.toml")
    assert through.plan.tf < rest.plan.tf - 5e-3
    assert [label for label, _, _ in through.steps][0] == "move 0 -> 2 (through 1)"
    t = np.linspace(through.plan.t0, through.plan.tf, 200001)
    theta, speed = through.plan.theta_deriv(t, 0), through.plan.theta_deriv(t, 1)
    for via, step in ((2.0, 0), (6.0, -1)):  # waypoints 1 and 8, in the first and the last move: crossed at speed
        _, start, duration = through.steps[step]
        inside = (t >= start) & (t <= start + duration)
        k = np.flatnonzero(np.diff(np.sign(theta[inside] - via)) != 0)
        assert k.size == 1 and abs(speed[inside][k[0]]) > 10.0
    for stop in (5.0, 4.0, 10.0, 0.5, 1.0, -3.0, 6.5):  # the rests: some sample sits there at (almost) no speed
        near = np.abs(theta - stop) < 1e-9
        assert near.any() and np.min(np.abs(speed[near])) < 1e-6
    m = plan_margins(through.plan, through.motor, through.limits)
    assert m["voltage"] <= through.limits.v_use and max(m["current"], m["torque_angle"]) <= 1.0


def test_through_runs_on_the_drive(tmp_path, capsys):
    assert main(["plan", str(PLANS / "ten-waypoints-through.toml"), "--out", str(tmp_path), "--simulate"]) == 0
    assert "move 7 -> 9 (through 8)" in capsys.readouterr().out


@pytest.mark.parametrize("text, match", [
    ('[plan]\nplanner = "psi"\nthrough = true\ndurations = [0.1]\nwaypoints = [0.0, 1.0]\n',
     "through = true is for the time_optimal planner"),
    ('[limits]\nv_bus = 24\ni_max = 1\n[plan]\nthrough = "yes"\nwaypoints = [0.0, 1.0]\n',
     "through='yes' must be true or false"),
    ('[limits]\nv_bus = 24\ni_max = 1\n[plan]\nthrough = true\nwaypoints = [0.0, {theta = 1.0, velocity = 3.0}, 2.0]\n',
     "chooses the speed at a waypoint"),
])
def test_bad_through_files_are_refused(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_plan_file(path)
