"""Batches of scenarios: rows equal to single runs, the C path, batch files, resume, locks, kill -9, a full disk."""
import errno
import itertools
import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest

import flatstep as fs
import flatstep._version
from flatstep.loop.drive import Drive
from flatstep.loop.sensors import Sensors
from flatstep.studies.batch import run_batch, scenario_grid
from flatstep.studies.batch_file import BatchFileWarning
from flatstep.studies.scenario import Scenario

SAMPLED = Scenario("s", loop=fs.DriveLoop(5e-5, substeps=4), measurement="model",
                   gains=fs.SMCGains(W1=150, W2=3e5, eps1=0.0375, eps2=75, xi=0.9, wn=400))
MOTOR = SAMPLED.motor


def loads(*taus):
    """A plant of the sampled scenario's motor for each load torque of ``taus``."""
    return [fs.Plant(MOTOR, load=tau) for tau in taus]


def loops(*periods, substeps=4):
    """A drive loop for each control period of ``periods``, with ``substeps`` plant steps a period."""
    return [fs.DriveLoop(Ts, substeps=substeps) for Ts in periods]


def test_grid_and_order_and_values_match_single_runs():
    """The grid's order and the rows follow the input, and each row's values are those of a single run."""
    grid = scenario_grid(SAMPLED, plant=loads(0.0, 2e-5), loop=loops(5e-5, 2.5e-5))
    assert len(grid) == 4 and grid[1].control_period == 2.5e-5 and grid[2].simulated_plant.load == 2e-5
    rows = run_batch(grid, workers=2, chunk_size=1)
    assert [r["index"] for r in rows] == [0, 1, 2, 3] and all(r["error"] is None for r in rows)
    for row, scenario in zip(rows, grid, strict=False):
        assert row["theta_final"] == scenario.run().summary()["theta_final"]
    assert rows[0]["theta_final"] != rows[2]["theta_final"]  # the load changed something


def test_any_executor_and_failures_are_rows():
    """The batch runs on a caller's executor, and a run that fails is a row with its error, not an exception."""
    bad = Scenario("fast", plan=fs.RestToRest(0.0, 0.05, 0.4, 0.4, 0.02, 0.022))
    with ThreadPoolExecutor(2) as ex:
        rows = run_batch([SAMPLED, bad], executor=ex)
    assert rows[0]["error"] is None
    assert rows[1]["error"].startswith("InfeasiblePlanError") and "theta_final" not in rows[1]


def test_results_are_written_as_they_go_and_a_rerun_resumes(tmp_path):
    """Rows are written as they finish; a rerun drops a cut last line and runs only the missing scenario."""
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
    """The progress bar goes to stderr once the work takes 2 s, never for short work or with progress=False."""
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
    """Bad workers, chunk sizes, scenarios and grid fields are refused with a ValueError naming them."""
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
    """Summarising in C is an explicit rule: not without a loop, with a delay over 8 or with a load function."""
    from flatstep.studies.batch import summarised_in_c

    assert summarised_in_c(replace(SAMPLED, **change)) is in_c


def test_the_c_batch_path_gives_the_per_run_rows(monkeypatch):
    """Sampled runs go through one C call per chunk, and one Scenario.run per scenario gives the same numbers.

    The chunk's runs and summaries are computed in C, whatever the controller, the plant effects and the loop's
    parts; Scenario.run (simulate + SimResult.summary) matches them bit for bit.
    """
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
    from flatstep import core

    calls, batch = [], core.run_sampled_summaries
    monkeypatch.setattr(core, "run_sampled_summaries", lambda runs: calls.append(len(runs)) or batch(runs))
    fast = run_batch(grid, workers=2, chunk_size=3)
    assert sorted(calls) == [0, 3, 3, 3, 3]  # one C call per chunk of 3; the infeasible plan never reaches C
    assert fast[-1]["error"].startswith("InfeasiblePlanError")
    assert all(r["error"] is None for r in fast[:-1]) and "max_abs_theta_error_after" in fast[0]
    for row, scenario in zip(fast[:-1], grid, strict=False):
        assert {k: row[k] for k in row if k not in ("index", "name", "error")} == scenario.run().summary(), \
            scenario.name


