"""flatstep: plan and control stepping motors by differential flatness and sliding modes.

The command line: ``reproduce`` (the paper's figures), ``simulate`` (one move), ``design`` (gains for a drive),
``robustness`` (a scenario under parameter errors), ``compare`` (every controller on one scenario), ``tune`` (a
law's gains searched under caps), ``identify`` (motor parameters from a recording), ``bench`` (benchmarks).
``flatstep --help`` prints :data:`DESCRIPTION` (the commands and the exit codes, docs/errors.md);
``flatstep COMMAND --help`` lists a command's flags.
"""
from __future__ import annotations

import argparse
import re
import signal
import sys
import traceback
from pathlib import Path
from typing import Any, Sequence

from .._version import __version__
from ..control.smc import MEASUREMENTS, SMCGains
from ..engine.result import SimResult
from ..engine.simulate import simulate
from ..errors import REASONS, RunError
from ..json_out import strict_json
from ..model.motor import MotorParams
from ..model.plant import Plant
from ..plan.feasibility import InfeasiblePlanError
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from ..studies.scenario import PAPER_SCENARIOS, Scenario
from ..studies.scenario_file import read_scenario_file
from ..validate import InputError
from ..validate.paths import CSV_MARK, PNG_MARK, check_distinct, check_output, check_output_dir, json_marks
from .calibrate import add_calibrate_command
from .compare import add_compare_command
from .curve import add_curve_command
from .design import add_design_command
from .export import add_export_command
from .flags import add_force, count, out_dir, quantity
from .identify import add_identify_command
from .motor import add_motor_command
from .plan import add_plan_command, check_plan_file, scenario_on_drive
from .robustness import add_robustness_command
from .status import EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_REFUSED, EXIT_STOPPED, exit_code, warn
from .tune import add_tune_command

#: The summary table's columns and their units.
TABLE_KEYS = {"theta_final": "rad", "max_abs_theta_error": "rad", "max_abs_rho_error": "A", "max_abs_va": "V",
              "max_abs_vb": "V", "omega_final": "rad/s"}


def _table(summaries: dict[str, dict[str, Any]]) -> str:
    """The runs' summaries as a fixed-width table, one row per run (the columns of :data:`TABLE_KEYS`, units below)."""
    head = f"{'run':<6}" + "".join(f"{k:>21}" for k in TABLE_KEYS)
    units = f"{'':<6}" + "".join(f"{f'[{u}]':>21}" for u in TABLE_KEYS.values())
    rows = [f"{name:<6}" + "".join(f"{s[k]:>21.6e}" for k in TABLE_KEYS) for name, s in summaries.items()]
    return "\n".join([head, units, *rows])


def _write(out: Path, name: str, result: SimResult, title: str) -> None:
    """Write a run's figure (``<name>.png``) and series (``<name>.csv``) to ``out``."""
    from .plots import plot_run

    plot_run(result, title=title, path=out / f"{name}.png")
    result.to_csv(out / f"{name}.csv")


#: The files ``flatstep reproduce --out`` writes, and the first bytes that make an existing one flatstep's.
REPRODUCE_FILES = {"fig1.png": PNG_MARK, "fig2.png": PNG_MARK, "fig1.csv": CSV_MARK, "fig2.csv": CSV_MARK,
                   "summary.json": json_marks("fig1")}


def cmd_reproduce(args: argparse.Namespace) -> int:
    """``flatstep reproduce``: the paper's Fig. 1 and Fig. 2 runs, their figures, series and summaries."""
    check_output_dir(args.out, "--out", REPRODUCE_FILES, force=args.force)  # before any work
    out = out_dir(args.out)
    titles = {"fig1": "Fig. 1: ideal closed loop, no load (W1 = W2 = 100)",
              "fig2": "Fig. 2: constant load torque 1e-5 N m (W1 = W2 = 300)"}
    summaries: dict[str, dict[str, Any]] = {}
    for name, scenario in PAPER_SCENARIOS.items():
        result = scenario.run()
        _write(out, name, result, titles[name])
        summaries[name] = result.summary()
    (out / "summary.json").write_text(strict_json(summaries, indent=2) + "\n")
    print(_table(summaries))
    print(f"wrote {out / 'fig1.png'}, {out / 'fig2.png'}, {out / 'summary.json'}")
    for name, summary in summaries.items():
        warn(name, summary)
    return exit_code(s["status"] for s in summaries.values())


