"""The tuner: seeded and reproducible, its caps honoured, its tables read back, its bad inputs refused."""
import dataclasses
import math
from pathlib import Path

import pytest
from conftest import TINY

from flatstep.studies.frontier import check_fractions, frontier, outside_layer
from flatstep.studies.scenario_file import read_scenario_file
from flatstep.studies.tune import Caps, check_budget, tune
from flatstep.studies.tune_file import TUNED_MARK, read_tuned, tuned_toml
from flatstep.studies.tune_laws import TUNABLE, law_gains

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FAST = dict(budget=10, population=5)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The tiny study of conftest's TINY, read from a scenario file."""
    path = tmp_path_factory.mktemp("tune") / "tiny.toml"
    path.write_text(TINY)
    return read_scenario_file(path)


@pytest.fixture(scope="module")
def tuned_smc(tiny):
    """The paper's law tuned on the tiny study with seed 3 and the fast budget."""
    return tune(tiny.scenario, "smc", seed=3, study=tiny.robustness, **FAST)


def test_seeded_tuning_is_reproducible(tiny, tuned_smc):
    """A seed gives the same search and answer again; another seed searches elsewhere."""
    again = tune(tiny.scenario, "smc", seed=3, study=tiny.robustness, **FAST)
    assert again.gains == tuned_smc.gains
    assert again.best.move_max == tuned_smc.best.move_max
    assert [e.gains for e in again.evaluations] == [e.gains for e in tuned_smc.evaluations]
    other = tune(tiny.scenario, "smc", seed=4, study=tiny.robustness, **FAST)
    assert [e.gains for e in other.evaluations][1:] != [e.gains for e in tuned_smc.evaluations][1:]


def test_the_early_stop_and_the_threads_change_nothing_but_the_time(tiny):
    """The search with every plant of every trial run, on one thread, takes the same path and gives the same answer."""
    study = dataclasses.replace(tiny.robustness, parameters=["R", "Km", "J"])  # 8 plants: rounds of 1, 4, 8
    fast = tune(tiny.scenario, "cascade", seed=2, study=study, budget=25, population=5, workers=2)
    full = tune(tiny.scenario, "cascade", seed=2, study=study, budget=25, population=5, workers=1, early_stop=False)
    assert [e.gains for e in fast.evaluations] == [e.gains for e in full.evaluations]
    assert fast.best == full.best and fast.gains == full.gains
    stopped = [e for e in fast.evaluations if not e.complete]
    assert stopped, "no trial was stopped early: the test no longer checks the early stop"
    assert all(e.evaluated < e.plants == 8 for e in stopped)
    assert all(e.complete for e in full.evaluations)
    by_gains = {tuple(e.gains.values()): e for e in full.evaluations}
    for e in stopped:  # a stopped trial lost to its member, and would not have been the answer
        whole = by_gains[tuple(e.gains.values())]
        assert e.move_max <= whole.move_max
        assert whole.move_max > full.best.move_max or full.caps.excess(whole) > 0


def test_budget_is_the_same_for_every_law(tiny, tuned_smc):
    """Every law gets the same budget of evaluations, over its own gains."""
    cascade = tune(tiny.scenario, "cascade", seed=3, study=tiny.robustness, **FAST)
    assert len(tuned_smc.evaluations) == len(cascade.evaluations) == 10
    assert set(cascade.gains) == {"current_bandwidth", "k_theta", "k_omega", "ki_omega"}
    assert set(tuned_smc.gains) == {"W1", "eps1", "W2", "eps2", "wn"}


def test_the_scenario_gains_are_the_first_candidate_and_never_beaten_by_a_worse(tiny, tuned_smc):
    """The scenario's gains are the first candidate, and the answer is never worse than them."""
    start = tuned_smc.start
    for key, value in tiny.scenario.gains.as_dict().items():
        if key in start.gains:
            assert start.gains[key] == pytest.approx(value, rel=1e-9)
    assert tuned_smc.feasible
    assert tuned_smc.best.move_max <= start.move_max
    assert start.plants == 2


def test_caps_are_honoured(tiny, tuned_smc):
    """A cap on the peak voltage or the copper is honoured, and one no run can meet leaves no feasible answer."""
    cap = 0.8 * tuned_smc.best.peak_voltage
    capped = tune(tiny.scenario, "smc", seed=3, study=tiny.robustness, caps=Caps(peak_voltage=cap), **FAST)
    assert capped.caps.peak_voltage == cap
    if capped.feasible:
        assert capped.best.peak_voltage <= cap
        assert capped.best.move_max >= tuned_smc.best.move_max  # a tighter cap never helps
    copper = tune(tiny.scenario, "cascade", seed=3, study=tiny.robustness,
                  caps=Caps(copper=1e-9), **FAST)  # no run can spend less than a nanojoule here
    assert not copper.feasible
    assert copper.best.copper > 1e-9
    assert copper.caps.peak_voltage == 24.0 and copper.caps.settling == pytest.approx(0.02)