# --- batch files: fingerprints, resume, lock, crash, full disk ---------------------------------------------------

GRID = scenario_grid(SAMPLED, plant=loads(0.0, 1e-5, 2e-5, 3e-5))


def counting(monkeypatch):
    """The indices of the scenarios run from now on (a counter on both chunk runners of run_batch)."""
    import flatstep.studies.batch as batch

    ran = []
    for name in ("_run_chunk", "_run_chunk_c"):
        real = getattr(batch, name)

        def run(chunk, engine, keep, real=real):
            ran.extend(i for i, _ in chunk)
            return real(chunk, engine, keep)

        monkeypatch.setattr(batch, name, run)
    return ran


def test_fingerprints_follow_the_content_not_the_object():
    """A fingerprint follows the content, engine, keep and version, not the object or a function's address."""
    from flatstep.studies.fingerprint import fingerprint

    def fp(scenario, engine="c", keep=(), version="1"):
        return fingerprint(scenario, engine, keep, version)

    twin = Scenario("s", loop=fs.DriveLoop(5e-5, substeps=4), measurement="model",
                    gains=fs.SMCGains(W1=150.0, W2=3e5, eps1=0.0375, eps2=75, xi=0.9, wn=400))
    assert twin is not SAMPLED and fp(twin) == fp(SAMPLED) and len(fp(SAMPLED)) == 16
    changed = [replace(SAMPLED, name="t"), replace(SAMPLED, t_end=0.06000000000000001),
               replace(SAMPLED, plant=fs.Plant(MOTOR, load=1e-5)),
               replace(SAMPLED, loop=fs.DriveLoop(5e-5, substeps=3))]
    prints = {fp(SAMPLED), fp(SAMPLED, engine="python"), fp(SAMPLED, keep=("t",)), fp(SAMPLED, version="2"),
              *map(fp, changed)}
    assert len(prints) == 8  # every change of content, engine, keep or version changes the fingerprint
    k1, k2 = 1e-5, 2e-5  # a load function: its code and the values it closes over count, not its address

    def ramp(k):
        return fs.Plant(MOTOR, load=lambda t: k * t)

    assert fp(replace(SAMPLED, plant=ramp(k1))) == fp(replace(SAMPLED, plant=ramp(k1)))
    assert fp(replace(SAMPLED, plant=ramp(k1))) != fp(replace(SAMPLED, plant=ramp(k2)))


def test_the_file_starts_with_a_header_and_rows_carry_fingerprints(tmp_path):
    """The file starts with a header naming the batch, and its rows carry fingerprints the returned rows do not."""
    from flatstep.studies.batch import _done_indices

    out = tmp_path / "rows.jsonl"
    rows = run_batch(GRID[:2], out=out, workers=1)
    head, *lines = [json.loads(x) for x in out.read_text().splitlines()]
    assert head["flatstep_batch"] == 1 and head["version"] == fs.__version__ and head["engine"] == "c"
    assert head["scenarios"] == 2 and len(head["scenarios_hash"]) == 16 and head["keep"] == []
    assert [r["index"] for r in lines] == [0, 1] and lines[0]["fingerprint"] != lines[1]["fingerprint"]
    assert all("fingerprint" not in r for r in rows)  # returned rows are the summaries, as without a file
    assert _done_indices(out) == {0, 1}


@pytest.mark.parametrize("second, match", [
    (dict(scenarios=[GRID[0], GRID[2]]),
     r"line 3, the row of scenario 1 \(\"s\[plant=.*'load': 1e-05}\]\"\), was computed for another scenario than "
     r"this batch's scenario 1 \(\"s\[plant=.*'load': 2e-05}\]\"\)"),
    (dict(engine="python"), r"the engine differs: the file has 'c', this batch 'python'"),
    (dict(keep=("t",)), r"keep differs: the file has \[\], this batch \['t'\]"),
    (dict(scenarios=GRID[:1]), "the row of scenario 1, and this batch has 1"),
    (dict(version="9.9"), r"the flatstep version differs: the file has '.*', this batch '9.9'"),
])
def test_a_file_of_another_batch_is_refused_naming_the_difference(tmp_path, monkeypatch, second, match):
    """A file of another batch is refused, naming the difference, before any run and with the file unchanged."""
    out = tmp_path / "rows.jsonl"
    run_batch(GRID[:2], out=out, workers=1)
    before = out.read_bytes()
    ran = counting(monkeypatch)
    if "version" in second:
        monkeypatch.setattr(flatstep._version, "__version__", second.pop("version"))
    scenarios = second.pop("scenarios", GRID[:2])
    with pytest.raises(ValueError, match=match) as info:
        run_batch(scenarios, out=out, workers=1, **second)
    assert str(out) in str(info.value) and "fresh=True" in str(info.value)
    assert ran == [] and out.read_bytes() == before and not (tmp_path / "rows.jsonl.lock").exists()


