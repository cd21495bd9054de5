"""Files flatstep writes: never over an input, never over a user's file without --force, paths checked before work."""
import os
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from pathlib import Path

import pytest

import flatstep as fs
from flatstep.studies.batch_file import acquire_lock, read_rows
from flatstep.validate.paths import check_distinct, check_output_dir, json_marks

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: A sampled scenario (20 kHz drive) whose run takes well under a second.
SCENARIO = (EXAMPLES / "nema17-20khz.toml").read_text()
NOTES = "my notes, not flatstep's\n"


@pytest.fixture
def scenario(tmp_path):
    path = tmp_path / "S.toml"
    path.write_text(SCENARIO)
    return path


def refused(run, *words):
    """An exit 2 whose one-line message holds every word, and nothing on stdout (nothing was run)."""
    assert run.returncode == 2, (run.stdout, run.stderr)
    assert all(w in run.stderr for w in words), run.stderr
    assert "Traceback" not in run.stderr and run.stdout == ""
    return True


# ---- flatstep simulate -----------------------------------------------------------------------------------------

def test_record_over_the_scenario_is_refused_even_with_force(cli, tmp_path, scenario):
    for extra in ([], ["--force"]):
        assert refused(cli(["simulate", "S.toml", "--record", "S.toml", *extra], cwd=tmp_path),
                       "--record", "is an input of this run")
    assert scenario.read_text() == SCENARIO


def test_record_into_the_runs_own_csv_is_refused_up_front(cli, tmp_path, scenario):
    for record in ("o/run.csv", "o/./run.csv", str(tmp_path / "o" / "run.csv")):
        assert refused(cli(["simulate", "S.toml", "--out", "o", "--record", record], cwd=tmp_path),
                       "--record", "is also written by --out o (run.csv)")
    assert not (tmp_path / "o").exists()  # refused before the directory was made


@pytest.mark.parametrize("argv, words", [
    (["--record", "nodir/rec.csv"], ["--record", "does not exist"]),          # a missing directory
    (["--record", "."], ["--record", "is a directory"]),                      # a directory for a file
    (["--record", "/proc/rec.csv"], ["--record", "cannot be written"]),       # an unwritable place
    (["--record", "notes.txt/rec.csv"], ["--record", "is not a directory"]),  # a file as a directory
    (["--out", "notes.txt"], ["--out", "is not a directory"]),
    (["--out", "notes.txt/o"], ["--out", "is a file, not a directory"]),
    (["--out", "/proc/o"], ["--out", "not writable"]),
    (["--out", "S.toml"], ["--out", "is not a directory"]),
])
def test_bad_output_paths_are_refused_before_the_run(cli, tmp_path, scenario, argv, words):
    (tmp_path / "notes.txt").write_text(NOTES)
    assert refused(cli(["simulate", "S.toml", *argv], cwd=tmp_path), *words)
    assert (tmp_path / "notes.txt").read_text() == NOTES


def test_a_users_file_needs_force(cli, tmp_path, scenario):
    notes = tmp_path / "notes.csv"
    notes.write_text(NOTES)
    assert refused(cli(["simulate", "S.toml", "--record", "notes.csv"], cwd=tmp_path),
                   "notes.csv: exists and is not a file flatstep wrote", "--force")
    assert notes.read_text() == NOTES
    run = cli(["simulate", "S.toml", "--record", "notes.csv", "--force"], cwd=tmp_path)
    assert run.returncode == 0 and notes.read_text().startswith("t,va,vb,ia,ib,theta\n")
    run = cli(["simulate", "S.toml", "--record", "notes.csv"], cwd=tmp_path)  # now flatstep's own: no force
    assert run.returncode == 0


def test_out_writes_again_over_its_own_files_but_not_over_a_users(cli, tmp_path, scenario):
    assert cli(["simulate", "S.toml", "--out", "o"], cwd=tmp_path).returncode == 0
    summary = tmp_path / "o" / "summary.json"
    assert summary.read_text().startswith('{\n  "status"')
    assert cli(["simulate", "S.toml", "--out", "o"], cwd=tmp_path).returncode == 0  # over its own files
    summary.write_text('{"my": "summary"}\n')
    assert refused(cli(["simulate", "S.toml", "--out", "o"], cwd=tmp_path), "summary.json", "--force")
    assert summary.read_text() == '{"my": "summary"}\n'


def test_record_needs_a_sampled_drive_before_the_run(cli, tmp_path):
    assert refused(cli(["simulate", "--record", "r.csv"], cwd=tmp_path), "--record", "sampled drive")
    assert not (tmp_path / "r.csv").exists()


# ---- flatstep plan, flatstep robustness ------------------------------------------------------------------------

