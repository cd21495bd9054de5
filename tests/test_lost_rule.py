"""The lost rule for round trips and waypoint sequences: half the plan's *last* move, the same in Python and C."""
import json
import math
from dataclasses import replace

import numpy as np
import pytest

import flatstep as fs
from flatstep.engine.result import REST_TOLERANCE, arrival_error, last_move, rest_angles
from flatstep.studies.scenario_file import read_scenario_file as load_plan_file

STEP = math.pi / 100  # one full step of a 50-tooth rotor

PLAN_FILE = """name = "{name}"
[motor]
preset = "nema17"
[limits]
i_max = 1.0
[plan]
planner = "time_optimal"
t0 = 0.005
through = {through}
waypoints = {waypoints}
[drive]
control_rate = {rate}
v_bus = 24.0
[sensors]
encoder_counts = 16384
current_bits = 12
current_range = 2.0
[controller]
design = true
"""


def plan_file(tmp_path, name="trip", waypoints="[0.0, 0.5, 0.0]", rate=20000.0, through="false"):
    path = tmp_path / f"{name}.toml"
    path.write_text(PLAN_FILE.format(name=name, waypoints=waypoints, rate=rate, through=through))
    return path


@pytest.mark.parametrize("rests, expected", [
    ((0.0, 0.02), 0.01),                      # the paper's move: half of it, as before
    ((0.0, 0.5), STEP),                       # a long move: one full step
    ((0.1, 0.1), STEP),                       # no move at all
    ((0.0, 1.0, 0.0), STEP),                  # a round trip: its last move is 1 rad (the old rule: 0)
    ((0.0, 1.0, 1.0, -1.06e-21), STEP),       # the same with a dwell and the planner's rounding at the end
    ((0.0, 0.02, 0.0), 0.01),                 # a short round trip: half its last move
    ((0.0, 1.0, 1.0 + 1e-15, 0.99), 0.005),   # a short last move after a dwell whose ends differ by rounding
    ((0.0, 0.02, 0.02 + 1e-16), 0.01),        # a dwell at the end is no move
    ((5.0,), STEP),                           # one rest: no move
])
def test_arrival_error_takes_half_the_last_move(rests, expected):
    assert arrival_error(50, *rests) == pytest.approx(expected, rel=1e-12)


def test_the_old_rule_fails_a_round_trip():
    """Half of |theta2 - theta1| of a 0 -> 1 -> 0 plan is rounding (5e-22 rad); the last move is 1 rad."""
    assert 0.5 * abs(-1.06e-21 - 0.0) < 1e-20 and last_move([0.0, 1.0, -1.06e-21]) == pytest.approx(1.0)


def random_rests(rng, n):
    """Rest sequences with dwells (repeated angles, some off by rounding), round trips and large angles."""
    scale = rng.choice([1e-6, 0.02, 1.0, 1e3, 1e6])
    rests = list(rng.uniform(-scale, scale, size=n))
    for k in range(1, n):
        u = rng.uniform()
        if u < 0.3:
            rests[k] = rests[k - 1] * (1 + rng.choice([0.0, 1e-16, -3e-16]))  # a dwell
        elif u < 0.45:
            rests[k] = rests[0]  # back to the start
    return rests


def test_c_and_python_give_the_same_arrival_error():
    """The C twin (batch_arrival_error, csrc/batch.c) against the Python rule on 2000 sequences, bit for bit."""
    from flatstep._flatstep_core import ffi, lib

    rng = np.random.default_rng(7)
    cases = [random_rests(rng, int(rng.integers(1, 12))) for _ in range(2000)]
    cases += [[0.0, 1.0, 0.0], [0.0, 1.0, 1.0, -1.06e-21], [0.3, 0.3], [0.0, 1e-13], [1e6, 1e6 + 1e-7, 1e6]]
    for Nr in (1, 50, 200):
        for rests in cases:
            c = lib.batch_arrival_error(math.pi / (2 * Nr), ffi.new("double[]", rests), len(rests))
            assert c == arrival_error(Nr, *rests), rests


def test_c_rest_tolerance_is_pythons():
    text = open(__file__.replace("tests/test_lost_rule.py", "csrc/batch.h")).read()
    assert f"#define BATCH_REST_TOLERANCE {REST_TOLERANCE:g}" in text


def test_rest_angles_of_waypoint_plans(tmp_path):
    trip = load_plan_file(plan_file(tmp_path)).plan
    rests = rest_angles(trip)
    assert rests[0] == 0.0 and max(rests) == pytest.approx(0.5) and abs(rests[-1]) < 1e-12
    assert last_move(rests) == pytest.approx(0.5)
    stops = load_plan_file(plan_file(tmp_path, "stops", "[0.0, 0.3, 0.6]")).plan
    assert last_move(rest_angles(stops)) == pytest.approx(0.3)  # it rests at 0.3
    through = load_plan_file(plan_file(tmp_path, "through", "[0.0, 0.3, 0.6]", through="true")).plan
    assert last_move(rest_angles(through)) == pytest.approx(0.6)  # it passes 0.3 at speed: one move
    assert rest_angles(fs.PAPER_PLAN) == [0.0, 0.02]