SIM_FLAGS = ("theta1", "theta2", "rho1", "rho2", "t0", "tf", "t_end", "load_torque", "W1", "W2", "eps1", "eps2",
             "xi", "wn", "hold_damping", "measurement")


def _scenario_from_flags(args: argparse.Namespace) -> Scenario:
    """The scenario of ``flatstep simulate``'s flags: the paper's motor, move and gains where a flag is not given."""
    p, g = PAPER_PLAN.as_dict(), SMCGains().as_dict()
    val = {k: getattr(args, k) for k in SIM_FLAGS}
    defaults = {**p, **g, "t_end": 0.06, "load_torque": 0.0, "measurement": "ideal"}
    val = {k: v if v is not None else defaults[k] for k, v in val.items()}
    plan = RestToRest(**{k: val[k] for k in p})
    gains = SMCGains(**{k: val[k] for k in g})
    motor = MotorParams.preset("paper")
    return Scenario("run", motor=motor, plan=plan, gains=gains, measurement=val["measurement"],
                    plant=Plant(motor, load=val["load_torque"]), t_end=val["t_end"])


#: The files ``flatstep simulate --out`` writes, and the first bytes that make an existing one flatstep's.
SIMULATE_FILES = {"run.png": PNG_MARK, "run.csv": CSV_MARK, "summary.json": json_marks("status")}


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse, before any work, an output of ``flatstep simulate`` that it may not write.

    Not over its scenario, not over a user's file without ``--force``, not twice over one file (docs/errors.md,
    "Files flatstep writes").
    """
    files = check_output_dir(args.out, "--out", SIMULATE_FILES, inputs=[args.scenario], force=args.force) \
        if args.out else []
    if args.record:
        check_distinct({**{f"--out {args.out} ({f.name})": f for f in files}, "--record": args.record})
        check_output(args.record, "--record", inputs=[args.scenario], force=args.force, marks=CSV_MARK)


def cmd_simulate(args: argparse.Namespace) -> int:
    """``flatstep simulate``: one closed-loop move from a scenario file or the flags; prints its summary."""
    _check_outputs(args)
    if args.scenario:
        given = [f"--{k.replace('_', '-')}" for k in SIM_FLAGS if getattr(args, k) is not None]
        if given:
            raise ValueError(f"{given} cannot be combined with a scenario file: set them in {args.scenario}")
        scenario = scenario_on_drive(check_plan_file(read_scenario_file(args.scenario), show_steps=not args.json),
                                     skip=args.no_verify)
    else:
        scenario = _scenario_from_flags(args)
    if args.record and scenario.loop is None:
        raise InputError("--record", args.record, f"--record {args.record}: a recording needs a sampled drive (a "
                         "scenario file with [drive] control_rate): a continuous-time run has no drive that measures")
    if args.x0 is None:
        result = scenario.run()
    else:
        scenario.feasibility().raise_if_infeasible()
        result = simulate(scenario.simulated_plant, scenario.plan, scenario.controller(), loop=scenario.loop,
                          solver=scenario.solver, t_end=scenario.t_end, x0=args.x0)
    plan = scenario.plan
    return _report(args, scenario.name, result, f"{scenario.name}: theta {plan.theta1:g} -> {plan.theta2:g} rad, "
                   f"load {scenario.simulated_plant.load:g} N m, {scenario.measurement} measurement")


def _report(args: argparse.Namespace, name: str, result: SimResult, title: str) -> int:
    """Record, write (``--out``) and print one run of ``flatstep simulate``; its exit code by status."""
    summary = result.summary()
    if args.record:
        from ..studies.record import recording_from_result, write_recording

        write_recording(args.record, recording_from_result(result, source=name))
    if args.out:
        out = out_dir(args.out)
        _write(out, "run", result, title)
        (out / "summary.json").write_text(strict_json(summary, indent=2) + "\n")
    print(strict_json(summary, indent=2) if args.json else _table({"run": summary}))
    if not args.json:
        print(f"status: {summary['status']}")
    warn(name, summary)
    return exit_code([summary["status"]])


def cmd_bench(args: argparse.Namespace) -> int:
    """``flatstep bench``: the chosen benchmarks (:func:`flatstep.bench.main`)."""
    from ..bench import main as bench_main

    return bench_main(args.which, args.repeat)


DESCRIPTION = """Plan and control stepping motors by differential flatness and sliding modes.