def test_plan_out_is_checked_before_planning(cli, tmp_path, scenario):
    (tmp_path / "notes.txt").write_text(NOTES)
    assert refused(cli(["plan", "S.toml", "--out", "notes.txt"], cwd=tmp_path), "--out", "not a directory")
    assert refused(cli(["plan", "S.toml", "--out", "/proc/p"], cwd=tmp_path), "--out", "not writable")
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "plan.json").write_text(NOTES)
    assert refused(cli(["plan", "S.toml", "--out", "p"], cwd=tmp_path), "plan.json", "--force")
    assert (tmp_path / "p" / "plan.json").read_text() == NOTES
    assert cli(["plan", "S.toml", "--out", "p", "--force"], cwd=tmp_path).returncode == 0
    assert (tmp_path / "p" / "plan.json").read_text().startswith('{\n  "name"')


def test_robustness_out_is_checked_before_the_study(cli, tmp_path, scenario):
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "robustness.png").write_text(NOTES)
    assert refused(cli(["robustness", "S.toml", "--samples", "2", "--out", "r"], cwd=tmp_path),
                   "robustness.png", "--force")
    assert refused(cli(["robustness", "S.toml", "--out", "S.toml"], cwd=tmp_path), "--out", "not a directory")
    assert refused(cli(["robustness", "S.toml", "--out", "/proc/r"], cwd=tmp_path), "--out", "not writable")
    assert scenario.read_text() == SCENARIO


# ---- run_batch --------------------------------------------------------------------------------------------------

BASE = fs.Scenario(t_end=0.045)


def test_run_batch_refuses_a_file_that_is_not_a_batch_file(tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text(NOTES)  # one line: it used to be dropped as a "last line cut short", and the file rewritten
    with pytest.raises(ValueError, match="notes.txt: exists and is not a file flatstep wrote.*fresh=True"):
        fs.run_batch([BASE], out=notes, progress=False)
    assert notes.read_text() == NOTES
    rows = fs.run_batch([BASE], out=notes, progress=False, fresh=True)  # moved aside, never deleted
    assert rows[0]["status"] == "ok" and (tmp_path / "notes.txt.bak").read_text() == NOTES
    assert fs.run_batch([BASE], out=notes, progress=False) == rows  # now a batch file: its rows are reused


@pytest.mark.parametrize("out, match", [
    (lambda d: d / "nodir" / "b.jsonl", "does not exist"), (lambda d: d, "is a directory"),
    (lambda d: "/proc/b.jsonl", "cannot be written"), (lambda d: 3, "is not a path"),
    (lambda d: True, "is not a path"), (lambda d: "", "the path is empty"),
])
def test_run_batch_checks_out_before_any_run(tmp_path, out, match):
    calls = []
    with pytest.raises(ValueError, match=match):
        fs.run_batch([BASE, BASE], out=out(tmp_path), progress=False, executor=_Counting(calls))
    assert calls == []


class _Counting(Executor):
    """Counts submitted tasks, runs them in place."""

    def __init__(self, calls):
        self.calls = calls

    def submit(self, fn, *args, **kwargs):
        self.calls.append(fn)
        fut = Future()
        fut.set_result(fn(*args, **kwargs))
        return fut


class _Returns(Executor):
    """An executor whose futures hold ``value`` instead of the task's result."""

    def __init__(self, value):
        self.value = value

    def submit(self, fn, *args, **kwargs):
        fut = Future()
        fut.set_result(self.value)
        return fut

    def __repr__(self):
        return f"_Returns({self.value!r})"


@pytest.mark.parametrize("executor, match", [
    (_Returns(None), r"executor=_Returns\(None\) returned None for the task of row [01] \(scenario 'run\["),
    (_Returns([{"x": 1}]), r"returned \[\{'x': 1\}\] for the task of row [01]"),
    (_Returns([{"index": 7}]), "with the indices"),
    (type("NoFuture", (Executor,), {"submit": lambda self, fn, *a, **k: 42})(), "submit\\(\\) returned 42"),
])
def test_an_executor_that_hands_back_no_rows_is_named(executor, match):
    runs = fs.scenario_grid(BASE, t_end=[0.045, 0.05])
    with pytest.raises(ValueError, match=match):
        fs.run_batch(runs, executor=executor, workers=1, chunk_size=1, progress=False)


@pytest.mark.parametrize("kwargs, match", [
    (dict(keep=5), "keep=5 must be a sequence"), (dict(keep=[["t"]]), "must hold series names"),
    (dict(keep=b"t"), "must be a sequence"), (dict(workers="2"), "workers="), (dict(chunk_size=-1), "chunk_size="),
    (dict(engine=["c"]), "is not an engine"), (dict(progress="yes"), "progress="), (dict(fresh=1), "fresh="),
    (dict(executor="threads"), "not a concurrent.futures.Executor"),
])
def test_run_batch_refuses_wrong_types_with_a_named_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.run_batch([BASE], **{"progress": False, **kwargs})


def test_a_good_executor_still_works(tmp_path):
    with ThreadPoolExecutor(2) as pool:
        rows = fs.run_batch(fs.scenario_grid(BASE, t_end=[0.045, 0.05]), executor=pool, chunk_size=1,
                            progress=False, out=tmp_path / "b.jsonl")
    assert [r["status"] for r in rows] == ["ok", "ok"]


def test_the_batch_files_helpers_replace_no_users_file(tmp_path):
    """A user's ``<out>.tmp`` survives a header rewrite; a ``<out>.lock`` that holds no pid is not taken over."""
    batch, tmp, lock = tmp_path / "b.jsonl", tmp_path / "b.jsonl.tmp", tmp_path / "b.jsonl.lock"
    tmp.write_text(NOTES)
    head = {"flatstep_batch": 1, "version": "x", "engine": "c", "keep": [], "scenarios": 0, "scenarios_hash": ""}
    assert read_rows(batch, head, [], []) == {} and batch.read_text().startswith('{"flatstep_batch"')
    assert tmp.read_text() == NOTES and oct(batch.stat().st_mode & 0o777) == oct(0o644)
    lock.write_text(NOTES)
    os.utime(lock, (1, 1))  # old: it would count as stale
    with pytest.raises(ValueError, match="is not a batch lock"):
        acquire_lock(batch)
    assert lock.read_text() == NOTES


# ---- the rule's helpers ------------------------------------------------------------------------------------------

def test_output_dir_checks_without_creating(tmp_path):
    (tmp_path / "in.csv").write_text("t,x\n")
    files = {"run.csv": (b"t,",), "summary.json": json_marks("status")}
    assert check_output_dir(tmp_path / "a" / "b", "--out", files) == [tmp_path / "a" / "b" / "run.csv",
                                                                       tmp_path / "a" / "b" / "summary.json"]
    assert not (tmp_path / "a").exists()
    with pytest.raises(ValueError, match="its run.csv is an input"):
        check_output_dir(tmp_path / "new", "--out", files, inputs=[tmp_path / "new" / "run.csv"])
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "run.csv").write_text("t,x\n")
    with pytest.raises(ValueError, match="is an input of this run"):
        check_output_dir(tmp_path / "d", "--out", files, inputs=[tmp_path / "d" / "run.csv"], force=True)
    with pytest.raises(ValueError, match="--record .*is also written by --out"):
        check_distinct({"--out (run.csv)": tmp_path / "d" / "run.csv", "--record": tmp_path / "d" / "." / "run.csv"})
    check_distinct({"--out (run.csv)": tmp_path / "d" / "run.csv", "--record": None, "--x": tmp_path / "x.csv"})


