import itertools
import json
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from types import SimpleNamespace

import pytest

import flatstep as fs
from flatstep.loop.drive import Drive
from flatstep.loop.sensors import Sensors
from flatstep.studies.batch import run_batch, scenario_grid
from flatstep.studies.batch_file import BatchFileWarning
from flatstep.studies.scenario import Scenario

SAMPLED = Scenario("s", loop=fs.DriveLoop(5e-5, substeps=4), measurement="model",
                   gains=fs.SMCGains(W1=150, W2=3e5, eps1=0.0375, eps2=75, xi=0.9, wn=400))
MOTOR = SAMPLED.motor


def loads(*taus):
    return [fs.Plant(MOTOR, load=tau) for tau in taus]


def loops(*periods, substeps=4):
    return [fs.DriveLoop(Ts, substeps=substeps) for Ts in periods]


def test_grid_and_order_and_values_match_single_runs():
    grid = scenario_grid(SAMPLED, plant=loads(0.0, 2e-5), loop=loops(5e-5, 2.5e-5))
    assert len(grid) == 4 and grid[1].control_period == 2.5e-5 and grid[2].simulated_plant.load == 2e-5
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
    grid = scenario_grid(SAMPLED, plant=loads(0.0, 1e-5, 2e-5))
    run_batch(grid[:2], out=out, workers=1)
    lines = [json.loads(x) for x in out.read_text().splitlines()[1:]]  # after the header
    assert [r["index"] for r in lines] == [0, 1]
    out.write_text(out.read_text() + '{"index": 2, "theta_fi')  # a line cut by an interruption
    with pytest.warns(BatchFileWarning, match="dropping 22 bytes"):
        rows = run_batch(grid, out=out, workers=1)
    assert [r["index"] for r in rows] == [0, 1, 2] and rows[2]["error"] is None
    indices = [json.loads(x)["index"] for x in out.read_text().splitlines()[3:]]
    assert indices == [2]  # only the missing run was done again


def test_progress_bar_goes_to_stderr_once_the_work_takes_2_s(capsys, monkeypatch):
    import flatstep.studies.batch as batch

    run_batch([SAMPLED] * 3, workers=1)
    assert capsys.readouterr().err == ""  # short work stays quiet
    clock = itertools.count(0.0, 3.0)  # every reading of the batch's clock 3 s after the last
    monkeypatch.setattr(batch, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    run_batch([SAMPLED] * 3, workers=1, progress=False)
    assert capsys.readouterr().err == ""
    run_batch([SAMPLED] * 3, workers=1)
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


@pytest.mark.parametrize("change, in_c", [
    (dict(), True), (dict(loop=None), False), (dict(loop=fs.DriveLoop(5e-5, compute_delay=True)), True),
    (dict(loop=fs.DriveLoop(5e-5, sensors=Sensors(delay=8))), True),
    (dict(loop=fs.DriveLoop(5e-5, drive=Drive(v_bus=24.0))), True),
    (dict(controller_type="microstep"), True),
    (dict(plant=fs.Plant(MOTOR, fs.PlantEffects(coulomb_torque=1e-4), load=1e-5)), True),
    (dict(loop=fs.DriveLoop(5e-5, drive=Drive(pwm="switched"))), True),
    (dict(loop=fs.DriveLoop(5e-5, sensors=Sensors(delay=9))), False),
    (dict(plant=fs.Plant(MOTOR, load=lambda t: 1e-5 * t)), False),
])
def test_the_c_summary_condition_is_explicit(change, in_c):
    from flatstep.studies.batch import summarised_in_c

    assert summarised_in_c(replace(SAMPLED, **change)) is in_c


def test_the_c_batch_path_gives_the_per_run_rows(monkeypatch):
    """Sampled runs go through one C call per chunk (runs and summaries computed in C), whatever the controller,
    the plant effects and the loop's parts; one Scenario.run per scenario (simulate + SimResult.summary) gives
    the same numbers, bit for bit."""
    ideal = Scenario("ideal", loop=fs.DriveLoop(5e-5))
    drive = fs.DriveLoop(5e-5, drive=Drive(v_bus=24.0), sensors=Sensors(current_noise=1e-3, seed=3),
                         observer=fs.Observer(1500.0))
    infeasible = Scenario("fast", plan=fs.RestToRest(0.0, 0.05, 0.4, 0.4, 0.02, 0.022), loop=fs.DriveLoop(5e-5))
    grid = (scenario_grid(SAMPLED, plant=loads(0.0, 2e-5), loop=loops(5e-5, 3e-5))
            + scenario_grid(ideal, plant=[None, fs.Plant(MOTOR.replace(R=1.1 * MOTOR.R))], loop=loops(5e-5, substeps=3)
                            + loops(5e-5, substeps=10))
            + scenario_grid(Scenario("baseline", loop=drive, measurement="observer", plant=loads(1e-5)[0]),
                            controller_type=["microstep", "cascade", "exact_linearization"])
            + [replace(SAMPLED, name="effects", plant=fs.Plant(MOTOR, fs.PlantEffects(detent_torque=1e-4)))]
            + [infeasible])
    from flatstep import _core

    calls, batch = [], _core.run_sampled_summaries
    monkeypatch.setattr(_core, "run_sampled_summaries", lambda runs: calls.append(len(runs)) or batch(runs))
    fast = run_batch(grid, workers=2, chunk_size=3)
    assert sorted(calls) == [0, 3, 3, 3, 3]  # one C call per chunk of 3; the infeasible plan never reaches C
    assert fast[-1]["error"].startswith("InfeasiblePlanError")
    assert all(r["error"] is None for r in fast[:-1]) and "max_abs_theta_error_after" in fast[0]
    for row, scenario in zip(fast[:-1], grid):
        assert {k: row[k] for k in row if k not in ("index", "name", "error")} == scenario.run().summary(), \
            scenario.name
