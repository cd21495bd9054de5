"""The field-weakening planner against the true optimum, and its plans tracked on a 20 kHz drive.

For each motor, bus and move: the planned duration of :func:`flatstep.plan.time_optimal_dq.time_optimal_dq`, the
minimum time of the same problem by direct collocation (:func:`flatstep.bench.collocation.minimum_time`, the
``--voltage`` bus, i_d free, the planner's speed cap, rest at i_d = i_hold = 0.01 i_max, the planner's rest being
i_d = 0), their ratio, the C planner's CPU time (median of 5 calls) and the shots it fitted, and the plan run by
the d-q law (designed gains, observer, encoder, 12-bit current ADC) on the nominal plant on the C engine at 20 kHz:
its status and the largest angle error during the move.

    .venv/bin/python benchmarks/field_weakening_optimum.py [--motors nema17 ldo-42sth60-2004mac ...]
        [--bus 12 24] [--distances 0.3 1 5 20] [--grid 200] [--counts 4000] [--voltage vector]
        [--no-advance] [--no-optimum] [--wn-scale 1.5] [--no-edge-timing] [--no-torque-ramp]
        [--bandwidth-scale 0.4]

Needs the bench extra (CasADi). Motors are the ``nema17`` preset (at 1 A) or the stems of examples/motors/*.toml (at
their rated current norm). The law turns its voltage by the angle of half a control period (``advance``,
:func:`flatstep.control.dq_smc.advance_of`) unless ``--no-advance``; the 12-bit current sensor spans
:func:`flatstep.bench.field_weakening.adc_range` of i_max (the drive: that module); ``--no-optimum`` skips the
collocation (its columns print as ``-``); ``--wn-scale`` multiplies the designed error dynamics' ``wn`` of the law
(default 1: ``design_gains`` as it is) and ``--bandwidth-scale`` the designed observer's bandwidth (default 1). The
encoder latches its count edges (``Sensors(edge_timing=True)``) unless ``--no-edge-timing``, and the observer
predicts with the torque's ramp (``Observer(torque_ramp=True)``) unless ``--no-torque-ramp`` (docs/controllers.md,
"Quantization").
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from flatstep.bench.collocation import minimum_time
from flatstep.bench.field_weakening import RATE, V_USE, motor, track
from flatstep.model.motor import MotorParams
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_dq import speed_cap, time_optimal_dq
from flatstep.plan.time_optimal_dq_c import plan_raw

MOTORS = Path(__file__).resolve().parent.parent / "examples" / "motors"


def plan_time(dist: float, m: MotorParams, limits: MotorLimits) -> tuple[float, int]:
    """The median CPU time [us] of 5 calls of the C planner (time_optimal_dq_plan, through cffi) and its shots.

    The thread's CPU time, not the wall clock: on a shared machine the wall clock counts the other processes' turns.
    """
    times = []
    for _ in range(5):
        t = time.thread_time()
        _, out = plan_raw(dist, m, limits, RATE)
        times.append((time.thread_time() - t) * 1e6)
    return float(np.median(times)), int(out.tables)


def main() -> None:
    """Print one row per motor, bus and move."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--motors", nargs="+", default=["nema17", "ldo-42sth60-2004mac", "sanyo-103h5208-5240"])
    ap.add_argument("--bus", nargs="+", type=float, default=[12.0, 24.0])
    ap.add_argument("--distances", nargs="+", type=float, default=[0.1, 0.3, 1.0, 5.0, 20.0])
    ap.add_argument("--grid", type=int, default=200)
    ap.add_argument("--voltage", choices=("vector", "phase"), default="vector",
                    help="the bus limit of both the plan and the optimum (default vector)")
    ap.add_argument("--counts", type=int, default=4000, help="encoder counts per revolution (default 4000)")
    ap.add_argument("--no-advance", action="store_true",
                    help="the d-q law without its angle advance (the voltage at the measured angle)")
    ap.add_argument("--no-optimum", action="store_true", help="skip the collocation optimum (tracking only)")
    ap.add_argument("--wn-scale", type=float, default=1.0,
                    help="multiply the designed wn of the law's error dynamics (default 1)")
    ap.add_argument("--no-edge-timing", action="store_true",
                    help="the encoder without its count edges' times (the count alone)")
    ap.add_argument("--no-torque-ramp", action="store_true",
                    help="the observer predicts with the torque held over the period")
    ap.add_argument("--bandwidth-scale", type=float, default=1.0,
                    help="multiply the designed observer's bandwidth (default 1)")
    a = ap.parse_args()
    print(f"{'motor':22s} {'bus':>4s} {'rad':>5s} {'plan ms':>9s} {'opt ms':>9s} {'ratio':>6s} {'cap':>5s} "
          f"{'w_pk':>5s} {'id_min':>6s} {'plan us':>8s} {'shots':>6s} {'status':>7s} {'err mrad':>8s}")
    for name in a.motors:
        m, i_max = motor(name, MOTORS)
        for v_bus in a.bus:
            limits = MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.01 * i_max, v_use=V_USE)
            cap = speed_cap(m, limits, RATE)
            for dist in a.distances:
                fw = time_optimal_dq(dist, m, limits, control_rate=RATE, voltage=a.voltage)
                plan_us, tables = plan_time(dist, m, limits)
                status, err = track(m, fw, v_bus, a.counts, not a.no_advance, i_max, a.wn_scale,
                                    not a.no_edge_timing, not a.no_torque_ramp, a.bandwidth_scale)
                tf = fw.plan.tf - fw.plan.t0
                if a.no_optimum:
                    opt_ms, ratio = f"{'-':>9s}", f"{'-':>6s}"
                else:
                    opt = minimum_time(dist, m, MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.01 * i_max,
                                                            v_use=V_USE, speed_max=cap), voltage=a.voltage,
                                       grid=a.grid)
                    opt_ms, ratio = f"{opt.tf * 1e3:9.3f}", f"{tf / opt.tf:6.3f}"
                print(f"{name:22s} {v_bus:4.0f} {dist:5.1f} {tf * 1e3:9.3f} {opt_ms} {ratio} "
                      f"{cap:5.0f} {fw.found.margins['speed_peak']:5.0f} {fw.found.margins['i_d_min']:6.2f} "
                      f"{plan_us:8.0f} {tables:6d} {status:>7s} {err * 1e3:8.3f}", flush=True)
                if not math.isfinite(err):
                    print("  (the run did not finish)")


if __name__ == "__main__":
    main()
