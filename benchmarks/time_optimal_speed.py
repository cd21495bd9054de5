"""The time-optimal planner against an earlier version of itself, medians side by side in one run.

Run ``python benchmarks/time_optimal_speed.py 9e98b41``: it loads ``src/flatstep/plan/time_optimal.py`` as it
was at the given git revision (its relative imports made absolute), plans the same moves with both, checks the
plans are equal, and prints the median times.
"""
import importlib.util
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from flatstep.model.motor import PRESETS
from flatstep.plan import time_optimal as new
from flatstep.plan.limits import MotorLimits


def load_old(rev):
    """The module time_optimal.py of git revision ``rev``."""
    src = subprocess.run(["git", "show", f"{rev}:src/flatstep/plan/time_optimal.py"], check=True,
                         capture_output=True, text=True, cwd=Path(__file__).parents[1]).stdout
    src = re.sub(r"from \.\.(\w+)", r"from flatstep.\1", src)
    src = re.sub(r"from \.(\w+)", r"from flatstep.plan.\1", src)
    path = Path(tempfile.mkdtemp()) / "time_optimal_old.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("time_optimal_old", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def median_ms(fn, repeat=7):
    """Median wall time of ``fn()`` over ``repeat`` calls [ms]."""
    runs = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t)
    return 1e3 * statistics.median(runs)


def main(rev):
    """Plan 0.1, 1, 5 and 20 rad at 24 V and 12 V with both versions (the limits of flatstep.plan.compare)."""
    old, motor = load_old(rev), PRESETS["nema17"]
    for bus in (24.0, 12.0):
        def limits(bus=bus):  # a fresh object per call, as a caller would pass (equal limits share the cache)
            return MotorLimits(v_bus=bus, i_max=1.0, i_run=0.025, v_use=0.84, torque_angle_max=1.1)
        for d in (0.1, 1.0, 5.0, 20.0):
            a, b = old.time_optimal(d, motor, limits()), new.time_optimal(d, motor, limits())
            same = a.tf == b.tf and bool((a.theta == b.theta).all())
            t_old = median_ms(lambda d=d: old.time_optimal(d, motor, limits()))
            t_new = median_ms(lambda d=d: new.time_optimal(d, motor, limits()))
            print(f"{bus:g} V {d:g} rad: {rev} {t_old:.1f} ms, now {t_new:.1f} ms ({t_old / t_new:.2f} x faster), "
                  f"same plan: {same} ({1e3 * b.tf:.3f} ms)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "HEAD")
