"""The time-optimal planners against the true optimum and the fair baselines, per motor, bus and move.

For each motor (the NEMA 17 preset at 1 A and datasheet files of examples/motors/ at their rated current norm),
bus and move, under the limits of docs/planning.md's comparison (``v_use`` 0.84, ``i_hold`` 0.3 ``i_max``,
``i_run`` 0.025 ``i_max``, torque angle 1.1 rad, the bus limit on the voltage vector's norm):

* flatstep: :func:`flatstep.plan.time_optimal.time_optimal` (the paper's (rho, theta) law's plans), and the
  field-weakening planner ``flatstep.plan.time_optimal_dq`` where the tree has it;
* the optimum: :func:`flatstep.bench.collocation.grid_converged` (direct collocation, CasADi + IPOPT) with
  ``i_d`` free (field weakening) and with ``i_d = 0``; the change between its two grids is printed;
* the fair baselines of :mod:`flatstep.bench.fair_baselines`: Ruckig with ``i_d = 0`` and a trapezoid with field
  weakening, each at its best caps;
* each of flatstep's, Ruckig's and the trapezoid's plans tracked on the 20 kHz drive
  (:mod:`flatstep.bench.drive_tracking`): the largest error during the move and the run's status.

    .venv/bin/python benchmarks/time_optimal_yardstick.py                     # 3 motors x 24, 12 V x 5 moves
    .venv/bin/python benchmarks/time_optimal_yardstick.py --motors nema17 --buses 24 --moves 1,5 --no-track
    .venv/bin/python benchmarks/time_optimal_yardstick.py --detent            # the optimum with the detent
    .venv/bin/python benchmarks/time_optimal_yardstick.py --voltage phase     # each phase within v_use v_bus

Durations in ms; a ratio over 1 is flatstep slower than the other.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Optional

from flatstep.bench.collocation import grid_converged
from flatstep.bench.drive_tracking import track
from flatstep.bench.fair_baselines import best_ruckig, best_trapezoid
from flatstep.model.datasheet import motor_from_table
from flatstep.model.motor import MotorParams
from flatstep.model.plant import PlantEffects
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal import time_optimal

ROOT = Path(__file__).resolve().parents[1]
MOTORS = ("nema17", "jkongmotor-jk42hs34-0844ya-01", "ldo-42sth40-1684ac")
MOVES = (0.1, 0.3, 1.0, 5.0, 20.0)
BUSES = (24.0, 12.0)
GRIDS = (300, 600)
CONTROL_RATE = 20000.0


def load_motor(name: str) -> tuple[MotorParams, float, float]:
    """(motor, i_max [A], detent torque [N m]): the preset at 1 A, or a datasheet file at its rated current norm."""
    if name == "nema17":
        return MotorParams.preset("nema17"), 1.0, 0.015
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    path = Path(name) if name.endswith(".toml") else ROOT / "examples" / "motors" / f"{name}.toml"
    model = motor_from_table(tomllib.loads(path.read_text())["motor"], str(path))
    return model.params, model.rated_rho, float(model.datasheet.get("detent_torque") or 0.0)


def limits_for(v_bus: float, i_max: float) -> MotorLimits:
    """docs/planning.md's comparison limits, scaled to ``i_max``."""
    return MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.3 * i_max, i_run=0.025 * i_max, v_use=0.84,
                       torque_angle_max=1.1)


def field_weakening_planner() -> Optional[Any]:
    """The field-weakening planner's module, or None when the tree does not have it."""
    try:
        from flatstep.plan import time_optimal_dq  # type: ignore[attr-defined]
    except ImportError:
        return None
    return time_optimal_dq


def case(motor: MotorParams, limits: MotorLimits, d: float, *, effects: PlantEffects, tracking: bool,
         fw: Optional[Any], voltage: str = "vector") -> dict[str, Any]:
    """One motor, bus and move: every planner's duration [s], the optima, the baselines and the tracking."""
    row: dict[str, Any] = {}
    try:
        plan = time_optimal(d, motor, limits)
        row["flatstep"] = plan.tf - plan.t0
    except ValueError as exc:
        plan, row["flatstep"], row["flatstep_error"] = None, math.nan, str(exc)
    for key, weak in (("optimum", True), ("optimum_id0", False)):
        try:
            c = grid_converged(d, motor, limits, grids=GRIDS, field_weakening=weak, effects=effects, voltage=voltage)
            row[key], row[f"{key}_change"], row[f"{key}_peaks"] = c.fine.tf, c.change, c.fine.peaks()
        except ValueError as exc:  # printed as "-", the reason kept in the JSON
            row[key], row[f"{key}_change"], row[f"{key}_error"] = math.nan, math.nan, str(exc)
            row[f"{key}_peaks"] = dict(speed_peak=math.nan, i_d_min=math.nan)
    if fw is not None:
        cap = fw.speed_cap(motor, limits, CONTROL_RATE)
        try:
            row["fw_planner"] = fw.plan_dq_move(d, motor, limits, voltage="vector", control_rate=CONTROL_RATE).tf
        except ValueError as exc:
            row["fw_planner"], row["fw_planner_error"] = math.nan, str(exc)
        capped = MotorLimits(**{**limits.as_dict(), "speed_max": cap})
        c = grid_converged(d, motor, capped, grids=GRIDS, i_rest=0.0, effects=effects, voltage=voltage)
        row["optimum_fw_problem"], row["optimum_fw_problem_change"], row["speed_cap"] = c.fine.tf, c.change, cap
    ruckig, trap = best_ruckig(d, motor, limits), best_trapezoid(d, motor, limits)
    row["ruckig"], row["ruckig_caps"], row["ruckig_margins"] = ruckig.duration, ruckig.caps, ruckig.margins
    row["trapezoid"], row["trapezoid_caps"], row["trapezoid_margins"] = trap.duration, trap.caps, trap.margins
    if tracking:
        if plan is not None:
            row["track_flatstep"] = track(plan, motor, limits.v_bus)
        row["track_ruckig"] = track(ruckig.plan, motor, limits.v_bus, ruckig.d_current)
        row["track_trapezoid"] = track(trap.plan, motor, limits.v_bus, trap.d_current)
    return row