def test_frontier_points_meet_their_caps_and_improve_with_the_cap(tiny):
    """Each frontier point meets its cap, and a larger cap gives an error no larger."""
    fr = frontier(tiny.scenario, "cascade", fractions=(0.5, 1.0), study=tiny.robustness, seed=1, **FAST)
    assert [p.cap for p in fr.points] == [12.0, 24.0]
    for p in fr.points:
        assert p.best is not None and p.best.peak_voltage <= p.cap
    assert fr.points[1].best.move_max <= fr.points[0].best.move_max
    assert len(fr.results) == 2


def test_outside_layer_share(tiny, tuned_smc):
    """The share of samples outside the boundary layers is a fraction, and there is none for a law without them."""
    share = outside_layer(tuned_smc.tuned, tiny.robustness)
    assert 0.0 <= share["s1"] <= share["either"] <= 1.0
    assert share["s2"] <= share["either"]
    assert share["max_s1_over_eps1"] > 0
    if share["max_s1_over_eps1"] <= 1.0:
        assert share["s1"] == 0.0
    assert outside_layer(dataclasses.replace(tiny.scenario, controller_type="cascade")) is None


def test_tuned_toml_keeps_the_file_and_reads_back(tiny, tuned_smc, tmp_path):
    """The tuned file keeps the scenario file, reads back the tuned gains, and keeps other laws' gains out."""
    text = tiny.path.read_text()
    out = tuned_toml(text, "smc", tuned_smc.gains, "smc tuned")
    assert out.encode().startswith(TUNED_MARK)
    path = tmp_path / "smc.toml"
    path.write_text(out)
    back = read_scenario_file(path)
    assert back.scenario.controller_type == "smc"
    for key, value in tuned_smc.gains.items():
        assert getattr(back.scenario.gains, key) == value
    assert back.scenario.loop.observer == tiny.scenario.loop.observer  # design = true kept: the designed observer
    assert read_tuned(tmp_path)["smc"].path == path
    # another law's gains in the file (a sliding law's W1, hold_damping) do not go into a cascade's table
    other = TINY.replace("uncertainty = 0.1", "uncertainty = 0.1\nW1 = 50.0\nhold_damping = 1.0\nbandwidth_scale = 2.0")
    gains = {"current_bandwidth": 3000.0, "k_theta": 100.0, "k_omega": 600.0, "ki_omega": 5e4}
    (tmp_path / "cascade.toml").write_text(tuned_toml(other, "cascade", gains, "cascade tuned"))
    cascade = read_scenario_file(tmp_path / "cascade.toml").scenario
    assert dict(cascade.law_gains["cascade"]) == gains and cascade.bandwidth_scale == 1.0
    assert cascade.controller().gains.k_omega == 600.0


