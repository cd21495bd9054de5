"""The fastest 10-revolution move (62.83 rad) of many motors on 24 V, checked and simulated on a 20 kHz drive.

Each motor runs the journey of docs/your-motor.md from one scenario file (:func:`journey_file`): its datasheet
``[motor]`` table, ``[limits]`` derived for the drive by :meth:`flatstep.plan.limits.MotorLimits.for_drive` (i_max
the rated current-vector norm), a time-optimal plan, a 20 kHz drive on 24 V with a 4000-count encoder and a 12-bit
current ADC, and the journey's controller (``[controller] design = true``: the sliding law with gains and observer
designed for the motor, plan and drive). For each motor it prints:

* what ``flatstep plan FILE`` reports (:func:`flatstep.studies.backoff.check_on_drive`: the file's scenario on the
  nominal plant and the 16 corners of +-10 % on R, L, Km, J, backed off where a case is lost or faults): the plan's
  duration, verified or refused, the plans made, the worst error, and what binds;
* for a verified plan, whether ``flatstep simulate FILE`` ends ok on every plant: the scenario
  ``flatstep simulate`` builds (``cli.plan.scenario_on_drive``, which checks it again) run on the nominal plant and on
  each of the 16 corners (:meth:`Scenario.run <flatstep.studies.scenario.Scenario.run>`).

    .venv/bin/python benchmarks/drive_verified_plans.py [--json] [examples/motors/*.toml]
    .venv/bin/python benchmarks/drive_verified_plans.py --table study.json   # the table of a --json run

Without motor files: the two presets and a NEMA 17 of 1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m holding, 68 g cm^2.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any, Optional

from flatstep.cli.plan import scenario_on_drive
from flatstep.model.datasheet import motor_from_table, uses_datasheet
from flatstep.model.motor import MotorParams
from flatstep.plan.limits import MotorLimits
from flatstep.studies.scenario import Scenario
from flatstep.studies.scenario_file import read_scenario_file
from flatstep.studies.backoff import check_on_drive
from flatstep.studies.verify import scenario_corners

DISTANCE = 62.83   # 10 revolutions [rad]
V_BUS = 24.0
RATE = 20000.0
COUNTS = 4000
UNCERTAINTY = 0.1
LIMIT_KEYS = ("i_hold", "speed_corner", "torque_angle_max", "v_use", "speed_max")


def nema17_168() -> dict[str, Any]:
    """A common NEMA 17 (1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m holding, 68 g cm^2, 1.8 deg), converted by hand.

    Km = holding torque / (sqrt(2) rated current): both phases at rated current hold sqrt(2) Km I.
    """
    return dict(R=1.65, L=2.8e-3, Km=0.44 / (math.sqrt(2) * 1.68), J=68e-7, B=1e-4, Nr=50)


def builtin_motors() -> list[tuple[str, dict[str, Any], float]]:
    """(name, [motor] table, i_max [A]): the presets at 1 A (their plan files' current) and the hand conversion."""
    return [("paper", {"preset": "paper"}, 1.0), ("nema17 preset", {"preset": "nema17"}, 1.0),
            ("NEMA 17 1.68 A", nema17_168(), 1.68)]


def file_motors(paths: list[str]) -> list[tuple[str, dict[str, Any], float]]:
    """(name, [motor] table, i_max) from datasheet files (flatstep.model.datasheet), i_max their rated norm."""
    out = []
    for p in paths:
        table = tomllib.loads(Path(p).read_text())["motor"]
        out.append((Path(p).stem, table, motor_from_table(table, p).rated_rho))
    return out


def _model(table: dict[str, Any], where: str) -> MotorParams:
    """The motor of a [motor] table: from its datasheet keys, a preset, or R, L, Km, J, B, Nr."""
    if uses_datasheet(table):
        return motor_from_table(table, where).params
    base = MotorParams.preset(table.get("preset", "paper"))
    return base.replace(**{k: v for k, v in table.items() if k != "preset"})


def _toml(value: Any) -> str:
    """A TOML value (numbers as Python prints them, strings quoted)."""
    return json.dumps(value) if isinstance(value, str) else repr(value)


def journey_file(name: str, table: dict[str, Any], i_max: float) -> str:
    """The scenario file of the journey for one motor (module docstring)."""
    motor = _model(table, name)
    lim = MotorLimits.for_drive(motor, v_bus=V_BUS, i_max=i_max, control_rate=RATE, encoder_counts=COUNTS,
                                uncertainty=UNCERTAINTY)
    current_range = math.ceil(1.25 * i_max)  # the ADC's full scale above the plan's largest phase current
    lines = [f"name = {_toml(name)}", "", "[motor]"] + [f"{k} = {_toml(v)}" for k, v in table.items()]
    lines += ["", "[limits]", f"i_max = {i_max!r}"] + [f"{k} = {getattr(lim, k)!r}" for k in LIMIT_KEYS]
    lines += [f"uncertainty = {UNCERTAINTY!r}", "", "[plan]", 'planner = "time_optimal"', "t0 = 0.005",
              f"waypoints = [0.0, {DISTANCE!r}]", "", "[drive]", f"control_rate = {RATE!r}", f"v_bus = {V_BUS!r}",
              "", "[sensors]", f"encoder_counts = {COUNTS}", "current_bits = 12",
              f"current_range = {float(current_range)!r}", "", "[controller]", 'type = "smc"', "design = true", ""]
    return "\n".join(lines)


def simulate_corners(path: Path, scenario: Optional[Scenario] = None) -> tuple[int, int, list[str]]:
    """``flatstep simulate``'s scenario for the file on the nominal plant and each corner: (ok, runs, statuses).

    ``scenario``: the checked scenario to run (``None``: as ``flatstep simulate`` builds it, checking it again).
    """
    scenario = scenario_on_drive(read_scenario_file(path)) if scenario is None else scenario
    statuses = [sc.run().status for _, sc in scenario_corners(scenario, UNCERTAINTY)]
    return sum(s == "ok" for s in statuses), len(statuses), statuses


def study_one(name: str, table: dict[str, Any], i_max: float, folder: Path, simulate: bool = True,
              recheck: bool = True) -> dict[str, Any]:
    """One motor's row: the check of ``flatstep plan`` and, for a verified plan, simulate on every plant.

    ``recheck``: simulate builds its scenario as ``flatstep simulate`` does (checking the file again); without,
    it runs the scenario the check returned (the same plan and law, half the time).
    """
    path = folder / f"{name.replace(' ', '-')}.toml"
    path.write_text(journey_file(name, table, i_max))
    start = time.perf_counter()
    sf = read_scenario_file(path)
    checked, info = check_on_drive(sf, sf.planner)
    rounds = info["rounds"]
    row: dict[str, Any] = dict(
        motor=name, duration=checked.plan.tf - checked.plan.t0 if info["verified"] else None,
        status="verified" if info["verified"] else "refused", controller=info["controller"], plants=info["plants"],
        cases=len(info["cases"]), bad=sum(c["status"] != "ok" for c in info["cases"]),
        worst_error=info["worst_error"], binds=info["binds"] or rounds[-1].get("refused"), rounds=len(rounds),
        advice=info["advice"], check_seconds=time.perf_counter() - start, history=rounds)
    if simulate and info["verified"]:
        start = time.perf_counter()
        ok, runs, statuses = simulate_corners(path, None if recheck else checked.scenario)
        row.update(simulate_ok=ok, simulate_runs=runs, simulate_statuses=statuses,
                   simulate_seconds=time.perf_counter() - start)
    return row


def study(motors: list[tuple[str, dict[str, Any], float]], simulate: bool = True,
          recheck: bool = True) -> list[dict[str, Any]]:
    """One row per motor (:func:`study_one`), the scenario files written in a temporary folder."""
    with tempfile.TemporaryDirectory() as tmp:
        return [study_one(name, table, i_max, Path(tmp), simulate, recheck) for name, table, i_max in motors]


def table(rows: list[dict[str, Any]]) -> str:
    """The study as a Markdown table: motor, duration, status, plans, worst error, simulate, time, what binds."""
    lines = ["| motor | duration [s] | status | plans | worst error [rad] | simulate ok | time [s] | binds |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        dur = f"{r['duration']:.4f}" if r["duration"] is not None else "-"
        err = f"{r['worst_error']:.3g}" if r["worst_error"] is not None else "-"
        sim = f"{r['simulate_ok']}/{r['simulate_runs']}" if "simulate_ok" in r else "-"
        first = r["history"][0]
        note = r["binds"] or (f"backed off from {first['duration']:.4f} s ({first['binds']})" if r["rounds"] > 1
                              else "")
        seconds = r["check_seconds"] + r.get("simulate_seconds", 0.0)
        lines.append(f"| {r['motor']} | {dur} | {r['status']} | {r['rounds']} | {err} | {sim} | {seconds:.1f} | "
                     f"{note} |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Run the study and print the table (or JSON); ``--table FILE`` prints the table of a ``--json`` run."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("motors", nargs="*", help="motor datasheet files (default: the built-in three)")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    ap.add_argument("--table", metavar="FILE", help="print the table of a --json run's output instead of running")
    ap.add_argument("--no-simulate", action="store_true", help="only the check, not simulate on every plant")
    args = ap.parse_args(argv)
    if args.table:
        print(table(json.loads(Path(args.table).read_text())))
        return 0
    rows = study(file_motors(args.motors) if args.motors else builtin_motors(), simulate=not args.no_simulate)
    print(json.dumps(rows, indent=2) if args.json else table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