def test_a_result_judges_a_round_trip_by_its_last_move(motor, plan):
    """A run whose rest angles are those of a 0.02 rad round trip: 5 mrad off at the end is kept, 12 mrad is lost."""
    r = fs.simulate(motor, plan, t_end=0.06)
    trip = {**r.meta["plan"], "theta2": -1.06e-21, "rests": [0.0, 0.02, -1.06e-21]}
    for off, status in ((0.005, "ok"), (0.012, "lost")):
        theta = r.theta_ref + np.where(r.t > plan.tf, off, 0.0)
        moved = replace(r, theta=theta, meta={**r.meta, "plan": trip})
        assert moved.status == status
    assert r.meta["plan"]["rests"] == [0.0, 0.02]


def test_batch_c_rows_match_per_run_rows_on_a_short_move():
    """C batch_sampled and Scenario.run give the same status on a move of half a step (the rule of its last move)."""
    base = fs.Scenario(loop=fs.DriveLoop(5e-5, drive=fs.Drive(v_bus=24.0)), measurement="model",
                       plan=replace(fs.PAPER_PLAN, theta2=0.01), gains=fs.SMCGains())
    runs = fs.scenario_grid(base, t_end=[0.04, 0.06])
    in_c = fs.run_batch(runs, workers=1, progress=False)
    per_run = fs.run_batch(runs, workers=1, progress=False, keep=("t",))
    assert [r["status"] for r in in_c] == [r["status"] for r in per_run]
    assert [r["lost_at"] for r in in_c] == [r["lost_at"] for r in per_run]


def test_simulate_and_plan_simulate_agree_on_a_kept_round_trip(cli, tmp_path):
    """0 -> 0.5 -> 0 on the 20 kHz drive is tracked to well under a step: ok and exit 0 in both commands (the old
    rule called it lost in 'simulate', exit 3, and ok in 'plan --simulate', exit 0)."""
    path = plan_file(tmp_path)
    sim = cli(["simulate", path, "--json", "--no-verify"], cwd=tmp_path)
    assert sim.returncode == 0, sim.stderr
    assert json.loads(sim.stdout[sim.stdout.index("{"):])["status"] == "ok"
    run = cli(["plan", path, "--simulate", "--out", "p"], cwd=tmp_path)
    tracking = json.loads((tmp_path / "p" / "plan.json").read_text())["tracking"]
    assert (run.returncode, tracking["status"], tracking["lost_at"]) == (0, "ok", None)


def test_simulate_and_plan_simulate_agree_on_a_lost_round_trip(cli, tmp_path):
    """The same trip on a 2 kHz drive loses its move: status lost, exit 3 and a warning in both commands."""
    path = plan_file(tmp_path, rate=2000.0)
    sim = cli(["simulate", path, "--json", "--no-verify"], cwd=tmp_path)
    run = cli(["plan", path, "--simulate", "--no-verify", "--out", "p"], cwd=tmp_path)  # unchecked: as simulate runs it
    tracking = json.loads((tmp_path / "p" / "plan.json").read_text())["tracking"]
    summary = json.loads(sim.stdout[sim.stdout.index("{"):])
    assert (sim.returncode, run.returncode) == (3, 3)
    assert summary["status"] == tracking["status"] == "lost" and summary["lost_at"] == tracking["lost_at"]
    assert "lost its move" in sim.stderr and "lost its move" in run.stderr


def test_the_plan_check_does_not_call_the_lost_trip_feasible(cli, tmp_path):
    """The trip that the 2 kHz drive loses is not reported feasible as it stands: refused, or backed off and kept."""
    path = plan_file(tmp_path, rate=2000.0)
    run = cli(["plan", path, "--simulate", "--out", "p"], cwd=tmp_path)
    report = json.loads((tmp_path / "p" / "plan.json").read_text())
    assert run.returncode in (0, 2), run.stderr
    if run.returncode == 0:
        assert report["tracking"]["status"] == "ok" and report["verify"]["backed_off"], report["verify"]
    else:
        assert not report["verify"]["verified"] and "binds" in run.stdout + run.stderr and "tracking" not in report


def test_simulate_refuses_the_trip_the_check_does_not_keep(cli, tmp_path):
    """simulate runs only what plan reports feasible: the trip the 2 kHz drive loses under the paper's law is
    refused, naming what binds (the default controller keeps a backed-off plan of it)."""
    path = plan_file(tmp_path, rate=2000.0)
    path.write_text(path.read_text().replace("design = true", 'law = "smc"\ndesign = true'))
    run = cli(["simulate", path], cwd=tmp_path)
    assert run.returncode == 2 and "the plan is not kept on the drive" in run.stderr and "binds" in run.stderr
    assert "--no-verify" in run.stderr and "status:" not in run.stdout  # the steps at most: nothing was run
