"""Planner timings of docs/planning.md: median of repeated runs, side by side.

Run ``.venv/bin/python benchmarks/plan_timing.py``.
"""
import numpy as np

from flatstep.bench.common import median_ms
from flatstep.core.traj import traj_flag
from flatstep.model.motor import PRESETS
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal import time_optimal
from flatstep.plan.waypoints import Caps, plan_waypoints

motor = PRESETS["nema17"]
limits = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.1, v_use=0.87)
for d in (0.1, 5.0):
    # a fresh limits object each call, so that the envelope cache does not carry over between repeats
    ms = median_ms(lambda d=d: time_optimal(d, motor, limits.__class__(**limits.as_dict())))
    print(f"time_optimal {d:g} rad: {ms:.1f} ms")
waypoints = np.cumsum(np.random.default_rng(0).uniform(-3, 5, 100))
caps = Caps(60.0, 8000.0, 2e6)
for family in ("psi", "hermite", "spline", "scurve"):
    ms = median_ms(lambda family=family: plan_waypoints(waypoints, family=family, caps=caps))
    print(f"plan_waypoints 100 waypoints, {family}: {ms:.1f} ms")
plan = plan_waypoints(waypoints, family="hermite", caps=caps)
t = np.linspace(plan.t0, plan.tf, 1_000_000)
c_ms, py_ms = median_ms(lambda: traj_flag(plan, t), 5), median_ms(lambda: plan.flag(t), 3)
print(f"flag at 1e6 times over 99 segments: C traj_flag_n {c_ms:.1f} ms ({c_ms:.1f} ns/sample), "
      f"NumPy {py_ms:.1f} ms ({py_ms:.1f} ns/sample), ratio {py_ms / c_ms:.1f}")
