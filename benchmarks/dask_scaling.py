"""Throughput of run_batch on a local Dask cluster against a local process pool, side by side (docs/scaling.md).

    .venv/bin/python benchmarks/dask_scaling.py [--runs 1000] [--workers 2] [--repeat 3]

The runs are a robustness study of examples/drive-20khz-14bit.toml: seeded plants with +-10 % errors in
R, L, Km, J and B, each a 0.06 s move on the 20 kHz drive, summarised in C. Each executor first runs a short
warm-up batch (so that its workers have imported flatstep); then the executors take turns, ``--repeat``
batches each, so that a busy machine slows them alike. The medians and the ratio are printed, with the
start-up time of each executor and whether the rows agree.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable

import flatstep as fs
from flatstep.studies.robustness import perturbed, plant_errors
from flatstep.studies.scenario_file import load_scenario
from flatstep.studies.workers import die_with_parent

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "drive-20khz-14bit.toml"


def study(runs: int) -> list[fs.Scenario]:
    """``runs`` seeded plants around the example's scenario."""
    scenario, robustness = load_scenario(EXAMPLE)
    assert robustness is not None, f"{EXAMPLE} has no [robustness] table"
    return perturbed(scenario, plant_errors(replace(robustness, samples=runs, seed=7)))


def once(run: Callable[[], Any]) -> tuple[float, Any]:
    """The seconds ``run()`` took, and what it returned."""
    start = time.perf_counter()
    out = run()
    return time.perf_counter() - start, out


def busy(tasks: list[dict[str, Any]]) -> dict[str, float]:
    """The seconds each Dask worker spent computing, from a task stream's records."""
    out: dict[str, float] = {}
    for task in tasks:
        for span in task["startstops"]:
            if span["action"] == "compute":
                out[task["worker"]] = out.get(task["worker"], 0.0) + span["stop"] - span["start"]
    return out


def main() -> None:
    """Run the comparison and print one line per executor, then the ratio."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--only-dask", action="store_true", help="time the Dask cluster alone (a long study)")
    args = parser.parse_args()
    from distributed import Client, LocalCluster, get_task_stream

    built, runs = once(lambda: study(args.runs))
    n = args.workers
    print(f"{len(runs)} runs of {EXAMPLE.name} (+-10 % plants), {n} workers, {os.cpu_count()} cores, "
          f"median of {args.repeat}, executors taking turns; the scenarios built in {built:.1f} s")
    warm = runs[:8 * n]
    pool = ProcessPoolExecutor(n, initializer=die_with_parent, initargs=(os.getpid(),))
    start_pool, _ = once(lambda: fs.run_batch(warm, executor=pool, progress=False))
    start_dask, (cluster, client) = once(lambda: (lambda c: (c, Client(c)))(
        LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=40)))
    start_dask += once(lambda: fs.run_batch(warm, executor=client, progress=False))[0]
    executors: dict[str, dict[str, Any]] = {"Dask LocalCluster": dict(executor=client)} if args.only_dask else {
        "process pool": dict(executor=pool), "Dask LocalCluster": dict(executor=client),
        "threads (default)": dict(workers=n)}
    times: dict[str, list[float]] = {name: [] for name in executors}
    rows: dict[str, Any] = {}
    overhead: list[float] = []   # a Dask batch's wall time less its busiest worker's compute time
    with pool, cluster, client:
        for _ in range(args.repeat):
            for name, options in executors.items():
                with get_task_stream(client) as stream:
                    seconds, rows[name] = once(lambda o=options: fs.run_batch(runs, progress=False, **o))
                times[name].append(seconds)
                if name == "Dask LocalCluster":
                    overhead.append(seconds - max(busy(stream.data).values()))
    starts = {"process pool": start_pool, "Dask LocalCluster": start_dask}
    for name, ts in times.items():
        med = statistics.median(ts)
        start = f"start-up and warm-up {starts[name]:.2f} s; " if name in starts else ""
        print(f"{name:<18} {med:7.3f} s {len(runs) / med:7.0f} runs/s  ({start}runs "
              f"{', '.join(f'{t:.3f}' for t in ts)} s)")
    dask_rows = rows["Dask LocalCluster"]
    statuses = {s: sum(r["status"] == s for r in dask_rows) for s in ("ok", "fault", "lost")}
    size = statistics.mean(len(json.dumps(r)) for r in dask_rows[:1000])
    print(f"statuses: {statuses}; a row is {size:.0f} bytes of JSON; Dask's own time per batch (wall less the "
          f"busiest worker's compute): median {statistics.median(overhead):.3f} s")
    if args.only_dask:
        return
    ratio = statistics.median(times["process pool"]) / statistics.median(times["Dask LocalCluster"])
    print(f"Dask throughput / process pool throughput: {ratio:.3f} (target >= 0.8)")
    same = dask_rows == rows["process pool"] == rows["threads (default)"]
    print(f"rows identical on the three executors: {same}")


if __name__ == "__main__":
    main()