def test_a_png_is_flatsteps_only_when_matplotlib_drew_it(tmp_path):
    from flatstep.validate.paths import PNG_MARK, check_output

    photo, figure = tmp_path / "photo.png", tmp_path / "figure.png"
    photo.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    figure.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0\0\0:tEXtSoftware\x00Matplotlib version3.11.2")
    with pytest.raises(ValueError, match="photo.png: exists and is not a file flatstep wrote"):
        check_output(photo, "--out", marks=PNG_MARK)
    assert check_output(figure, "--out", marks=PNG_MARK) == figure
    with pytest.raises(ValueError, match="not a file flatstep wrote"):
        check_output(figure, "--record", marks=(b"t,",))  # a figure is no recording


def test_reproduce_checks_its_outputs_before_running(cli, tmp_path):
    """reproduce --out: a user's fig1.png needs --force, refused before the two runs; its own files are rewritten."""
    (tmp_path / "fig1.png").write_text("my photo\n")
    run = cli(["reproduce", "--out", "."], cwd=tmp_path)
    assert run.returncode == 2 and "fig1.png: exists and is not a file flatstep wrote" in run.stderr
    assert run.stdout == "" and (tmp_path / "fig1.png").read_text() == "my photo\n"
    assert not (tmp_path / "summary.json").exists()
    (tmp_path / "out").write_text("a file\n")
    run = cli(["reproduce"], cwd=tmp_path)  # the default --out names a file
    assert run.returncode == 2 and "out" in run.stderr and (tmp_path / "out").read_text() == "a file\n"


def test_compare_and_design_check_out_before_any_run(cli, tmp_path):
    """A bad --out is refused at once (nothing printed on stdout: no run), not after the study."""
    (tmp_path / "afile").write_text("x\n")
    scenario = Path(__file__).resolve().parent.parent / "examples" / "compare-paper-20khz.toml"
    for argv in (["compare", scenario, "--out", "afile"], ["design", "--out", "afile"]):
        run = cli(argv, cwd=tmp_path)
        assert run.returncode == 2 and "--out afile: exists and is not a directory" in run.stderr, run.stderr
        assert run.stdout == "" and "[compare" not in run.stderr
