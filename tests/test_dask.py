"""run_batch on a real Dask cluster: a LocalCluster of 2 worker processes, 1 thread each."""
import os

import pytest

import flatstep as fs
from flatstep.studies.executors import as_executor, executor_workers

distributed = pytest.importorskip("distributed")

GAINS = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)   # flatstep design's, for 20 kHz


@pytest.fixture(scope="module")
def client():
    """A client of a fresh 2-process LocalCluster (dashboard on a free port), closed after the module's tests."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=40) as cluster, distributed.Client(cluster) as c:
        yield c


def runs(n):
    """``n`` sampled runs on the realistic drive (14-bit encoder, 12-bit ADC with noise, observer), loads varied."""
    loop = fs.DriveLoop.at(20e3, drive=fs.Drive(v_bus=24.0), sensors=fs.Sensors(encoder_counts=16384),
                           observer=fs.Observer(bandwidth=1500.0))
    base = fs.Scenario("d", loop=loop, measurement="observer", gains=GAINS, t_end=0.05)
    motor = base.motor
    return fs.scenario_grid(base, plant=[fs.Plant(motor, load=1e-6 * k) for k in range(n)])


def test_rows_on_the_cluster_equal_a_local_run(client, tmp_path):
    """Every row, to the last bit, and the batch file written from the cluster's results resumes locally."""
    grid = runs(12)
    local = fs.run_batch(grid, workers=1, progress=False)
    out = tmp_path / "rows.jsonl"
    remote = fs.run_batch(grid, executor=client.get_executor(), progress=False, out=out)
    assert remote == local
    assert fs.run_batch(grid, progress=False, out=out) == local   # every row read back, none run again
    assert len({row["theta_final"] for row in local}) == len(grid)  # the loads really differ


def test_chunks_follow_the_clusters_workers_not_this_machines_cores(client, monkeypatch):
    """48 runs on 2 worker threads: 16 tasks of 3 runs (8 per worker), even if this machine had 64 cores."""
    assert executor_workers(client.get_executor()) == 2
    monkeypatch.setattr(os, "cpu_count", lambda: 64)   # the client machine's cores must not matter
    grid = runs(48)
    with distributed.get_task_stream(client) as tasks:
        rows = fs.run_batch(grid, executor=client, progress=False)   # a Client is taken for its executor
    assert len(tasks.data) == 16
    assert [row["index"] for row in rows] == list(range(48))
    assert fs.run_batch(grid, executor=client, workers=1, chunk_size=48, progress=False) == rows


def test_a_client_or_its_executor_submits_unhashed_tasks_on_the_workers_it_names(client):
    """pure=False (no hash of the scenarios per task); an executor held to one worker counts that worker only."""
    assert as_executor(client)._kwargs == {"pure": False}
    one = sorted(client.nthreads())[0]
    held = as_executor(client.get_executor(workers=[one]))
    assert held._kwargs == {"pure": False, "workers": [one]}
    assert executor_workers(held) == 1
    mine = client.get_executor(pure=True)
    assert as_executor(mine) is mine   # an explicit choice is kept
