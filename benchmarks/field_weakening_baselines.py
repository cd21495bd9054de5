"""The field-weakening planner against the fair baselines under the same limits, each tracked on the same drive.

For each motor, bus and move: the planned duration of :func:`flatstep.plan.time_optimal_dq.time_optimal_dq` and
of the two fair baselines of :mod:`flatstep.bench.fair_baselines` under the same limits (the bus share, ``i_max``
and the planner's speed cap from the control rate): Ruckig with ``i_d = 0``, its three caps searched on a grid,
and a trapezoid with field weakening, its caps and weakening searched; the ratios (above 1: the planner slower);
and each plan run by the d-q law on the 20 kHz drive of the planner's benchmark (:mod:`flatstep.bench.field_weakening`:
designed gains and observer, 4000-count encoder with its count edges' times, 12-bit current sensor, from rest at
zero current): the largest angle error during the move and the status.

    .venv/bin/python benchmarks/field_weakening_baselines.py [--motors nema17 ldo-42sth60-2004mac ...]
        [--bus 12 24] [--distances 0.3 1 5 20]

The collocation optimum of the same moves is benchmarks/field_weakening_optimum.py's (docs/planning.md section 8).
Needs the bench extra (Ruckig).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from flatstep.bench.fair_baselines import best_ruckig, best_trapezoid
from flatstep.bench.field_weakening import RATE, V_USE, motor, track
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_dq import speed_cap, time_optimal_dq

MOTORS = Path(__file__).resolve().parent.parent / "examples" / "motors"


def tracked(run: tuple[str, float]) -> str:
    """The error [mrad] and the status of a tracked run, for one column."""
    status, err = run
    return f"{err * 1e3:9.3f} {status:>7s}" if math.isfinite(err) else f"{'nan':>9s} {'failed':>7s}"


def main() -> None:
    """Print one row per motor, bus and move."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--motors", nargs="+", default=["nema17", "ldo-42sth60-2004mac", "sanyo-103h5208-5240"])
    ap.add_argument("--bus", nargs="+", type=float, default=[12.0, 24.0])
    ap.add_argument("--distances", nargs="+", type=float, default=[0.1, 0.3, 1.0, 5.0, 20.0])
    a = ap.parse_args()
    print(f"{'motor':22s} {'bus':>4s} {'rad':>5s} {'cap':>5s} {'plan ms':>9s} {'ruckig':>9s} {'/ruckig':>7s} "
          f"{'trap FW':>9s} {'/trap':>6s} "
          + " ".join(f"{k + ' mrad':>9s} {'status':>7s}" for k in ("plan", "ruck", "trap")))
    for name in a.motors:
        m, i_max = motor(name, MOTORS)
        for v_bus in a.bus:
            limits = MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.01 * i_max, v_use=V_USE)
            cap = speed_cap(m, limits, RATE)
            capped = MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.01 * i_max, v_use=V_USE, speed_max=cap)
            for dist in a.distances:
                fw = time_optimal_dq(dist, m, limits, control_rate=RATE)
                tf = fw.plan.tf - fw.plan.t0
                ruckig, trap = best_ruckig(dist, m, capped), best_trapezoid(dist, m, capped)
                runs = [track(m, p, v_bus, i_max=i_max) for p in (fw, ruckig, trap)]
                print(f"{name:22s} {v_bus:4.0f} {dist:5.1f} {cap:5.0f} {tf * 1e3:9.3f} "
                      f"{ruckig.duration * 1e3:9.3f} {tf / ruckig.duration:7.3f} {trap.duration * 1e3:9.3f} "
                      f"{tf / trap.duration:6.3f} " + " ".join(tracked(r) for r in runs), flush=True)


if __name__ == "__main__":
    main()
