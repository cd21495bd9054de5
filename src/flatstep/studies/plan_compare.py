r"""The comparison of docs/planning.md: flatstep's time-optimal plan against a trapezoid and a Ruckig profile.

Same motor (the NEMA 17 preset), same bus, same current and torque-angle limits
(:class:`~flatstep.plan.limits.MotorLimits`); each baseline at its best constant caps
(:func:`~flatstep.plan.baselines.best_baseline`) with a fixed holding current and its feedforward within 90 % of
the bus, flatstep's plan with the across-axis current planned down to ``i_run`` = :data:`I_RUN` at speed (plus
what the torque angle's cap asks for, :meth:`~flatstep.plan.limits.MotorLimits.across`) and its feedforward within
``v_use`` = :data:`V_USE` of the bus (the headroom the drive's feedback needs at speed: at 20 kHz it carries up to
0.06 A more than planned, whose reactance takes about 2 V at the top speed; docs/planning.md). Every plan is
tracked on the 20 kHz drive (bus, 14-bit encoder, 12-bit current ADC, observer, gains of
:func:`~flatstep.loop.design.design_gains`). Run::

    python -m flatstep.studies.plan_compare --out docs/figures

It prints the tables of docs/planning.md and writes ``planning_compare.png`` and ``planning_compare.json``.
"""
from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional, Sequence, cast

import numpy as np

from ..model.motor import PRESETS, MotorParams
from ..plan.baselines import KINDS, best_baseline, ruckig_duration
from ..plan.limits import MotorLimits
from ..plan.margins import plan_margins
from ..plan.piecewise import PiecewisePlan
from ..plan.time_optimal import bang_bang_time, time_optimal

DISTANCES = (0.1, 0.3, 1.0, 2.0, 5.0, 10.0, 20.0)
SEQUENCE = (0.0, 2.0, 5.0, 4.0, 10.0, 0.5, 1.0, -3.0, 6.0, 6.5)
PLANNERS = ("flatstep",) + KINDS
#: flatstep's defaults: the across-axis current at speed [A] and the share of the bus its feedforward may use, the
#: pair of a sweep (docs/planning.md) that meets 20 % shorter than Ruckig from 5 rad on with no clipped period
I_RUN, V_USE = 0.025, 0.84
#: flatstep's cap on the torque angle [rad], below the baselines' :data:`BASELINE_TORQUE_ANGLE`: at 1.2 rad the
#: 0.3 rad move's law reached its singularity on the drive (the planned i_d = i_q cot 1.2 left too little margin)
TORQUE_ANGLE = 1.1
#: the baselines' (and MotorLimits') torque-angle cap [rad]
BASELINE_TORQUE_ANGLE = 1.2


def track(plan: PiecewisePlan, motor: MotorParams, v_bus: float) -> dict[str, float]:
    """The plan on the 20 kHz drive: max |theta - theta*|, peak phase voltage, share of saturated periods, loss."""
    from ..control.smc import FlatnessSMC
    from ..engine.simulate import simulate
    from ..loop.design import design_gains
    from ..loop.drive import Drive
    from ..loop.reference import DriveLoop
    from ..loop.sensors import Sensors

    d = design_gains(motor, cast(Any, plan), control_period=5e-5, v_bus=v_bus)
    loop = DriveLoop(control_period=5e-5, substeps=4, drive=Drive(v_bus=v_bus), sensors=Sensors(),
                     observer=d.observer)
    r = simulate(motor, plan, FlatnessSMC(motor, plan, d.gains, "observer"), loop=loop, t_end=plan.tf + 0.02)
    peak = np.max(np.abs([r.va, r.vb]), axis=0)
    i2 = r.ia**2 + r.ib**2
    return dict(max_error=float(np.max(np.abs(r.theta - r.theta_ref))), v_peak=float(peak.max()),
                saturated=float(np.mean(peak >= v_bus * (1 - 1e-9))),
                copper_loss=float(motor.R * np.sum(0.5 * (i2[1:] + i2[:-1]) * np.diff(r.t))),
                faults=float(r.meta.get("controller_faults", 0)))


def baseline_limits(limits: MotorLimits) -> MotorLimits:
    """The baselines' limits: a fixed holding current, the feedforward within 90 % of the bus."""
    return replace(limits, i_run=None, v_use=0.9, torque_angle_max=BASELINE_TORQUE_ANGLE)


def plans_for(distance: float, motor: MotorParams, limits: MotorLimits) -> dict[str, PiecewisePlan]:
    """The time-optimal plan and both baselines at their best over ``distance``, each from t = 5 ms."""
    fixed = baseline_limits(limits)
    out = {"flatstep": time_optimal(distance, motor, limits, t0=0.005)}
    for kind in KINDS:
        plan, caps = best_baseline(kind, distance, motor, fixed)
        out[kind] = PiecewisePlan(plan.breaks + 0.005, plan.theta, plan.rho)
        if kind == "ruckig":  # the table's duration is Ruckig's own for these caps
            assert abs(ruckig_duration(distance, **caps) - plan.tf) < 1e-9 * max(1.0, plan.tf)
    return out


def sequence_plans(motor: MotorParams, limits: MotorLimits) -> dict[str, PiecewisePlan]:
    """The 10-waypoint sequence, resting at each waypoint, by each planner (moves planned one by one)."""
    fixed = baseline_limits(limits)
    out: dict[str, PiecewisePlan] = {}
    for name in PLANNERS:
        moves: list[PiecewisePlan] = []
        t = 0.005
        for a, b in zip(SEQUENCE[:-1], SEQUENCE[1:], strict=True):
            if name == "flatstep":
                moves.append(time_optimal(b - a, motor, limits, theta1=a, t0=t))
            else:
                base, _ = best_baseline(name, b - a, motor, fixed)
                th = base.theta.copy()
                th[:, -1] += a
                moves.append(PiecewisePlan(base.breaks + t, th, base.rho))
            t = moves[-1].tf
        out[name] = PiecewisePlan.concatenate(moves)
    return out


