import json
from concurrent.futures import ThreadPoolExecutor

import pytest

import flatstep as fs
from flatstep.studies.batch import run_batch, scenario_grid
from flatstep.loop.drive import Drive
from flatstep.loop.sensors import Sensors
from flatstep.studies.scenario import Scenario

SAMPLED = Scenario("s", control_period=5e-5, substeps=4, measurement="model",
                   gains=fs.SMCGains(W1=150, W2=3e5, eps1=0.0375, eps2=75, xi=0.9, wn=400))


def test_grid_and_order_and_values_match_single_runs():
    grid = scenario_grid(SAMPLED, load_torque=[0.0, 2e-5], control_period=[5e-5, 2.5e-5])
    assert len(grid) == 4 and grid[1].control_period == 2.5e-5 and grid[2].load_torque == 2e-5
    rows = run_batch(grid, workers=2, chunk_size=1)
    assert [r["index"] for r in rows] == [0, 1, 2, 3] and all(r["error"] is None for r in rows)
    for row, scenario in zip(rows, grid):
        assert row["theta_final"] == scenario.run().summary()["theta_final"]
    assert rows[0]["theta_final"] != rows[2]["theta_final"]  # the load changed something


def test_any_executor_and_failures_are_rows():
    bad = Scenario("fast", plan=fs.RestToRest(0.0, 0.05, 0.4, 0.4, 0.02, 0.022))
    with ThreadPoolExecutor(2) as ex:
        rows = run_batch([SAMPLED, bad], executor=ex)
    assert rows[0]["error"] is None
    assert rows[1]["error"].startswith("InfeasiblePlanError") and "theta_final" not in rows[1]


def test_results_are_written_as_they_go_and_a_rerun_resumes(tmp_path):
    out = tmp_path / "rows.jsonl"
    grid = scenario_grid(SAMPLED, load_torque=[0.0, 1e-5, 2e-5])
    run_batch(grid[:2], out=out, workers=1)
    lines = [json.loads(x) for x in out.read_text().splitlines()]
    assert [r["index"] for r in lines] == [0, 1]
    out.write_text(out.read_text() + '{"index": 2, "theta_fi')  # a line cut by an interruption
    rows = run_batch(grid, out=out, workers=1)
    assert [r["index"] for r in rows] == [0, 1, 2] and rows[2]["error"] is None
    indices = [json.loads(x)["index"] for x in out.read_text().splitlines()[3:]]
    assert indices == [2]  # only the missing run was done again


def test_progress_bar_goes_to_stderr(capsys):
    run_batch([SAMPLED] * 3, progress=True, workers=1)
    assert "3/3 runs" in capsys.readouterr().err


@pytest.mark.parametrize("kwargs, match", [
    (dict(workers=0), "workers=0"), (dict(chunk_size=-1), "chunk_size=-1"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        run_batch([SAMPLED], **kwargs)
    with pytest.raises(ValueError, match="is not a flatstep Scenario"):
        run_batch([SAMPLED, "fig1"])
    with pytest.raises(ValueError, match="unknown scenario field"):
        scenario_grid(SAMPLED, W2=[1.0])


@pytest.mark.parametrize("change, plain", [
    (dict(), True), (dict(control_period=None), False), (dict(compute_delay=True), False),
    (dict(sensors=Sensors()), False), (dict(drive=Drive(v_bus=24.0)), False),
    (dict(controller_type="microstep"), False),
])
def test_the_fast_path_condition_is_explicit(change, plain):
    from dataclasses import replace
    from flatstep.studies.batch import plain_sampled

    assert plain_sampled(replace(SAMPLED, **change)) is plain


def test_the_c_batch_fast_path_gives_the_per_run_rows(monkeypatch):
    """Plain sampled runs go through one C call per chunk (summaries computed in C); engine='c' forces the
    per-run path (simulate + SimResult.summary) on the same runs: every row is equal, bit for bit."""
    ideal = Scenario("ideal", control_period=5e-5)
    infeasible = Scenario("fast", plan=fs.RestToRest(0.0, 0.05, 0.4, 0.4, 0.02, 0.022), control_period=5e-5)
    grid = (scenario_grid(SAMPLED, load_torque=[0.0, 2e-5], control_period=[5e-5, 3e-5])
            + scenario_grid(ideal, plant=[None, ideal.motor.replace(R=1.1 * ideal.motor.R)], substeps=[3, 10])
            + [infeasible])
    from flatstep import _core

    calls, batch = [], _core.run_sampled_summaries
    monkeypatch.setattr(_core, "run_sampled_summaries", lambda runs: calls.append(len(runs)) or batch(runs))
    fast = run_batch(grid, workers=2, chunk_size=3)
    assert sorted(calls) == [2, 3, 3]  # one C call per chunk of 3; the infeasible plan never reaches C
    slow = run_batch(grid, workers=1, engine="c")
    assert len(calls) == 3 and fast == slow
    assert fast[-1]["error"].startswith("InfeasiblePlanError")
    assert all(r["error"] is None for r in fast[:-1]) and "max_abs_theta_error_after" in fast[0]
