"""(e) One engine for every run: the comparison on the C engine against the Python reference loop.

Beside it, the ``flatstep compare`` command end to end, and every controller's batch throughput with detent and
friction.
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace

import numpy as np

from ..control.tuning import CONTROLLER_TYPES
from ..studies.batch import run_batch, scenario_grid
from ..studies.compare import compare_worst
from ..studies.scenario_file import Robustness, load_scenario
from .common import ROOT, Report, Target, race

SCENARIO = ROOT / "examples" / "compare-nema17-fast.toml"


def _cli_seconds(repeat: int) -> list[float]:
    """Wall times of ``flatstep compare examples/compare-nema17-fast.toml --scales 0.5,2``.

    A new process each, interpreter start-up and figures included.
    """
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeat):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "flatstep", "compare", str(SCENARIO), "--scales", "0.5,2",
                            "--quiet", "--out", tmp], check=True, capture_output=True, timeout=600)
            out.append(time.perf_counter() - start)
    return out


def bench_engine(repeat: int = 3, plants: int = 4, runs: int = 400) -> Report:
    """(e) The NEMA 17 comparison on the C engine and on the Python reference loop, side by side.

    The comparison (every controller, realistic 20 kHz drive, detent, Coulomb friction, load) runs on
    ``plants`` random plants of its +-10 % box, both engines through ``compare_worst`` on every core; beside it,
    the whole ``flatstep compare`` command (4 controllers x 32 plants and the 0.5x and 2x bandwidth sweeps) on the
    C engine, and ``runs`` 60 ms runs per controller through ``run_batch`` (summaries in C on every core), each
    under its own load.
    """
    if not SCENARIO.exists():
        raise RuntimeError(f"benchmark (e) reads {SCENARIO}: run it from a source checkout")
    scenario, _ = load_scenario(SCENARIO)
    subset = Robustness(relative_error=0.1, samples=plants, seed=1)
    workers = os.cpu_count() or 1
    n_runs = plants * len(CONTROLLER_TYPES)
    c_name, py_name = "C engine (compare_worst)", "Python reference loop (compare_worst)"
    cases = {py_name: lambda: compare_worst(scenario, subset, engine="python", progress=False),
             c_name: lambda: compare_worst(scenario, subset, engine="c", progress=False)}
    times, results = race(cases, repeat, per={name: n_runs for name in cases})
    worst_diff = max(abs(results[c_name][k]["worst"][m] - results[py_name][k]["worst"][m])
                     for k in CONTROLLER_TYPES for m in ("move_max", "peak_voltage", "copper_loss"))
    cli = statistics.median(_cli_seconds(repeat))

    short = replace(scenario, t_end=0.06)
    loads = [replace(short.simulated_plant, load=float(x)) for x in np.linspace(0.0, 0.02, runs)]
    rates = {}
    for kind in CONTROLLER_TYPES:
        grid = scenario_grid(replace(short, controller_type=kind), plant=loads)
        samples = []
        for _ in range(repeat):
            start = time.perf_counter()
            rows = run_batch(grid, progress=False)
            samples.append(time.perf_counter() - start)
            if any(row["error"] for row in rows):
                first = next(r["error"] for r in rows if r["error"])
                raise RuntimeError(f"benchmark (e): a {kind} run failed: {first}")
        rates[kind] = runs / statistics.median(samples)

    checks = [("largest difference of a worst-case metric (move_max [rad], peak_voltage [V], copper_loss [J]) "
               "between the engines", worst_diff, "")]
    targets = [Target("flatstep compare examples/compare-nema17-fast.toml --scales 0.5,2, wall time", cli, 5.0,
                      False, " s")]
    targets += [Target(f"60 ms runs per second at 20 kHz with detent and Coulomb friction, {kind}, {workers} cores",
                       rate, 1500.0, True) for kind, rate in rates.items()]
    notes = [f"{plants} plants x {len(CONTROLLER_TYPES)} controllers per compare_worst call, 100 ms each "
             f"({scenario.name}: 20 kHz, 14-bit encoder, 12-bit ADC, observer, 24 V bus, load, detent, Coulomb)",
             f"throughput: {runs} runs per controller, 1200 periods of 4 RK4 substeps, the scenario's sensors and "
             f"observer; runs/s: " + ", ".join(f"{k} {r:.0f}" for k, r in rates.items())]
    return Report("e", "one engine: the comparison on C against the Python reference loop", "run", times, py_name,
                  checks, targets, notes)
