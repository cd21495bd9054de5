"""Where the 4000-count encoder's error reaches the d-q law: each input given exactly, one at a time.

The field-weakening move of benchmarks/field_weakening_optimum.py (its motor, bus and distance, the designed gains
and observer, the 12-bit current ADC, the angle advance) run period by period as
:func:`flatstep.loop.reference.run_reference` runs it, but with chosen inputs of the law replaced by the plant's true
values: the currents, the angle of the Park transforms, the angle of the error ``e``, the speed, the acceleration.
Prints the largest |theta error| in the move.

    .venv/bin/python benchmarks/quantization_sources.py [--motor nema17] [--bus 12] [--distance 1]
        [--counts 4000] [--wn-scale 1.5] [--edge-timing] [--torque-ramp]
"""
from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from flatstep.bench.field_weakening import RATE, V_USE, adc_range, motor
from flatstep.control.dq_smc import DQFlatnessSMC, advance_of
from flatstep.loop.design import design_gains
from flatstep.loop.drive import Drive
from flatstep.loop.reference import _rk4
from flatstep.loop.sensors import Sensors
from flatstep.model.motor import torque
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_dq import time_optimal_dq

MOTORS = Path(__file__).resolve().parent.parent / "examples" / "motors"
CASES = [("nothing (the drive as it is)", ()), ("the currents (no 12-bit ADC)", ("currents",)),
         ("the angle of the Park transforms only", ("park",)), ("the angle of the error e only", ("error",)),
         ("the speed", ("speed",)), ("the acceleration", ("acceleration",)),
         ("angle, speed and acceleration", ("park", "error", "speed", "acceleration"))]


class _Shifted:
    """The plan with its angle moved by ``shift``: the law's error angle apart from its Park angle."""

    def __init__(self, plan: Any, shift: float) -> None:
        self.plan, self.shift = plan, shift

    def flag(self, t: Any) -> Any:
        f = self.plan.flag(t)
        return f._replace(theta=f.theta + self.shift)


def run(args: argparse.Namespace, exact: tuple[str, ...], counts: int) -> float:
    """The largest |theta - theta*| [rad] in the move with the ``exact`` inputs read from the plant."""
    m, i_max = motor(args.motor, MOTORS)
    limits = MotorLimits(v_bus=args.bus, i_max=i_max, i_hold=0.01 * i_max, v_use=V_USE)
    fw = time_optimal_dq(args.distance, m, limits, control_rate=RATE)
    plan, Ts = fw.plan, 1 / RATE
    sensors = Sensors(encoder_counts=counts, current_range=adc_range(i_max), edge_timing=args.edge_timing)
    d = design_gains(m, plan, control_period=Ts, v_bus=args.bus, encoder_counts=counts,
                     current_step=sensors.current_step)
    obs = replace(d.observer, torque_ramp=args.torque_ramp)
    ctrl = DQFlatnessSMC(m, plan, replace(d.gains, wn=d.gains.wn * args.wn_scale), "observer",
                         d_current=fw.d_current, advance=advance_of(Ts))
    Ad, Bd, Lc = obs.matrices(m, Ts)
    Bf, drive = obs.ramp(m, Ts), Drive(v_bus=args.bus)
    x, xh, te_prev, worst = np.array([0.0, 0.0, 0.0, plan.theta1]), None, None, 0.0
    for k in range(int(round(plan.tf / Ts)) + 1):
        t = k * Ts
        th_m = float(sensors.read_angle(x[3]))
        ia, ib = sensors.read_currents(x[:2])
        th_e, age = sensors.read_edge(float(x[3]), float(x[2]))
        if xh is None:
            xh = np.array([th_m] + [0.0] * (obs.order - 1))
        elif 0.0 <= age < Ts:
            xh = xh + Lc * (th_e - (xh[0] - xh[1] * age))
        else:
            xh = xh + Lc * (th_m - xh[0])
        te = torque((ia, ib, xh[1], xh[0]), m)
        y = np.array([ia, ib, xh[1], xh[0], (te - m.B * xh[1] - xh[2]) / m.J])
        if "currents" in exact:
            y[0], y[1] = x[0], x[1]
        if "speed" in exact:
            y[2] = x[2]
        if "acceleration" in exact:
            y[4] = (torque(x, m) - m.B * x[2]) / m.J
        park, error = ("park" in exact), ("error" in exact)
        shift = (x[3] - y[3]) * (park - error)  # e = (angle read) - (theta* + shift)
        if park:
            y[3] = x[3]
        ctrl.plan = _Shifted(plan, shift)
        v, _ = ctrl.step(None, y, t)
        if t >= plan.t0:
            worst = max(worst, abs(x[3] - float(plan.flag(t).theta)))
        v = drive.saturate(v)
        for _ in range(4):
            x = _rk4(x, v, Ts / 4, m, 0.0)
        xh = Ad @ xh + Bd * te + Bf * (0.0 if te_prev is None else te - te_prev)
        te_prev = float(te)
    return worst


def main() -> None:
    """Print one row per case."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--motor", default="nema17")
    ap.add_argument("--bus", type=float, default=12.0)
    ap.add_argument("--distance", type=float, default=1.0)
    ap.add_argument("--counts", type=int, default=4000)
    ap.add_argument("--wn-scale", type=float, default=1.5)
    ap.add_argument("--edge-timing", action="store_true")
    ap.add_argument("--torque-ramp", action="store_true")
    a = ap.parse_args()
    print(f"{'the law reads exactly':42s} {'err mrad':>8s}")
    for name, exact in CASES:
        print(f"{name:42s} {run(a, exact, a.counts) * 1e3:8.3f}", flush=True)
    print(f"{'nothing, with a 2^24-count encoder':42s} {run(a, (), 1 << 24) * 1e3:8.3f}", flush=True)


if __name__ == "__main__":
    main()