def test_a_file_without_a_header_is_refused(tmp_path):
    """A file without a batch header, or a directory, is refused as the output."""
    out = tmp_path / "old.jsonl"
    out.write_text('{"index": 0, "name": "s", "theta_final": 1.0, "error": null}\n')
    with pytest.raises(ValueError, match="old.jsonl holds another batch: its first line is not a flatstep batch"):
        run_batch(GRID[:1], out=out, workers=1)
    with pytest.raises(ValueError, match="is a directory"):
        run_batch(GRID[:1], out=tmp_path, workers=1)


def test_fresh_moves_the_old_file_to_bak(tmp_path, monkeypatch):
    """With fresh=True the old file moves to .bak (then .bak.2) and every scenario runs again."""
    out = tmp_path / "rows.jsonl"
    run_batch(GRID[:2], out=out, workers=1)
    old = out.read_bytes()
    ran = counting(monkeypatch)
    rows = run_batch(GRID[2:], out=out, workers=1, fresh=True)
    assert (tmp_path / "rows.jsonl.bak").read_bytes() == old and ran == [0, 1]
    assert [json.loads(x)["index"] for x in out.read_text().splitlines()[1:]] == [0, 1]
    assert rows[0]["name"] == GRID[2].name
    run_batch(GRID[2:], out=out, workers=1, fresh=True)
    assert (tmp_path / "rows.jsonl.bak").read_bytes() == old and (tmp_path / "rows.jsonl.bak.2").exists()


def test_a_resume_reuses_exactly_the_matching_rows(tmp_path, monkeypatch):
    """A resume reuses the rows that match, runs only the others, and gives the rows of a clean run."""
    out = tmp_path / "rows.jsonl"
    clean = run_batch(GRID, workers=1)
    ran = counting(monkeypatch)
    run_batch(GRID[:2], out=out, workers=1)
    assert ran == [0, 1]
    rows = run_batch(GRID, out=out, workers=2, chunk_size=1)  # the list grew: rows 0 and 1 are reused
    assert sorted(ran) == [0, 1, 2, 3] and rows == clean
    assert json.loads(out.read_text().splitlines()[0])["scenarios"] == 4  # the header follows the grown list
    ran.clear()
    assert run_batch(GRID, out=out, workers=1) == clean and ran == []  # nothing left to run


@pytest.mark.parametrize("tail, dropped", [
    ('{"index": 2, "theta_fi', 22),  # cut in a row
    ('{"index": 2, "fingerprint": "0"}', 32),  # whole, but the newline never came
    ("#!garbage\n", 10),  # closed by a newline, not JSON
])
def test_a_last_line_cut_short_is_truncated_off(tmp_path, monkeypatch, tail, dropped):
    """A last line cut short is truncated off with a warning, the whole rows kept and its scenario run again."""
    out = tmp_path / "rows.jsonl"
    run_batch(GRID[:2], out=out, workers=1)
    whole = out.read_bytes()
    out.write_bytes(whole + tail.encode())
    ran = counting(monkeypatch)
    with pytest.warns(BatchFileWarning, match=f"rows.jsonl: dropping {dropped} bytes"):
        rows = run_batch(GRID[:3], out=out, workers=1)
    assert ran == [2] and rows[2]["error"] is None
    assert out.read_bytes().splitlines()[1:3] == whole.splitlines()[1:]  # the whole rows are kept
    assert [json.loads(x)["index"] for x in out.read_text().splitlines()[1:]] == [0, 1, 2]


