"""(d) Batch throughput: sampled 60 ms closed-loop runs per second, one worker against all cores.

The runs go through ``run_batch`` (summaries in C), one ``Scenario.run`` per run, and the binding.
"""
from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..loop.reference import DriveLoop
from ..model.plant import Plant
from ..studies.scenario import PAPER_SCENARIOS
from .common import Report, Target, core_module, race


def bench_batch(repeat: int = 3, runs: int = 200, control_period: float = 5e-5, substeps: int = 10,
                workers: Optional[int] = None, min_time: float = 0.0) -> Report:
    """(d) Sampled closed-loop runs of 60 ms per second, each under its own load torque in [0, 1e-5] N m.

    The controller fires every ``control_period``, its voltage is held, the plant integrated by RK4 substeps. The
    cases are the public batch API
    :func:`flatstep.run_batch` (one C call per chunk, runs and summaries in C, threads), one
    :meth:`~flatstep.studies.scenario.Scenario.run` + ``SimResult.summary`` per run (the C run, the result
    assembled in Python), each on one and on ``workers`` threads (default: every core), beside the binding's
    ``run_sampled`` (one C call per run; cffi releases the GIL, so threads run on separate cores).
    """
    from ..studies.batch import run_batch, scenario_grid

    core = core_module()
    if core is None:
        raise RuntimeError("benchmark (d) needs the C binding (flatstep.core); install flatstep with its C core")
    loop = DriveLoop(control_period=control_period, substeps=substeps)
    sc = replace(PAPER_SCENARIOS["fig1"], loop=loop)
    motor, plan, ctrl = sc.motor, sc.plan, sc.controller()
    workers = workers or os.cpu_count() or 1
    periods = math.ceil(sc.t_end / control_period - 1e-9)
    loads = [float(load) for load in np.linspace(0.0, 1e-5, runs)]
    scenarios = scenario_grid(sc, plant=[Plant(motor, load=load) for load in loads])
    x0 = plan.x0(motor.Nr)

    def one(load: float) -> Any:  # run_sampled's (x, v, y, status, stats)
        return core.run_sampled(ctrl, motor, load, x0, periods, Ts=control_period, substeps=substeps)

    fast1, fast_n = "run_batch, 1 worker", f"run_batch, {workers} threads"
    slow1, slow_n = "Scenario.run per run, 1 thread", f"Scenario.run per run, {workers} threads"
    raw1, raw_n = "binding run_sampled, 1 thread", f"binding run_sampled, {workers} threads"
    with ThreadPoolExecutor(workers) as pool:
        cases = {slow1: lambda: [s.run().summary() for s in scenarios],
                 slow_n: lambda: list(pool.map(lambda s: s.run().summary(), scenarios)),
                 fast1: lambda: run_batch(scenarios, workers=1, progress=False),
                 fast_n: lambda: run_batch(scenarios, workers=workers, progress=False),
                 raw1: lambda: [one(load) for load in loads],
                 raw_n: lambda: list(pool.map(one, loads))}
        times, results = race(cases, repeat, min_time, per={name: runs for name in cases})
    rows, slow_rows, raw = results[fast_n], results[slow_n], results[raw_n]
    errors = [row["error"] for row in rows if row["error"]]
    summaries = [{k: v for k, v in row.items() if k not in ("index", "name", "error")} for row in rows]
    checks = [("runs that failed", float(len(errors)), ""),
              ("rows of run_batch that differ from Scenario.run's summaries",
               float(sum(a != b for a, b in zip(summaries, slow_rows, strict=True))), ""),
              ("max |theta_final(run_batch) - theta_final(binding)| over the runs",
               float(max(abs(row["theta_final"] - res[0][3, -1]) for row, res in zip(rows, raw, strict=True))), " rad"),
              ("no-load run: |theta(60 ms) - theta2| (sampled at this period)", abs(raw[0][0][3, -1] - plan.theta2),
               " rad"),
              (f"speed-up of {workers} threads over 1 (run_batch)", times[fast1] / times[fast_n], "x"),
              (f"speed-up of {workers} threads over 1 (Scenario.run)", times[slow1] / times[slow_n], "x"),
              (f"speed-up of {workers} threads over 1 (binding)", times[raw1] / times[raw_n], "x")]
    targets = [Target(f"runs per second, {fast_n}", 1 / times[fast_n], 1000, True, ""),
               Target(f"runs per second, {slow_n}", 1 / times[slow_n], 1000, True, ""),
               Target(f"runs per second, {raw_n}", 1 / times[raw_n], 1000, True, "")]
    notes = [f"{runs} runs per batch (pool start-up included), {periods} control periods of "
             f"{control_period * 1e6:g} us, {substeps} RK4 substeps each; runs/s: "
             + ", ".join(f"{name} {1 / t:.0f}" for name, t in times.items()),
             "the sampled loop with the paper's law and gains does not hold Fig. 1's move at this rate: see "
             "docs/benchmarks.md (not a cost of the engine: a Python ZOH + RK4 loop gives the same angle)"]
    if errors:
        notes.append(f"first failure: {errors[0]}")
    return Report("d", "batch throughput: 60 ms closed-loop runs, sampled control", "run", times, slow1,
                  checks, targets, notes)