def _ms(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{1e3 * x:.2f}"


def _ratio(a: float, b: float) -> str:
    return "-" if not (math.isfinite(a) and math.isfinite(b)) else f"{a / b:.3f}"


def print_tables(rows: list[dict[str, Any]], fw: bool) -> None:
    """The durations, ratios and tracking as markdown tables (docs/planning.md)."""
    head = ["motor", "bus", "move", "flatstep", "optimum", "flatstep / optimum", "optimum i_d=0",
            "flatstep / optimum i_d=0", "Ruckig i_d=0", "flatstep / Ruckig", "trapezoid FW", "flatstep / trapezoid",
            "grid change (free / i_d=0)", "optimum peak speed, least i_d"]
    if fw:
        head[4:4] = ["FW planner", "FW planner / its optimum"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        f = r["flatstep"]
        cells = [r["motor"], f"{r['v_bus']:g} V", f"{r['move']:g} rad", _ms(f), _ms(r["optimum"]),
                 _ratio(f, r["optimum"]), _ms(r["optimum_id0"]), _ratio(f, r["optimum_id0"]), _ms(r["ruckig"]),
                 _ratio(f, r["ruckig"]), _ms(r["trapezoid"]), _ratio(f, r["trapezoid"]),
                 f"{100 * r['optimum_change']:.3f} % / {100 * r['optimum_id0_change']:.3f} %",
                 f"{r['optimum_peaks']['speed_peak']:.0f} rad/s, {r['optimum_peaks']['i_d_min']:.2f} A"]
        if fw:
            cells[4:4] = [_ms(r["fw_planner"]), _ratio(r["fw_planner"], r["optimum_fw_problem"])]
        print("| " + " | ".join(cells) + " |")
    if not any("track_ruckig" in r for r in rows):
        return
    print("\n| motor | bus | move | planner | duration [ms] | max error during the move [mrad] | status "
          "| saturated periods | peak phase voltage [V] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        for name in ("flatstep", "ruckig", "trapezoid"):
            t = r.get(f"track_{name}")
            if t is None:
                continue
            print(f"| {r['motor']} | {r['v_bus']:g} V | {r['move']:g} rad | {name} | {_ms(r[name])} | "
                  f"{1e3 * t['max_error']:.3f} | {t['status']} | {100 * t['saturated']:.1f} % | {t['v_peak']:.2f} |")


def main() -> int:
    """Run the cases of the command line and print the tables (or the rows as JSON)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--motors", default=",".join(MOTORS), help="nema17 and examples/motors/ names or .toml files")
    parser.add_argument("--buses", default=",".join(f"{b:g}" for b in BUSES), help="bus voltages [V]")
    parser.add_argument("--moves", default=",".join(f"{m:g}" for m in MOVES), help="distances [rad]")
    parser.add_argument("--no-track", action="store_true", help="skip the runs on the 20 kHz drive")
    parser.add_argument("--detent", action="store_true", help="the optimum with the motor's detent torque")
    parser.add_argument("--voltage", choices=("vector", "phase"), default="vector",
                        help="the optimum's bus limit: the voltage vector's norm (the planners'), or each phase's")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON instead of the tables")
    args = parser.parse_args()
    fw = field_weakening_planner()
    rows = []
    start = time.perf_counter()
    for name in args.motors.split(","):
        motor, i_max, detent = load_motor(name)
        effects = PlantEffects(detent_torque=detent if args.detent else 0.0)
        for v_bus in (float(b) for b in args.buses.split(",")):
            limits = limits_for(v_bus, i_max)
            for d in (float(m) for m in args.moves.split(",")):
                row = dict(motor=Path(name).stem, v_bus=v_bus, move=d, i_max=i_max,
                           **case(motor, limits, d, effects=effects, tracking=not args.no_track, fw=fw,
                                voltage=args.voltage))
                rows.append(row)
                print(f"{row['motor']} {v_bus:g} V {d:g} rad: flatstep {_ms(row['flatstep'])} ms, optimum "
                      f"{_ms(row['optimum'])} ms ({time.perf_counter() - start:.0f} s)", file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps(rows, indent=1, default=float))
    else:
        print_tables(rows, fw is not None)
        print(f"\n{len(rows)} cases in {time.perf_counter() - start:.0f} s; grids {GRIDS}; "
              f"field-weakening planner: {'yes' if fw is not None else 'not in this tree'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
