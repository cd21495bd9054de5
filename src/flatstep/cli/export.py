"""Command line: ``flatstep export FILE.toml``, a scenario's plan as a machine runs it (docs/export.md).

``--steps``: step timestamps for a step/dir driver (CSV ``t,direction,position``); ``--setpoints``: the setpoint
stream of a field-oriented drive at a rate (CSV, or a C header the core's ``setpoint_at`` replays, by the
``--out`` suffix ``.h``). The plan is the one ``flatstep plan`` reports feasible: checked on the file's drive and
backed off as it is there (``--no-verify`` exports the file's plan as it is).
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ..plan.export import setpoint_stream, step_times
from ..validate import InputError
from ..validate.paths import CSV_MARK, check_output
from .flags import add_force, count, quantity

#: First bytes of a C setpoint table flatstep writes.
HEADER_MARK = (b"/* Setpoints written by flatstep",)


def cmd_export(args: argparse.Namespace) -> int:
    """``flatstep export FILE.toml --steps | --setpoints --out PATH``."""
    from ..studies.scenario_file import read_scenario_file
    from .plan import scenario_on_drive

    out = Path(args.out)
    as_header = out.suffix == ".h"
    if as_header and args.steps:
        raise InputError("--out", args.out, f"--out {args.out}: step timestamps are written as CSV (.csv); a C "
                         "header (.h) holds a setpoint stream (--setpoints)")
    check_output(out, "--out", inputs=[args.file], force=args.force, marks=HEADER_MARK if as_header else CSV_MARK)
    sf = read_scenario_file(args.file)
    scenario = scenario_on_drive(sf, skip=args.no_verify)
    plan, motor = scenario.plan, scenario.motor
    if args.steps:
        train = step_times(plan, motor, args.microsteps, timer_rate=args.timer_rate)
        np.savetxt(out, np.column_stack([train.t, train.direction, train.positions]), delimiter=",",
                   header="t,direction,position", comments="", fmt=("%.17g", "%d", "%.17g"))
        print(f"{sf.name}: {train.t.size} steps at {args.microsteps} microsteps ({train.increment:.6g} rad each) "
              f"over {plan.tf - plan.t0:.6g} s; timestamps within {train.timing_error:.3g} s of the exact "
              f"crossings; commanded position within {train.position_bound:.6g} rad of the plan at every time")
    else:
        rate = args.rate if args.rate is not None else _drive_rate(scenario, args)
        stream = setpoint_stream(plan, motor, rate, load_torque=_constant_load(scenario),
                                 d_current=scenario.d_current if scenario.controller_type.startswith("dq") else None)
        if as_header:
            out.write_text(stream.c_table(args.name))
        else:
            stream.to_csv(out)
        print(f"{sf.name}: {stream.rows.shape[0]} setpoints at {rate:g} Hz from t = {stream.t0:g} s "
              f"({'C table ' + args.name if as_header else 'CSV'})")
    print(f"  wrote {out}")
    return 0


def _drive_rate(scenario: Any, args: argparse.Namespace) -> float:
    """The scenario's control rate [Hz], or an InputError asking for --rate."""
    if scenario.loop is None:
        raise InputError("--rate", None, f"{args.file} has no [drive] control_rate: give --rate HZ")
    return 1.0 / scenario.loop.control_period


def _constant_load(scenario: Any) -> float:
    """The plant's constant load torque [N m] (0 without a plant or for a time-varying load)."""
    plant = scenario.plant
    load = plant.constant_load if plant is not None else 0.0
    return float(load) if load is not None else 0.0


def add_export_command(sub: Any) -> None:
    """Register ``flatstep export`` on the subcommand parser ``sub``."""
    p = sub.add_parser("export", help="a scenario's plan as step timestamps or a setpoint stream (docs/export.md)",
                       description="Export a scenario file's plan (the one 'flatstep plan' reports feasible) as a "
                       "machine runs it: --steps writes step timestamps for a step/dir driver (CSV t,direction,"
                       "position; the commanded position stays within half a microstep of the plan, plus the "
                       "timer's rounding); --setpoints writes the plan sampled at --rate (default: the drive's "
                       "control rate) as theta, omega, alpha, torque, i_d, i_q (CSV, or a C header for the core's "
                       "setpoint_at when --out ends in .h). Exit 2 when an argument or path is refused or the "
                       "drive would not keep the plan.")
    p.add_argument("file", help="a scenario file (TOML, docs/scenario-reference.md)")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--steps", action="store_true", help="step timestamps for a step/dir driver")
    what.add_argument("--setpoints", action="store_true", help="a setpoint stream for a field-oriented drive")
    p.add_argument("--out", required=True, help="the file to write (.csv; .h for a C setpoint table)")
    p.add_argument("--microsteps", type=count("microsteps", "--microsteps"), default=16,
                   help="microsteps per full step of the driver (default 16)")
    p.add_argument("--timer-rate", type=quantity("rate", "--timer-rate"), default=None,
                   help="the step timer's clock [Hz]: timestamps round to its ticks (default: exact times)")
    p.add_argument("--rate", type=quantity("rate", "--rate"), default=None,
                   help="setpoints per second [Hz] (default: the file's [drive] control_rate)")
    p.add_argument("--name", default="setpoints", help="the C table's name in a .h file (default: setpoints)")
    p.add_argument("--no-verify", action="store_true", help="export the file's plan without the check on the drive")
    add_force(p)
    p.set_defaults(func=cmd_export)
