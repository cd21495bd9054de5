"""Time-optimal sequences through their via points (a scenario file's ``[plan] through = true``)."""
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli.main import main
from flatstep.plan.margins import plan_margins
from flatstep.plan.sequence import runs
from flatstep.plan.waypoints import Waypoint
from flatstep.studies.scenario_file import read_scenario_file

PLANS = Path(__file__).resolve().parents[1] / "examples" / "plans"
TEN = [Waypoint(0.0), Waypoint(2.0), Waypoint(5.0, dwell=0.02), Waypoint(4.0), Waypoint(10.0),
       Waypoint(0.5, dwell=0.01), Waypoint(1.0), Waypoint(-3.0), Waypoint(6.0), Waypoint(6.5)]


def test_a_run_ends_where_the_motion_reverses_dwells_or_ends():
    assert runs(TEN) == [(0, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 9)]
    assert runs([Waypoint(0.0), Waypoint(1.0)]) == [(0, 1)]
    assert runs([Waypoint(0.0), Waypoint(-1.0), Waypoint(-2.0), Waypoint(-1.5)]) == [(0, 2), (2, 3)]


def test_through_passes_the_via_points_at_speed_rests_elsewhere_and_is_faster():
    rest = read_scenario_file(PLANS / "ten-waypoints.toml")
    through = read_scenario_file(PLANS / "ten-waypoints-through.toml")
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


HEAD = '[motor]\npreset = "nema17"\n[drive]\ncontrol_rate = 20000.0\nv_bus = 24\n[limits]\ni_max = 1\n'


@pytest.mark.parametrize("text, match", [
    (HEAD + '[plan]\nplanner = "psi"\nthrough = true\ndurations = [0.1]\nwaypoints = [0.0, 1.0]\n',
     "plan.through: the psi planner does not take through"),
    (HEAD + '[plan]\nplanner = "time_optimal"\nthrough = "yes"\nwaypoints = [0.0, 1.0]\n',
     "through='yes' must be true or false"),
    (HEAD + '[plan]\nplanner = "time_optimal"\nthrough = true\n'
     'waypoints = [0.0, {theta = 1.0, velocity = 3.0}, 2.0]\n', "chooses the speed at a waypoint"),
])
def test_bad_through_files_are_refused(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_scenario_file(path)