def test_a_second_writer_is_refused_while_the_first_holds_the_lock(tmp_path, monkeypatch):
    """A second writer is refused while the first holds the lock, and only the holder removes it."""
    import threading

    import flatstep.studies.batch as batch

    out, lock = tmp_path / "rows.jsonl", tmp_path / "rows.jsonl.lock"
    started, go, real = threading.Event(), threading.Event(), batch._run_chunk_c

    def slow(chunk, engine, keep):
        started.set()
        assert go.wait(10)
        return real(chunk, engine, keep)

    monkeypatch.setattr(batch, "_run_chunk_c", slow)
    first = threading.Thread(target=run_batch, args=(GRID,), kwargs=dict(out=out, workers=1))
    first.start()
    try:
        assert started.wait(10) and lock.read_text() == f"{os.getpid()}\n"
        with pytest.raises(ValueError, match=f"rows.jsonl is being written by process {os.getpid()} "
                                             f"\\(lock {lock}\\)"):
            run_batch(GRID, out=out, workers=1)
    finally:
        go.set()
        first.join()
    assert not lock.exists()  # released by the first writer
    assert [json.loads(x)["index"] for x in out.read_text().splitlines()[1:]] == [0, 1, 2, 3]  # written once
    lock.write_text(f"{os.getpid()}\n")  # a lock file held by a live process (this one)
    with pytest.raises(ValueError, match=f"process {os.getpid()}"):
        run_batch(GRID, out=out, workers=1)
    assert lock.exists()  # not the refused writer's to remove


def test_a_stale_lock_is_taken_over(tmp_path):
    """A lock whose process is gone, or left without a pid for over 10 s, is taken over with a warning."""
    out, lock = tmp_path / "rows.jsonl", tmp_path / "rows.jsonl.lock"
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()  # reaped: its pid no longer runs
    lock.write_text(f"{gone.pid}\n")
    with pytest.warns(BatchFileWarning, match=f"taking over a stale lock \\(pid {gone.pid} no longer runs\\)"):
        run_batch(GRID[:1], out=out, workers=1)
    assert not lock.exists()
    lock.write_text("")  # a writer killed before it wrote its pid: held for 10 s, then stale
    with pytest.raises(ValueError, match="has not written its pid yet"):
        run_batch(GRID[:1], out=out, workers=1)
    os.utime(lock, (time.time() - 60, time.time() - 60))
    with pytest.warns(BatchFileWarning, match="stale lock"):
        run_batch(GRID[:1], out=out, workers=1)


def test_a_full_disk_hands_back_the_rows(tmp_path, monkeypatch):
    """A full disk raises BatchWriteError holding every row; the cut row is truncated off and a rerun resumes."""
    from flatstep.studies.batch_file import BatchWriteError, RowWriter

    out = tmp_path / "rows.jsonl"
    clean = run_batch(GRID, workers=1)
    real, written = RowWriter._write, []

    def write(self, data):
        if len(written) == 2:  # the disk fills in the third row
            real(self, data[:40])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written.append(data)
        real(self, data)

    monkeypatch.setattr(RowWriter, "_write", write)
    with pytest.warns(BatchFileWarning, match="writing failed"), pytest.raises(BatchWriteError) as info:
        run_batch(GRID, out=out, workers=1, chunk_size=1)
    assert f"writing the batch file {out} failed (No space left on device)" in str(info.value)
    assert info.value.errno == errno.ENOSPC and info.value.path == out
    assert info.value.rows == clean  # computed to the end, in input order
    assert out.read_bytes().count(b"\n") == 3 and out.read_bytes().endswith(b"\n")  # the cut row truncated off
    assert not (tmp_path / "rows.jsonl.lock").exists()
    monkeypatch.setattr(RowWriter, "_write", real)
    ran = counting(monkeypatch)
    assert run_batch(GRID, out=out, workers=1) == clean and ran == [2, 3]  # the disk has room again


KILLED_BATCH = """
import sys
import flatstep as fs
from flatstep.studies.batch import run_batch
from tests.test_batch import killed_grid
run_batch(killed_grid(), engine="python", workers=2, chunk_size=1, out=sys.argv[1], progress=False)
"""


