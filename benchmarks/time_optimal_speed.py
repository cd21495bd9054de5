"""The time-optimal planner: the C planner and the Python reference side by side in one run, medians and ratios.

Run ``python benchmarks/time_optimal_speed.py``: plans 0.1, 1, 5 and 20 rad at 24 V and 12 V (the limits of
flatstep.studies.plan_compare) and a 100-waypoint sequence with both engines, checks that they plan the same durations,
and prints the median times. ``python benchmarks/time_optimal_speed.py REV`` adds ``time_optimal.py`` as it was
at git revision ``REV`` (its relative imports made absolute) as a third column.
"""
import importlib.util
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from flatstep.bench.common import median_ms
from flatstep.model.motor import PRESETS
from flatstep.plan import time_optimal as now
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_c import plan_raw


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


def limits(bus):
    """The comparison's limits at bus voltage ``bus`` (a fresh object per call, as a caller would pass)."""
    return MotorLimits(v_bus=bus, i_max=1.0, i_run=0.025, v_use=0.84, torque_angle_max=1.1)


def main(rev=None):
    """Single moves, then the 100-waypoint sequence, with both engines (and revision ``rev``'s planner)."""
    motor, old = PRESETS["nema17"], load_old(rev) if rev else None
    for bus in (24.0, 12.0):
        lim = limits(bus)
        for d in (0.1, 1.0, 5.0, 20.0):
            c, py = now.time_optimal(d, motor, lim), now.time_optimal(d, motor, lim, engine="python")
            tables = plan_raw(d, motor, lim)[1].tables
            t_raw = median_ms(lambda d=d, lim=lim: plan_raw(d, motor, lim), 21)
            t_c = median_ms(lambda d=d, lim=lim: now.time_optimal(d, motor, lim), 21)
            t_py = median_ms(lambda d=d, lim=lim: now.time_optimal(d, motor, lim, engine="python"))
            line = (f"{bus:g} V {d:g} rad: C {1e3 * t_raw:.0f} us ({tables} tables, {1e3 * t_raw / tables:.0f} us "
                    f"each; {1e3 * t_c:.0f} us with the PiecewisePlan), Python {t_py:.1f} ms ({t_py / t_c:.0f} x), "
                    f"same duration: {abs(c.tf / py.tf - 1):.1e} ({1e3 * c.tf:.3f} ms)")
            if old:
                t_old = median_ms(lambda d=d, lim=lim: old.time_optimal(d, motor, lim), 3)
                line += f"; {rev} {t_old:.0f} ms ({1e3 * old.time_optimal(d, motor, lim).tf:.3f} ms)"
            print(line, flush=True)
    theta = np.cumsum(np.random.default_rng(0).uniform(-3, 5, 100))
    points = [(float(x), 0.0) for x in theta]
    c = now.time_optimal_sequence(points, motor, limits(24.0))
    py = now.time_optimal_sequence(points, motor, limits(24.0), engine="python")
    steps = [b[0] - a[0] for a, b in zip(points, points[1:], strict=False)]
    t_raw = median_ms(lambda: [plan_raw(step, motor, limits(24.0)) for step in steps], 5)
    t_c = median_ms(lambda: now.time_optimal_sequence(points, motor, limits(24.0)), 5)
    t_py = median_ms(lambda: now.time_optimal_sequence(points, motor, limits(24.0), engine="python"), 3)
    print(f"100 waypoints (99 moves, 24 V): C {t_raw:.1f} ms in time_optimal_plan, {t_c:.1f} ms with the "
          f"PiecewisePlan, Python {t_py:.0f} ms ({t_py / t_c:.0f} x), same duration: {abs(c.tf / py.tf - 1):.1e} "
          f"({c.tf:.4f} s)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
