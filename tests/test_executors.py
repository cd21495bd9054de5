"""The executor a batch runs on: its worker count, the chunk size that follows from it, bad executors."""
import os
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor

import pytest

import flatstep as fs
from flatstep.studies.executors import TASKS_PER_WORKER, as_executor, default_chunk_size, executor_workers


class Counting(Executor):
    """Runs every task in place and counts them; tells nothing about its workers."""

    def __init__(self):
        self.tasks = 0

    def submit(self, fn, /, *args, **kwargs):
        self.tasks += 1
        fut = Future()
        fut.set_result(fn(*args, **kwargs))
        return fut


class Pool(Counting):
    """A counting executor that says it has ``n`` workers, as a pool does."""

    def __init__(self, n):
        super().__init__()
        self._max_workers = n


def test_executor_workers_asks_the_pool():
    with ThreadPoolExecutor(3) as threads, ProcessPoolExecutor(5) as processes:
        assert (executor_workers(threads), executor_workers(processes)) == (3, 5)
    assert executor_workers(Counting()) is None


@pytest.mark.parametrize("n, workers, size", [(100, 2, 6), (16, 2, 1), (15, 2, 1), (1000, 3, 41), (0, 4, 1)])
def test_default_chunk_size_gives_about_8_tasks_per_worker(n, workers, size):
    assert default_chunk_size(n, workers) == size
    assert TASKS_PER_WORKER == 8


def runs(n):
    """``n`` short sampled runs (summarised in C)."""
    base = fs.Scenario("e", loop=fs.DriveLoop(5e-5), measurement="model", t_end=0.045,
                       gains=fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500))
    return fs.scenario_grid(base, t_end=[0.045 + 1e-4 * k for k in range(n)])


def test_chunks_follow_the_executors_workers_then_workers_then_the_cores(monkeypatch):
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    grid = runs(48)
    told = Pool(3)                      # 48 // (8 * 3) = 2 runs per task
    rows = fs.run_batch(grid, executor=told, progress=False)
    assert told.tasks == 24
    given = Pool(3)                     # workers= overrides what the executor says: 48 // (8 * 1) = 6 runs per task
    assert fs.run_batch(grid, executor=given, workers=1, progress=False) == rows
    assert given.tasks == 8
    silent = Counting()                 # no answer: this machine's 2 cores, 48 // 16 = 3 runs per task
    assert fs.run_batch(grid, executor=silent, progress=False) == rows
    assert silent.tasks == 16


def test_a_non_executor_is_refused():
    with pytest.raises(ValueError, match="executor=42 is not a concurrent.futures.Executor"):
        as_executor(42)
    with pytest.raises(ValueError, match="is not a concurrent.futures.Executor"):
        fs.run_batch(runs(2), executor="dask", progress=False)