Commands: reproduce (the paper's figures), simulate (one move), design (gains for a drive), robustness (a
scenario under parameter errors), compare (every controller on one scenario), tune (a law's gains searched
on the scenario's plants under caps), identify (motor parameters
from a recording), calibrate (detent, friction and load from the drive's own sensors), plan (the fastest
moves through waypoints under the motor's limits), motor (a motor from its datasheet, with what was assumed),
export (a plan as step timestamps or a setpoint stream), curve (pull-out torque against speed for a drive),
bench (benchmarks). 'flatstep COMMAND --help' lists a
command's flags.

Exit codes: 0 every run ok; 1 an unexpected error; 2 a refused input (nothing was run); 3 a run lost its
move; 4 a controller faulted; 5 a run stopped before its end (non-finite state, or the continuous law
faulted at every step); 130 interrupted (docs/errors.md)."""


class _Parser(argparse.ArgumentParser):
    """argparse with negative numbers in scientific notation taken as values (``--load-torque -1e-5``)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def build_parser() -> argparse.ArgumentParser:
    """The ``flatstep`` argument parser, one subcommand per ``cmd_*``."""
    parser = _Parser(prog="flatstep", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"flatstep {__version__}")
    parser.add_argument("--debug", action="store_true", help="print the traceback of an unexpected error")
    sub: Any = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    rep = sub.add_parser("reproduce", help="run the paper's Fig. 1 and Fig. 2 scenarios",
                         description="Run the paper's two simulations (Fig. 1: no load, W1 = W2 = 100; Fig. 2: "
                         "load 1e-5 N m, W1 = W2 = 300) with continuous control; write fig1.png, fig2.png, their "
                         "series (CSV) and summary.json, and print the summary table.")
    rep.add_argument("--out", default="out", help="output directory (default: out)")
    add_force(rep)
    rep.set_defaults(func=cmd_reproduce)

    sim = sub.add_parser("simulate", help="simulate one closed-loop move (defaults: the paper's Fig. 1)",
                         description="Simulate one closed-loop move: a scenario file (a whole drive: motor, plant, "
                         "plan, controller, sensors, observer; the paper's move or a waypoint sequence, refused "
                         "beyond its [limits]), or the paper's motor with the move and "
                         "gains given by the flags (continuous control). Prints the summary and the run's status; "
                         "the exit code says whether it kept its move (flatstep --help).")
    sim.add_argument("scenario", nargs="?", default=None,
                     help="a scenario file (TOML, docs/scenario-reference.md; examples/*.toml, "
                     "examples/plans/*.toml); or give the move and gains by flags")
    p, g = PAPER_PLAN, SMCGains()
    for flag, kind, default, help_ in (
        ("--theta1", "angle", p.theta1, "start angle [rad]"), ("--theta2", "angle", p.theta2, "end angle [rad]"),
        ("--rho1", "current", p.rho1, "start current norm [A]"), ("--rho2", "current", p.rho2, "end current norm [A]"),
        ("--t0", "time", p.t0, "move start [s]"), ("--tf", "time", p.tf, "move end [s]"),
        ("--t-end", "t_end", 0.06, "horizon [s]"),
        ("--load-torque", "load", 0.0, "constant load torque on the plant [N m]"),
        ("--W1", "gain", g.W1, "sliding gain on s1"), ("--W2", "gain", g.W2, "sliding gain on s2"),
        ("--eps1", "gain", g.eps1, "boundary layer of s1"), ("--eps2", "gain", g.eps2, "boundary layer of s2"),
        ("--xi", "damping", g.xi, "damping of the theta error dynamics"),
        ("--wn", "gain", g.wn, "natural frequency [rad/s]"),
    ):
        sim.add_argument(flag, type=quantity(kind, flag), default=None, help=f"{help_} (default {default:g})")
    sim.add_argument("--hold-damping", type=quantity("damping", "--hold-damping"), default=None,
                     help="from tf on, hold the target's detent with this damping ratio (default: track the plan)")
    sim.add_argument("--measurement", choices=MEASUREMENTS, default=None,
                     help="where the law's acceleration theta'' comes from. ideal: the plant's true value (the "
                     "paper's assumption; default); model: the zero-load model of the measured state, J theta'' = Km "
                     "(ib cos Nr theta - ia sin Nr theta) - B omega; observer: a drive's speed and load observer (a "
                     "scenario file's [observer]; without a drive, as here, it reads the true value like ideal). A "
                     "scenario file picks the mode its drive can give ([controller] measurement)")
    sim.add_argument("--x0", type=float, nargs=4, metavar=("IA", "IB", "OMEGA", "THETA"), default=None,
                     help="initial plant state (default: the plan's start equilibrium)")
    sim.add_argument("--out", default=None, help="write run.png, run.csv and summary.json here")
    sim.add_argument("--json", action="store_true", help="print the summary as JSON")
    sim.add_argument("--no-verify", action="store_true", help="run a plan made against [limits] as the file gives it, "
                     "without the check on the drive that 'flatstep plan' runs (the nominal and +-10 %% plants; "
                     "by default a plan the drive would lose is refused, one it keeps after backing off runs backed "
                     "off)")
    sim.add_argument("--record", metavar="DATA.csv", default=None, help="write what the drive measured (t, va, vb, ia, "
                     "ib, theta) for 'flatstep identify' (docs/identification.md); needs a sampled drive")
    add_force(sim)
    sim.set_defaults(func=cmd_simulate)

    add_design_command(sub)
    add_robustness_command(sub)
    add_compare_command(sub)
    add_tune_command(sub)
    add_identify_command(sub)
    add_plan_command(sub)
    add_calibrate_command(sub)
    add_motor_command(sub)
    add_export_command(sub)
    add_curve_command(sub)

    ben = sub.add_parser("bench", help="benchmarks side by side, medians and ratios (docs/benchmarks.md)",
                         description="Benchmarks side by side in one run: medians and their ratios against each "
                         "benchmark's baseline, with the targets (docs/benchmarks.md). Needs a source checkout for "
                         "the C drivers, and valgrind for instruction counts.")
    ben.add_argument("--which", default="a,b,c,d,e", help="a: planning, b: closed loop, c: controller step, "
                     "d: batch throughput, e: one engine for every run (default: a,b,c,d,e)")
    ben.add_argument("--repeat", type=count("repeat", "--repeat"), default=None,
                     help="rounds per benchmark (default: each one's own)")
    ben.set_defaults(func=cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (:mod:`flatstep.cli.status`, docs/errors.md)."""
    if hasattr(signal, "SIGPIPE"):  # a closed pipe (``flatstep ... | head``) ends the output quietly
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    try:
        return _run(argv)
    except KeyboardInterrupt:
        print("flatstep: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _run(argv: Sequence[str] | None) -> int:
    """Parse ``argv`` and run its command; every error becomes one line on stderr and an exit code."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as done:  # --help, --version, or a refused flag (argparse printed why): its exit code
        return done.code if isinstance(done.code, int) else EXIT_REFUSED
    try:
        return int(args.func(args))
    except InfeasiblePlanError as exc:
        print(f"flatstep: refused: {exc}", file=sys.stderr)
        return EXIT_REFUSED
    except ValueError as exc:
        print(f"flatstep: error: {exc}", file=sys.stderr)
        return EXIT_REFUSED
    except RunError as exc:
        print(f"flatstep: run stopped: {exc} ({REASONS.get(exc.reason, exc.reason)})", file=sys.stderr)
        return EXIT_STOPPED
    except OSError as exc:  # a full disk, a file that cannot be written: not a bug of flatstep's
        print(f"flatstep: error: {exc.strerror or exc}" + (f": {exc.filename}" if exc.filename else ""),
              file=sys.stderr)
        return EXIT_INTERNAL
    except MemoryError:
        print("flatstep: error: out of memory (shorten t_end or lower the sample rate)", file=sys.stderr)
        return EXIT_INTERNAL
    except Exception as exc:  # noqa: BLE001 -- the command line never prints a traceback unless asked to
        if args.debug:
            traceback.print_exc()
        print(f"flatstep: internal error: {type(exc).__name__}: {exc} (run again with --debug for the traceback, "
              "and please report it)", file=sys.stderr)
        return EXIT_INTERNAL

if __name__ == "__main__":
    sys.exit(main())