#: The killed batch's move: the paper's 0.02 rad in 10 ms from t = 2 ms (300 periods of 15 ms a run).
KILLED_PLAN = fs.RestToRest(0.0, 0.02, 0.4, 0.4, 0.002, 0.012)


def killed_grid():
    """Six sampled runs of about 0.4 s each on the Python engine."""
    return [replace(SAMPLED, name=f"k{i}", plan=KILLED_PLAN, t_end=0.015, plant=fs.Plant(MOTOR, load=i * 1e-6))
            for i in range(6)]


def descendants(pid):
    """The pids of the live processes descended from ``pid`` (from /proc)."""
    parent = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z":
            parent[int(stat.parent.name)] = int(fields[1])
    found, todo = set(), [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        found.update(kids)
        todo.extend(kids)
    return found


def running(pid):
    """Whether ``pid`` is a live process (a zombie is not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_kill_9_of_the_parent_ends_its_workers_and_the_file_resumes(tmp_path, monkeypatch):
    """Kill -9 of the parent ends its workers, and a rerun takes over its lock and runs only the missing rows."""
    out = tmp_path / "rows.jsonl"
    root = Path(__file__).resolve().parent.parent
    proc = subprocess.Popen([sys.executable, "-c", KILLED_BATCH, str(out)], cwd=root)
    try:
        deadline = time.monotonic() + 30
        while not (out.exists() and out.read_text().count("\n") >= 2):  # the header and a row
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        workers = descendants(proc.pid)
        assert len(workers) >= 2
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    deadline = time.monotonic() + 5
    while any(running(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert [w for w in workers if running(w)] == []
    assert (tmp_path / "rows.jsonl.lock").read_text() == f"{proc.pid}\n"  # left behind by the killed writer
    written = {json.loads(x)["index"] for x in out.read_text().splitlines()[1:] if x.endswith("}")}
    clean = run_batch(killed_grid(), engine="python", workers=2, chunk_size=1)
    ran = counting(monkeypatch)
    with pytest.warns(BatchFileWarning, match="stale lock"):
        rows = run_batch(killed_grid(), engine="python", workers=1, out=out)
    assert sorted(ran) == sorted(set(range(6)) - written) and len(ran) < 6
    assert sorted(json.loads(x)["index"] for x in out.read_text().splitlines()[1:]) == list(range(6))
    assert rows == clean and all(r["error"] is None for r in rows)


ORPHAN = """
import os, sys, time
from flatstep.studies import workers
parent = os.getpid()
child = os.fork()
if child == 0:
    if sys.argv[1] == "watchdog":
        workers.sys = type(sys)("fake_sys")
        workers.sys.platform = "darwin"  # no prctl: the watchdog thread
    workers.die_with_parent(parent)
    time.sleep(30)
    os._exit(0)
print(child, flush=True)
time.sleep(30)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("how", ["prctl", "watchdog"])
def test_die_with_parent_ends_a_worker_when_its_parent_is_killed(how):
    """A worker ends when its parent is killed, through prctl or through the watchdog thread."""
    proc = subprocess.Popen([sys.executable, "-c", ORPHAN, how], stdout=subprocess.PIPE, text=True)
    try:
        child = int(proc.stdout.readline())
        assert running(child)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        proc.stdout.close()
    deadline = time.monotonic() + 3
    while running(child) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not running(child)


def test_a_file_that_cannot_be_created_raises_batch_write_error(tmp_path, monkeypatch):
    """A batch file that cannot be created raises BatchWriteError before any run, leaving no lock."""
    import flatstep.studies.batch_file as batch_file

    def full(path, head, rest):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(batch_file, "_rewrite", full)
    ran = counting(monkeypatch)
    with pytest.raises(fs.BatchWriteError, match="opening the batch file .*rows.jsonl failed \\(No space left"
                                                 " on device\\); 0 of 4 rows") as info:
        run_batch(GRID, out=tmp_path / "rows.jsonl", workers=1)
    assert info.value.rows == [None] * 4 and ran == [] and not (tmp_path / "rows.jsonl.lock").exists()
