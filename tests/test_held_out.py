"""The held-out check: fixed gains re-run on plants and moves their search did not see."""
import json
import math
from dataclasses import replace

import pytest
from conftest import TINY

from flatstep.studies.held_out import RANDOM_PLANTS, STRETCHES, held_out, held_out_mean, held_out_runs, stretched
from flatstep.studies.scenario_file import read_scenario_file
from flatstep.studies.tune import Evaluation, evaluate, study_of
from flatstep.studies.tune_laws import law_gains

CASCADE = "cascade+voltage_feedforward"
GAINS = {"current_bandwidth": 9000.0, "k_theta": 300.0, "k_omega": 1200.0, "ki_omega": 2e5}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The tiny study of conftest's TINY, read from a scenario file."""
    path = tmp_path_factory.mktemp("held") / "tiny.toml"
    path.write_text(TINY)
    return read_scenario_file(path)


def test_the_runs_are_the_study_then_random_plants_then_the_stretched_moves(tiny):
    """The runs are the study as tuned, then random plants, then the stretched moves, each built as stated."""
    runs = held_out_runs(tiny.scenario, tiny.robustness)
    assert [r.label for r in runs] == ["as tuned", f"{RANDOM_PLANTS} random plants"] + [
        f"move x {s:g}" for s in STRETCHES]
    assert runs[0].study == tiny.robustness and runs[0].scenario is tiny.scenario
    assert runs[1].study.samples == RANDOM_PLANTS and runs[1].study.seed == tiny.robustness.seed + 1
    assert len(study_of(tiny.scenario, runs[1].study)) == RANDOM_PLANTS
    for run, s in zip(runs[2:], STRETCHES, strict=True):
        plan = run.scenario.plan
        assert plan.t0 == tiny.scenario.plan.t0 and plan.theta2 == tiny.scenario.plan.theta2
        assert plan.tf - plan.t0 == pytest.approx(s * 0.02)
        assert run.scenario.t_end - plan.tf == pytest.approx(tiny.scenario.t_end - tiny.scenario.plan.tf)


def test_stretched_refuses_a_plan_it_cannot_scale(tiny):
    """Stretching refuses a plan that is no rest-to-rest move, naming the scenario and the plan's type."""
    from flatstep.plan.piecewise import PiecewisePlan

    hold = PiecewisePlan([0.0, 0.05], [[0.0]], [[0.4]])  # a plan of segments: no one duration to scale
    with pytest.raises(ValueError, match="stretches a rest-to-rest move; tiny's plan is a PiecewisePlan"):
        stretched(replace(tiny.scenario, plan=hold), 1.01)


def test_held_out_runs_the_given_gains_and_the_rule(tiny):
    """The given gains and the rule's run on every held-out run; the first is the plain evaluation."""
    res = held_out(tiny.scenario, tiny.robustness, {CASCADE: GAINS, "cascade+voltage_feedforward+plan_frame": None})
    assert set(res) == {CASCADE, "cascade+voltage_feedforward+plan_frame"}
    assert all(len(evs) == 2 + len(STRETCHES) for evs in res.values())
    # the first run is the plain evaluation of those gains on the study's plants
    sc = law_gains(CASCADE).apply(replace(tiny.scenario, controller_type=CASCADE), GAINS)
    direct = evaluate([sc], study_of(sc, tiny.robustness), [GAINS])[0]
    assert res[CASCADE][0].move_max == direct.move_max and res[CASCADE][0].gains == GAINS
    assert res[CASCADE][1].plants == RANDOM_PLANTS and res[CASCADE][2].plants == 2
    # the stretched moves are other runs: their errors differ from the study's
    assert len({e.move_max for e in res[CASCADE]}) > 1
    mean = held_out_mean(res[CASCADE])
    assert mean == pytest.approx(sum(e.move_max for e in res[CASCADE][1:]) / (1 + len(STRETCHES)))


def test_held_out_mean_is_nan_when_a_run_failed():
    """The held-out mean averages the runs after the first: NaN where one lost its move or there is none."""
    ok = Evaluation({}, 1e-4, 5.0, 1e-3, 0.0, 0, 2)
    lost = Evaluation({}, 1e-4, 5.0, 1e-3, 0.0, 1, 2)
    assert held_out_mean([lost, ok, ok]) == pytest.approx(1e-4)
    assert math.isnan(held_out_mean([ok, ok, lost]))
    assert math.isnan(held_out_mean([ok]))


def _tuned_json(path, gains):
    best = {"gains": gains, "move_max": 1e-4, "peak_voltage": 5.0}
    path.write_text(json.dumps({"scenario": "tiny", "frontiers": {CASCADE: {"points": [{"best": best}]}}}))


def test_cli_held_out_reads_a_tuned_json_and_prints_the_default_beside(tiny, cli, tmp_path):
    """The command line's --held-out reads a tuned.json and prints the rule's gains and default / best beside."""
    _tuned_json(tmp_path / "tuned.json", GAINS)
    run = cli(["compare", str(tiny.path), "--tuned", "tuned.json", "--held-out", "--controllers", CASCADE],
              cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert "as tuned" in lines[1] and "held-out mean" in lines[1]
    assert lines[2].startswith(CASCADE) and lines[3].startswith("cascade+voltage_feedforward+plan_frame (rule gains)")
    assert "default / best" in lines[4]


@pytest.mark.parametrize("argv, match", [
    (["--held-out", "--controllers", CASCADE], "--held-out re-runs gains read from --tuned PATH"),
    (["--tuned", "tuned.json", "--held-out", "--controllers", "smc"], "smc is not in tuned.json"),
    (["--tuned", "tuned.json", "--held-out", "--controllers", CASCADE, "--out", "o"], "--out does not apply"),
    (["--tuned", "bad.json", "--controllers", CASCADE], "not a tuned.json"),
])
def test_cli_held_out_refuses(tiny, cli, tmp_path, argv, match):
    """The command line refuses --held-out without --tuned, a law not in the file, --out and a bad tuned.json."""
    _tuned_json(tmp_path / "tuned.json", GAINS)
    (tmp_path / "bad.json").write_text("{}")
    run = cli(["compare", str(tiny.path)] + argv, cwd=tmp_path)
    assert run.returncode == 2 and match in run.stderr