def test_cli_tune_writes_a_table_that_simulate_reads(tiny, cli, tmp_path):
    """The tune command writes a table simulate and compare read; a rerun replaces its own file with the same result."""
    (tmp_path / "s.toml").write_text(TINY)
    run = cli(["tune", "s.toml", "--law", "cascade", "--budget", "10", "--population", "5", "--out", "t.toml",
               "--quiet"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "cascade tuned" in run.stdout and "wrote t.toml" in run.stdout
    back = read_scenario_file(tmp_path / "t.toml")
    assert back.scenario.controller_type == "cascade"
    k_theta = float(run.stdout.split("k_theta = ")[1].split(",")[0])
    assert back.scenario.law_gains["cascade"]["k_theta"] == pytest.approx(k_theta, rel=1e-4)
    assert back.scenario.controller().gains.k_theta == back.scenario.law_gains["cascade"]["k_theta"]
    sim = cli(["simulate", "t.toml"], cwd=tmp_path)
    assert sim.returncode == 0, sim.stderr
    again = cli(["tune", "s.toml", "--law", "cascade", "--budget", "10", "--population", "5", "--out", "t.toml",
                 "--quiet"], cwd=tmp_path)  # its own file: replaced without --force
    assert again.returncode == 0, again.stderr

    def tuned_line(out):  # the tuned row without its wall time
        return next(line for line in out.splitlines() if line.startswith("cascade tuned")).rsplit("  ", 1)[0]

    assert tuned_line(again.stdout) == tuned_line(run.stdout)
    cmp_ = cli(["compare", "s.toml", "--tuned", "t.toml", "--controllers", "cascade", "--quiet"], cwd=tmp_path)
    assert cmp_.returncode == 0, cmp_.stderr
    assert "(read)" in cmp_.stdout


@pytest.mark.parametrize("argv, match", [
    (["--budget", "3"], "--budget 3 evaluations: give at least"),
    (["--population", "2"], "population=2 must be >= 5"),
    (["--law", "pid"], "--law"),
    (["--law", "smc,smc"], "given twice"),
    (["--law", "smc,cascade", "--out", "one.toml"], "one file holds one law's table"),
    (["--out", "s.toml"], "is an input of this run"),
    (["--peak-voltage", "-1"], "peak_voltage"),
    (["--budget", "1000000"], "or lower --budget"),
    (["--law", "cascade_ff"], "--law cascade_ff: controller type 'cascade_ff' needs the torques"),
])
def test_cli_tune_refuses_bad_input(cli, tmp_path, argv, match):
    """The tune command refuses bad input with exit 2 and a message naming it, no traceback."""
    (tmp_path / "s.toml").write_text(TINY)
    run = cli(["tune", "s.toml", *argv], cwd=tmp_path)
    assert run.returncode == 2
    assert match in run.stderr
    assert "Traceback" not in run.stderr


def test_cli_refuses_a_user_file_and_a_scenario_without_drive(cli, tmp_path):
    """The command line refuses to write over a user's file, a scenario without a drive and bad --tuned options."""
    (tmp_path / "s.toml").write_text(TINY)
    (tmp_path / "mine.toml").write_text("# my notes\n")
    run = cli(["tune", "s.toml", "--out", "mine.toml"], cwd=tmp_path)
    assert run.returncode == 2 and "--force" in run.stderr
    (tmp_path / "c.toml").write_text("[plan]\ntf = 0.04\n")
    run = cli(["tune", "c.toml"], cwd=tmp_path)
    assert run.returncode == 2 and "control_rate" in run.stderr
    run = cli(["compare", "s.toml", "--tuned", "--scales", "0.5"], cwd=tmp_path)
    assert run.returncode == 2 and "--scales does not apply with --tuned" in run.stderr
    run = cli(["compare", "s.toml", "--tuned", "nowhere"], cwd=tmp_path)
    assert run.returncode == 2 and "no such file or directory" in run.stderr
    run = cli(["compare", "s.toml", "--tuned", "--frontier", "0.5,2"], cwd=tmp_path)
    assert run.returncode == 2 and "fractions of the bus in (0, 1]" in run.stderr


def test_api_refuses_bad_input(tiny):
    """The tuning functions refuse bad laws, seeds, caps, budgets, fractions and gains with a ValueError."""
    with pytest.raises(ValueError, match="law 'nope'|is unknown"):
        tune(tiny.scenario, "nope", **FAST)
    with pytest.raises(ValueError, match="seed=-1"):
        tune(tiny.scenario, "smc", seed=-1, **FAST)
    with pytest.raises(ValueError, match="copper=-2.0 J must be > 0"):
        Caps(copper=-2.0)
    with pytest.raises(ValueError, match="caps=.* is not a flatstep Caps"):
        tune(tiny.scenario, "smc", caps={"peak_voltage": 3}, **FAST)
    with pytest.raises(ValueError, match="no drive loop"):
        tune(dataclasses.replace(tiny.scenario, loop=None, controller_type="smc"), "smc", **FAST)
    with pytest.raises(ValueError, match="needs the torques"):
        tune(tiny.scenario, "smc_ff", **FAST)
    with pytest.raises(ValueError, match="give at least 10"):
        check_budget(9, 5)
    with pytest.raises(ValueError, match="fractions of the bus"):
        check_fractions([0.0])
    with pytest.raises(ValueError, match="not the tunable gains"):
        tuned_toml(TINY, "smc", {"k_theta": 2.0}, "x")


def test_every_law_has_a_table_row_with_bounds_around_its_value():
    """Every law has a row of tunable gains with bounds around its value, and its variants share the row."""
    for law, row in TUNABLE.items():
        assert row.gains, law
        for g in row.gains:
            assert g.low < 0 < g.high
    assert law_gains("cascade_model") is TUNABLE["cascade"]
    assert law_gains("dq_smc_i_ff") is TUNABLE["dq_smc"]


@pytest.mark.parametrize("kind", ["smc", "cascade", "microstep", "exact_linearization", "dq_smc"])
def test_each_row_reads_and_applies_the_controller_as_built(tiny, kind):
    """Each row reads the gains of the controller as built and applies them back unchanged."""
    import dataclasses as dc

    row = law_gains(kind)
    base = dc.replace(tiny.scenario, controller_type=kind, bandwidth_scale=2.0)
    centre = row.read(base)
    same = row.apply(base, centre)
    assert row.read(same) == pytest.approx(centre, rel=1e-12)  # the rule's scaling moved into the gains, unchanged
    doubled = row.apply(base, {k: 2 * v for k, v in centre.items()})
    assert row.read(doubled) == pytest.approx({k: 2 * v for k, v in centre.items()}, rel=1e-12)
    if kind != "smc" and kind != "dq_smc":  # a baseline's gains go under its law, the other laws' stay
        other = dc.replace(base, law_gains={"microstep" if kind != "microstep" else "cascade": {"x": 1.0}})
        assert len(row.apply(other, centre).law_gains) == 2


@pytest.mark.slow
@pytest.mark.parametrize("example", ["compare-nema17-fast.toml", "compare-paper-20khz.toml"])
@pytest.mark.parametrize("kind", ["smc", "cascade"])
def test_full_tuning_on_the_shipped_examples(example, kind):
    """A full tuning of the shipped examples is feasible, never worse than the start, and within the bus."""
    sf = read_scenario_file(EXAMPLES / example)
    res = tune(sf.scenario, kind, seed=0, study=sf.robustness)
    assert res.feasible
    assert res.best.move_max <= res.start.move_max
    assert res.best.peak_voltage <= 24.0
    assert len(res.evaluations) == 120
    assert math.isfinite(res.wall_time)
