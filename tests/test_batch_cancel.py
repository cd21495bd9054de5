"""Ctrl-C during run_batch on threads: the running chunks stop within 0.5 s, and the batch resumes from its file."""
import os
import signal
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

import flatstep as fs
from flatstep.studies.batch import _done_indices

GAINS = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)   # flatstep design's, for 20 kHz


def grid(long_end):
    """Two short sampled runs (0.06 s of motor time), then two of ``long_end`` s (about 30 ms of CPU per s)."""
    base = fs.Scenario("s", loop=fs.DriveLoop(5e-5), measurement="model", gains=GAINS)
    return fs.scenario_grid(base, t_end=[0.06, 0.07, long_end, long_end + 0.5])


def interrupted(call, after, rows=None):
    """Run ``call()``, send this process SIGINT (Ctrl-C) ``after`` s later; the seconds from signal to raise.

    With ``rows`` (a batch file), the signal waits until the file holds the two short runs' rows as well, so that a
    loaded machine still interrupts the long runs, not the short ones.
    """
    sent, stop = [], threading.Event()

    def fire():
        start = time.perf_counter()
        while not stop.is_set():
            late = time.perf_counter() - start >= after
            if late and (rows is None or {0, 1} <= _done_indices(rows) or time.perf_counter() - start > 30):
                sent.append(time.perf_counter())
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.002)

    # Python's own Ctrl-C handler, even when this process started with SIGINT ignored (a background job)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Thread(target=fire, daemon=True)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        stop.set()
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert sent, "the batch ended before the signal: make its runs longer"
    return time.perf_counter() - sent[0]


@pytest.mark.parametrize("keep", [(), ("theta",)])
def test_ctrl_c_stops_running_thread_chunks_within_half_a_second(tmp_path, keep):
    """Summaries in C (one C call per chunk) and one Scenario.run per run (keep): both stop in < 0.5 s.

    Without the cancel flag the batch waited for its chunks: 1.7 s of C run each here.
    """
    out = tmp_path / "rows.jsonl"
    before = threading.active_count()
    stop = interrupted(lambda: fs.run_batch(grid(60.0), workers=2, chunk_size=1, progress=False, out=out,
                                            keep=keep), after=0.25, rows=out)
    assert stop < 0.5, f"the batch took {stop:.3f} s to stop after Ctrl-C"
    assert threading.active_count() == before   # no chunk runs on
    assert _done_indices(out) == {0, 1}         # the finished rows are kept, no interrupted run is written
    assert not (tmp_path / "rows.jsonl.lock").exists()


def test_ctrl_c_stops_chunks_on_a_given_thread_pool_and_the_batch_resumes(tmp_path):
    """On the caller's own ThreadPoolExecutor too (its threads are free when the batch raises).

    Then the same call finishes the batch from the file, and its rows equal those of an uninterrupted run.
    """
    out, runs = tmp_path / "rows.jsonl", grid(30.0)
    with ThreadPoolExecutor(2) as pool:
        stop = interrupted(lambda: fs.run_batch(runs, executor=pool, chunk_size=1, progress=False, out=out),
                           after=0.1, rows=out)
        assert stop < 0.5, f"the batch took {stop:.3f} s to stop after Ctrl-C"
        barrier = threading.Barrier(3)   # both workers are free at once: no interrupted chunk runs on
        free = [pool.submit(barrier.wait, 0.3) for _ in range(2)]
        barrier.wait(0.3)
        assert all(f.result() in (0, 1, 2) for f in free)
        done = _done_indices(out)
        assert {0, 1} <= done and len(done) < 4
        resumed = fs.run_batch(runs, executor=pool, chunk_size=1, progress=False, out=out)
    assert resumed == fs.run_batch(runs, workers=1, progress=False)
    assert [row["status"] for row in resumed] == ["ok"] * 4
