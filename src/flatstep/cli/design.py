"""Command line: ``flatstep design``, gains and observer for a sampled drive."""
from __future__ import annotations

import argparse
from dataclasses import replace

from ..control.smc import SMCGains
from ..json_out import strict_json
from ..loop.design import design_gains
from ..loop.drive import Drive
from ..loop.reference import DriveLoop
from ..loop.sensors import Sensors
from ..model.motor import MotorParams
from ..model.plant import Plant
from ..studies.robustness import encoder_count
from ..studies.scenario import Scenario
from ..studies.scenario_file import load_scenario
from ..validate.paths import PNG_MARK, check_output_dir, json_marks
from .flags import add_force, count, out_dir, quantity
from .status import exit_code, warn


def _design_scenario(args: argparse.Namespace) -> Scenario:
    """The scenario file's drive, or the realistic default: paper motor and move, 24 V, 14-bit, 12-bit."""
    if args.scenario:
        scenario, _ = load_scenario(args.scenario)
        if scenario.loop is None:
            raise ValueError(f"{args.scenario} has no [drive] control_rate: gain design is for sampled drives")
        return scenario
    sensors = Sensors(encoder_counts=args.encoder_counts, current_bits=args.current_bits,
                      current_range=args.current_range)
    loop = DriveLoop.at(args.control_rate, substeps=4, drive=Drive(v_bus=args.v_bus), sensors=sensors,
                        compute_delay=args.compute_delay)
    motor = MotorParams.preset("paper")
    return Scenario("drive", motor=motor, plant=Plant(motor, load=args.load_torque), loop=loop,
                    measurement="observer")


#: The files ``flatstep design --out`` writes, and the first bytes that make an existing one flatstep's.
DESIGN_FILES = {"design.png": PNG_MARK, "design.json": json_marks("gains")}


def cmd_design(args: argparse.Namespace) -> int:
    """``flatstep design``: sliding gains and observer for a sampled drive, and optionally runs of both gain sets."""
    if args.out:  # before any work
        check_output_dir(args.out, "--out", DESIGN_FILES, inputs=[getattr(args, "scenario", None)], force=args.force)
    base = _design_scenario(args)
    loop, load = base.loop, base.simulated_plant.constant_load
    assert loop is not None  # _design_scenario
    assert load is not None, "scenario files and the flags give a constant load torque"
    s = loop.sensors
    d = design_gains(base.motor, base.plan, control_period=loop.control_period,
                     v_bus=loop.drive.v_bus if loop.drive else float("inf"),
                     encoder_counts=s.encoder_counts if s else None, current_step=s.current_step if s else 0.0,
                     load_torque=load, uncertainty=args.uncertainty, compute_delay=loop.compute_delay)
    report = d.as_dict()
    if args.out:
        from .plots_compare import plot_overlay

        out = out_dir(args.out)
        designed = replace(base, gains=d.gains, loop=replace(loop, observer=d.observer if s else None))
        paper = replace(designed, gains=SMCGains())
        runs = {"paper's gains": paper.run(), "designed gains": designed.run()}
        report["runs"] = {k: r.summary() for k, r in runs.items()}
        plot_overlay(runs, base.plan, encoder_count(base), title=f"{base.name}: {1 / loop.control_period:g} Hz "
                     f"control, load {load:g} N m", path=out / "design.png")
        (out / "design.json").write_text(strict_json(report, indent=2) + "\n")
    designed_status = [report["runs"]["designed gains"]["status"]] if "runs" in report else []
    if args.json:
        print(strict_json(report, indent=2))
        return exit_code(designed_status)
    print("designed gains: " + ", ".join(f"{k}={v:.6g}" for k, v in report["gains"].items() if v is not None))
    print("observer: " + ", ".join(f"{k}={v:.6g}" for k, v in report["observer"].items()))
    print("rationale: " + ", ".join(f"{k}={v:.6g}" for k, v in report["rationale"].items()))
    for w in d.warnings:
        print(f"warning: {w}")
    for label, summ in report.get("runs", {}).items():
        move = summ.get("max_abs_theta_error_move", float("nan"))
        print(f"{label:>15}: max |theta - theta*| during the move {move:.3e} "
              f"rad, after it {summ.get('max_abs_theta_error_after', float('nan')):.3e} rad, peak |v| "
              f"{max(summ['max_abs_va'], summ['max_abs_vb']):.3g} V, controller faults {summ['controller_faults']}, "
              f"status {summ['status']}")
    if "runs" in report:
        warn("designed gains", report["runs"]["designed gains"])
    return exit_code(designed_status)


def add_design_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep design`` to the subcommands ``sub``."""
    des = sub.add_parser("design", help="design sliding gains and observer for a sampled drive",
                         description="Design the sliding gains, boundary layers, error dynamics and observer for a "
                         "sampled drive (a scenario file's [drive], or the paper's motor and move on the flags' "
                         "drive), print them with their rationale; with --out, also run the paper's and the designed "
                         "gains on that drive (design.png: tracking error in encoder counts, current norm [A], "
                         "phase voltage [V]).")
    des.add_argument("scenario", nargs="?", default=None, help="a scenario file with a [drive] (default: "
                     "the paper's motor and move on the flags' drive)")
    des.add_argument("--control-rate", type=quantity("rate", "--control-rate"), default=20e3,
                     help="control rate [Hz] (default 20000)")
    des.add_argument("--v-bus", type=quantity("v_bus", "--v-bus"), default=24.0, help="bus voltage [V] (default 24)")
    des.add_argument("--encoder-counts", type=count("encoder_counts", "--encoder-counts"), default=16384,
                     help="counts per revolution (default 16384)")
    des.add_argument("--current-bits", type=count("current_bits", "--current-bits"), default=12,
                     help="current ADC bits (default 12)")
    des.add_argument("--current-range", type=quantity("current_range", "--current-range"), default=2.0,
                     help="current ADC full scale +-A (default 2)")
    des.add_argument("--load-torque", type=quantity("load", "--load-torque"), default=1e-5,
                     help="expected load torque [N m] (default 1e-5)")
    des.add_argument("--uncertainty", type=quantity("relative", "--uncertainty"), default=0.1,
                     help="relative parameter error, in [0, 0.5) (default 0.1)")
    des.add_argument("--compute-delay", action="store_true", help="one period between measuring and applying")
    add_force(des)
    des.add_argument("--out", default=None, help="also run the paper's and the designed gains on this drive: "
                     "design.png, design.json")
    des.add_argument("--json", action="store_true", help="print the design as JSON")
    des.set_defaults(func=cmd_design)