def _row(label: str, plans: dict[str, PiecewisePlan], motor: MotorParams, limits: MotorLimits,
         bound: Optional[float]) -> dict[str, Any]:
    """One table row: each planner's duration, margins and tracking."""
    row: dict[str, Any] = {"case": label, "bound": bound}
    for name, plan in plans.items():
        m = plan_margins(plan, motor, limits if name == "flatstep" else baseline_limits(limits))
        row[name] = dict(duration=plan.tf - plan.t0, voltage=m["voltage"], current=m["current"], speed=m["speed_peak"],
                         **track(plan, motor, limits.v_bus))
    row["ratio_ruckig"] = row["flatstep"]["duration"] / row["ruckig"]["duration"]
    row["ratio_trapezoid"] = row["flatstep"]["duration"] / row["trapezoid"]["duration"]
    return row


def _print(rows: list[dict[str, Any]], v_bus: float) -> None:
    """The rows as the markdown tables of docs/planning.md."""
    print(f"\n### {v_bus:g} V: move time [ms] and ratio\n")
    print("| move | bang-bang bound | flatstep | trapezoid | Ruckig | flatstep / Ruckig | flatstep / trapezoid "
          "| peak speed flatstep / Ruckig [rad/s] |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        bound = "-" if r["bound"] is None else f"{1e3 * r['bound']:.2f}"
        print(f"| {r['case']} | {bound} | {1e3 * r['flatstep']['duration']:.2f} | "
              f"{1e3 * r['trapezoid']['duration']:.2f} | {1e3 * r['ruckig']['duration']:.2f} | "
              f"{r['ratio_ruckig']:.3f} | {r['ratio_trapezoid']:.3f} | "
              f"{r['flatstep']['speed']:.1f} / {r['ruckig']['speed']:.1f} |")
    print(f"\n### {v_bus:g} V: tracked on the 20 kHz drive\n")
    print("| move | planner | max error [mrad] | peak phase voltage [V] | saturated periods | copper loss [mJ] "
          "| planned voltage / bus | faults |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        for name in PLANNERS:
            p = r[name]
            print(f"| {r['case']} | {name} | {1e3 * p['max_error']:.3f} | {p['v_peak']:.2f} | "
                  f"{100 * p['saturated']:.1f} % | {1e3 * p['copper_loss']:.2f} | {p['voltage']:.3f} | "
                  f"{int(p['faults'])} |")


def plot(results: dict[str, list[dict[str, Any]]], path: Path) -> None:
    """planning_compare.png: move time against distance for each planner and bus, and the ratio to Ruckig."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for (bus, rows), style in zip(results.items(), ("-", "--"), strict=False):
        moves = [r for r in rows if r["case"] != "10 waypoints"]
        d = [float(r["case"].split()[0]) for r in moves]
        for name, color in zip(PLANNERS, ("C0", "C1", "C2"), strict=True):
            ax[0].loglog(d, [1e3 * r[name]["duration"] for r in moves], style, color=color, marker="o", ms=3,
                         label=f"{name}, {bus}")
        ax[0].loglog(d, [1e3 * r["bound"] for r in moves], style, color="0.6", label=f"bang-bang bound, {bus}")
        ax[1].semilogx(d, [r["ratio_ruckig"] for r in moves], style, color="C0", marker="o", label=f"{bus}")
    ax[0].set_xlabel("move [rad]")
    ax[0].set_ylabel("move time [ms]")
    ax[0].legend(fontsize=7)
    ax[1].axhline(0.8, color="k", ls=":", lw=1, label="target: 20 % shorter")
    ax[1].set_xlabel("move [rad]")
    ax[1].set_ylabel("flatstep / best Ruckig")
    ax[1].legend(fontsize=8)
    fig.suptitle("NEMA 17 preset: time-optimal plan vs the best-limited trapezoid and Ruckig profiles")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the comparison (module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m flatstep.studies.plan_compare", description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="docs/figures", help="where the figure and the JSON go")
    parser.add_argument("--i-run", type=float, default=I_RUN,
                        help=f"flatstep's across-axis current at speed [A] (default {I_RUN:g})")
    parser.add_argument("--v-use", type=float, default=V_USE,
                        help=f"flatstep's share of the bus for its feedforward (default {V_USE:g})")
    parser.add_argument("--torque-angle", type=float, default=TORQUE_ANGLE,
                        help=f"flatstep's cap on the torque angle [rad] (default {TORQUE_ANGLE:g}; the baselines' "
                        f"is {BASELINE_TORQUE_ANGLE:g})")
    args = parser.parse_args(argv)
    motor = PRESETS["nema17"]
    results: dict[str, list[dict[str, Any]]] = {}
    start = time.perf_counter()
    for v_bus in (24.0, 12.0):
        limits = MotorLimits(v_bus=v_bus, i_max=1.0, i_run=args.i_run, v_use=args.v_use,
                             torque_angle_max=args.torque_angle)
        rows = [_row(f"{d:g} rad", plans_for(d, motor, limits), motor, limits, bang_bang_time(d, motor, limits))
                for d in DISTANCES]
        rows.append(_row("10 waypoints", sequence_plans(motor, limits), motor, limits, None))
        results[f"{v_bus:g} V"] = rows
        _print(rows, v_bus)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    plot(results, out / "planning_compare.png")
    (out / "planning_compare.json").write_text(json.dumps(results, indent=1) + "\n")
    print(f"\nwrote {out / 'planning_compare.png'} and {out / 'planning_compare.json'} "
          f"in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
