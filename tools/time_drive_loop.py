"""Time a robustness study on the Python reference loop and on the C drive loop, side by side in one run.

    python tools/time_drive_loop.py examples/drive-20khz-14bit.toml [--repeats 3] [--workers N]

Runs the scenario's ``[robustness]`` study (and the paper's gains on the same drive, as ``flatstep robustness``
does) once per engine and repeat, alternating engines, on the same ``run_batch`` executor (all cores unless
``--workers``). Prints the median wall time of each engine and their ratio, the worst values of each engine in
encoder counts, and the largest difference between the engines over every sample of every run.
"""
from __future__ import annotations

import argparse
import statistics
import time

from flatstep.studies.robustness import encoder_count, run_study
from flatstep.studies.scenario_file import Robustness, load_scenario

ENGINES = ("python", "c")
KEYS = ("move", "rest", "final", "peak_voltage")


def main() -> None:
    """Time the scenario's robustness study on the C and Python engines; print the ratio and the differences."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    scenario, study = load_scenario(args.scenario)
    study = study or Robustness()
    times: dict[str, list[float]] = {e: [] for e in ENGINES}
    results = {}
    for _ in range(args.repeats):
        for engine in ENGINES:
            start = time.perf_counter()
            results[engine] = run_study(scenario, study, workers=args.workers, engine=engine)
            times[engine].append(time.perf_counter() - start)
    runs = sum(len(s["rows"]) for s in results["c"]["sets"].values())
    med = {e: statistics.median(t) for e, t in times.items()}
    print(f"{scenario.name}: {runs} runs per study, median of {args.repeats}, workers={args.workers or 'all cores'}")
    print(f"  python reference loop {med['python']:.3f} s, C drive loop {med['c']:.3f} s, "
          f"ratio {med['python'] / med['c']:.1f}x")
    count = encoder_count(scenario) or 1.0
    print(f"  {'gains':<14}{'engine':<8}{'worst move':>12}{'worst rest':>12}{'final':>10}{'peak |v|':>10}  [counts, V]")
    for label in results["c"]["sets"]:
        for engine in ENGINES:
            w = results[engine]["sets"][label]["worst_rad"]
            print(f"  {label:<14}{engine:<8}{w['move'] / count:>12.3f}{w['rest'] / count:>12.3f}"
                  f"{w['final'] / count:>10.3f}{w['peak_voltage']:>10.3g}")
        d = {"theta_error": 0.0, "v": 0.0}
        for rc, rp in zip(results["c"]["sets"][label]["rows"], results["python"]["sets"][label]["rows"], strict=True):
            for name in ("theta_error", "va", "vb"):
                a, b = rc[f"series_{name}"], rp[f"series_{name}"]
                key = name if name == "theta_error" else "v"
                d[key] = max(d[key], max(abs(x - y) for x, y in zip(a, b, strict=True)))
        print(f"  {label:<14}largest C - Python difference over every sample of every run: theta "
              f"{d['theta_error']:.2e} rad ({d['theta_error'] / count:.2e} counts), voltage {d['v']:.2e} V")

if __name__ == "__main__":
    main()
