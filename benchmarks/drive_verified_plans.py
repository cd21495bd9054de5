"""The fastest 10-revolution move (62.83 rad) of many motors on 24 V, verified on a 20 kHz drive.

Each motor's limits come from :meth:`flatstep.plan.limits.MotorLimits.for_drive` (its rated current, the bus, the
control rate, a 4000-count encoder, +-10 % uncertainty); the time-optimal plan is run on the drive on the nominal
plant and the 16 corners of +-10 % on R, L, Km, J (:func:`flatstep.studies.verify.plan_for_drive`), backed off
where a case is lost or faults. Prints one row per motor: the plan's duration, its status and what binds.

    .venv/bin/python benchmarks/drive_verified_plans.py [--json] [examples/motors/*.toml]
    .venv/bin/python benchmarks/drive_verified_plans.py --table study.json   # the table of a --json run

Without motor files: the two presets and a NEMA 17 of 1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m, 68 g cm^2.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

from flatstep.model.motor import MotorParams
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal import time_optimal
from flatstep.studies.verify import drive_loop, plan_for_drive

DISTANCE = 62.83   # 10 revolutions [rad]
V_BUS = 24.0
RATE = 20000.0
COUNTS = 4000


def nema17_168() -> MotorParams:
    """A common NEMA 17 (1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m holding, 68 g cm^2, 1.8 deg), converted by hand.

    Km = holding torque / (sqrt(2) rated current): both phases at rated current hold sqrt(2) Km I.
    """
    return MotorParams(R=1.65, L=2.8e-3, Km=0.44 / (math.sqrt(2) * 1.68), J=68e-7, B=1e-4, Nr=50)


def builtin_motors() -> list[tuple[str, MotorParams, float]]:
    """(name, motor, i_max [A]): the presets at 1 A (their plan files' current) and the hand-converted NEMA 17."""
    return [("paper", MotorParams.preset("paper"), 1.0), ("nema17 preset", MotorParams.preset("nema17"), 1.0),
            ("NEMA 17 1.68 A", nema17_168(), 1.68)]


def file_motors(paths: list[str]) -> list[tuple[str, MotorParams, float]]:
    """(name, motor, i_max) from datasheet files (flatstep.model.datasheet), i_max their rated current norm."""
    import tomllib

    from flatstep.model.datasheet import motor_from_table

    out = []
    for p in paths:
        model = motor_from_table(tomllib.loads(Path(p).read_text())["motor"], p)
        out.append((Path(p).stem, model.params, model.rated_rho))
    return out


def study(motors: list[tuple[str, MotorParams, float]]) -> list[dict[str, Any]]:
    """One row per motor: duration [s] (None when refused), status, binds, worst error, rounds, seconds."""
    rows = []
    loop = drive_loop(V_BUS, RATE, COUNTS)
    for name, motor, i_max in motors:
        start = time.perf_counter()
        limits = MotorLimits.for_drive(motor, v_bus=V_BUS, i_max=i_max, control_rate=RATE, encoder_counts=COUNTS)
        plan, final, verdict = plan_for_drive(lambda lim, m=motor: time_optimal(DISTANCE, m, lim, t0=0.005),
                                              motor, limits, loop)
        last = verdict.rounds[-1]
        rows.append(dict(motor=name, duration=None if plan is None else plan.tf - plan.t0,
                         status="verified" if plan is not None else "refused",
                         cases=len(verdict.cases), bad=sum(c.status != "ok" for c in verdict.cases),
                         worst_error=verdict.worst_error if verdict.cases else None,
                         binds=verdict.binds or last.get("refused"), rounds=len(verdict.rounds),
                         speed_max=final.speed_max, seconds=time.perf_counter() - start,
                         history=verdict.rounds))
    return rows


def table(rows: list[dict[str, Any]]) -> str:
    """The study as a Markdown table: motor, duration, status, plans made, worst error, time, what binds."""
    lines = ["| motor | duration [s] | status | plans | worst error [rad] | time [s] | binds |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        dur = f"{r['duration']:.4f}" if r["duration"] is not None else "-"
        err = f"{r['worst_error']:.3g}" if r["worst_error"] is not None else "-"
        first = r["history"][0]
        note = r["binds"] or (f"backed off from {first['duration']:.4f} s ({first['binds']})" if r["rounds"] > 1
                              else "")
        lines.append(f"| {r['motor']} | {dur} | {r['status']} | {r['rounds']} | {err} | {r['seconds']:.1f} | {note} |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Run the study and print the table (or JSON); ``--table FILE`` prints the table of a ``--json`` run."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("motors", nargs="*", help="motor datasheet files (default: the built-in three)")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    ap.add_argument("--table", metavar="FILE", help="print the table of a --json run's output instead of running")
    args = ap.parse_args(argv)
    if args.table:
        print(table(json.loads(Path(args.table).read_text())))
        return 0
    rows = study(file_motors(args.motors) if args.motors else builtin_motors())
    print(json.dumps(rows, indent=2) if args.json else table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
