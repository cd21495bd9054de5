"""Command line: ``flatstep identify``, motor parameters from a recording (docs/identification.md).

* ``flatstep identify DATA.csv [--out motor.toml]``: the estimates with their intervals, and a [motor] table;
* ``flatstep identify --excite SCENARIO --record DATA.csv``: record the suggested excitation on the scenario's
  drive, then identify it against the scenario's plant;
* ``flatstep identify --accuracy SCENARIO ... --seeds 10``: the accuracy over seeds, against the targets.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, Optional

from ..json_out import strict_json
from ..model.motor import MotorParams
from ..studies.scenario_file import load_scenario
from ..validate import InputError
from ..validate.paths import check_output
from .flags import count, quantity
from .status import EXIT_REFUSED

#: Flags that only some uses read, with the uses (``data``, ``excite``, ``accuracy``) that do; given elsewhere they
#: would be ignored, so they are refused.
MODE_FLAGS = {"--record": ("excite",), "--seed": ("excite",), "--seeds": ("accuracy",),
              "--duration": ("excite", "accuracy"), "--noise": ("excite", "accuracy"),
              "--preset-plant": ("excite", "accuracy"), "--out": ("data", "excite"), "--nr": ("data", "excite")}
#: Defaults of the flags of :data:`MODE_FLAGS` (argparse leaves them None, so that a given flag is seen).
DEFAULTS = {"seeds": 10, "seed": 0, "duration": 1.0}
#: First bytes of the [motor] table ``--out`` writes (an existing file that starts so is flatstep's own).
MOTOR_MARK = b"# identified from "


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """The keywords of :func:`~flatstep.studies.identify.identify` that the flags set."""
    return {"detent": args.detent, "coulomb": args.coulomb, "coulomb_speed": args.coulomb_speed,
            "offsets": not args.no_offsets, "noise_compensation": not args.no_noise_compensation,
            "bandwidth": (args.bandwidth[0], args.bandwidth[1]), "confidence": args.confidence}


def _identify(args: argparse.Namespace, data: Any, truth: Optional[MotorParams] = None) -> int:
    """Identify ``data``, print the table (or JSON), warn of its flags and write ``--out``; 2 if flagged."""
    from ..studies.identify import identify  # scipy.signal: imported when used, so that other commands start fast

    result = identify(data, Nr=args.nr if args.nr is not None else (truth.Nr if truth else 50), **_options(args))
    if args.json:
        out = result.as_dict()
        if truth is not None:
            out["errors"] = result.errors(truth)
        print(strict_json(out, indent=2))
    else:
        rate = 1.0 / result.settings["period"]
        print(f"{result.source}: {result.settings['samples']} samples at {rate:.6g} Hz, Nr = {result.Nr}")
        print(result.table(truth))
        for note in result.notes:
            print(f"note: {note}")
    for flag in result.flags:
        print(f"flatstep: warning: {result.source}: {flag}", file=sys.stderr)
    if args.out:
        Path(args.out).write_text(result.as_toml())
        if not args.json:
            print(f"wrote {args.out}")
    return EXIT_REFUSED if result.flags else 0  # flagged: printed and written (with the flags), but not fine


def _accuracy(args: argparse.Namespace) -> int:
    """``--accuracy``: the table of :func:`~flatstep.studies.identify_accuracy.accuracy_table`."""
    from ..studies.identify_accuracy import accuracy, accuracy_table, meets_targets, preset_plant

    scenarios = [load_scenario(path)[0] for path in args.accuracy]
    if args.preset_plant:
        scenarios = [preset_plant(s) for s in scenarios]
    rows = accuracy(scenarios, range(args.seeds), current_noise=args.noise, duration=args.duration, **_options(args))
    if args.json:
        print(strict_json(rows, indent=2))
    else:
        print(accuracy_table(rows))
    ok = meets_targets(rows)
    if not args.json:
        print("targets: " + ("all met" if ok else "NOT all met"))
    return 0 if ok else EXIT_REFUSED


def _check_flags(args: argparse.Namespace, mode: str) -> None:
    """Refuse a flag that ``mode`` would ignore, naming it and the use that reads it; fill in the defaults."""
    uses = {"data": "a recording (DATA.csv)", "excite": "--excite", "accuracy": "--accuracy"}
    for flag, modes in MODE_FLAGS.items():
        value = getattr(args, flag.lstrip("-").replace("-", "_"))
        if value not in (None, False) and mode not in modes:
            raise InputError(flag, value, f"{flag} is read only with {' or '.join(uses[m] for m in modes)}, and this "
                             f"run identifies {uses[mode]}: drop {flag}, or give {uses[modes[0]]}")
    if args.coulomb_speed is not None and not args.coulomb:
        raise InputError("--coulomb-speed", args.coulomb_speed, "--coulomb-speed sets the Coulomb term that --coulomb "
                         "estimates: give --coulomb too, or drop --coulomb-speed")
    if args.coulomb_speed is None:
        args.coulomb_speed = 0.3
    for name, default in DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse ``--record``, ``--out`` where flatstep may not write (:func:`~flatstep.validate.paths.check_output`)."""
    inputs = [args.data, args.excite, *(args.accuracy or [])]
    if args.record:
        check_output(args.record, "--record", inputs=inputs, force=args.force)
    if args.out:
        check_output(args.out, "--out", inputs=[*inputs, args.record], force=args.force, marks=(MOTOR_MARK,))


def cmd_identify(args: argparse.Namespace) -> int:
    """``flatstep identify``: one of the three uses of the module docstring."""
    modes = [m for m in ("data", "excite", "accuracy") if getattr(args, m)]
    if len(modes) != 1:
        raise ValueError("give a recording (flatstep identify DATA.csv), or --excite SCENARIO --record DATA.csv, or "
                         f"--accuracy SCENARIO ...; got {modes or 'none'}")
    _check_flags(args, modes[0])
    if args.excite and not args.record:
        raise InputError("--record", None, "--excite needs --record DATA.csv: the file the recording is written to")
    _check_outputs(args)
    if args.accuracy:
        return _accuracy(args)
    if args.excite:
        from ..studies.excitation import excite
        from ..studies.record import write_recording

        scenario, _ = load_scenario(args.excite)
        if args.preset_plant:
            from ..studies.identify_accuracy import preset_plant

            scenario = preset_plant(scenario)
        rec = excite(scenario, duration=args.duration, seed=args.seed, current_noise=args.noise)
        write_recording(args.record, rec)
        if not args.json:
            print(f"wrote {args.record}: {rec.t.size} samples, {rec.duration:.4g} s of {rec.source}")
        return _identify(args, args.record, truth=scenario.simulated_plant.motor)
    return _identify(args, args.data)


DESCRIPTION = """Estimate R, L, Km, J, B (and detent and Coulomb friction) from a recording (docs/identification.md).

  flatstep identify DATA.csv [--out motor.toml]
      the estimates with their intervals, and a [motor] table for a scenario file
  flatstep identify --excite SCENARIO --record DATA.csv
      record the suggested excitation (a move sequence) on the scenario's drive, then identify it
  flatstep identify --accuracy SCENARIO ... --seeds 10
      excite and identify over seeds; the worst errors against the targets"""


def add_identify_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep identify`` to the subcommands ``sub``."""
    ide = sub.add_parser("identify", help="estimate R, L, Km, J, B from a recording (docs/identification.md)",
                         description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    ide.add_argument("data", nargs="?", default=None,
                     help="a recording: CSV with the columns t, va, vb, ia, ib, theta (docs/identification.md)")
    ide.add_argument("--nr", type=count("Nr", "--nr"), default=None, help="rotor teeth (default 50, or the scenario's)")
    ide.add_argument("--detent", action="store_true", help="also estimate the detent torque's amplitude and phase")
    ide.add_argument("--coulomb", action="store_true", help="also estimate the Coulomb friction")
    ide.add_argument("--coulomb-speed", type=quantity("coulomb_speed", "--coulomb-speed"), default=None,
                     help="with --coulomb: omega_s [rad/s] of the Coulomb term's smooth sign tanh(omega/omega_s) "
                     "(default 0.3)")
    ide.add_argument("--no-offsets", action="store_true", help="do not estimate a voltage offset per phase")
    ide.add_argument("--no-noise-compensation", action="store_true",
                     help="plain least squares: do not remove the current noise's bias from the electrical fit")
    ide.add_argument("--bandwidth", type=quantity("rate", "--bandwidth"), nargs=2, default=(200.0, 100.0),
                     metavar=("ELEC", "MECH"),
                     help="filter cutoffs [Hz] of the electrical and mechanical equations (default 200 100)")
    ide.add_argument("--confidence", type=quantity("confidence", "--confidence"),
                     default=0.95, help="level of the intervals (default 0.95)")
    ide.add_argument("--out", default=None, help="write the [motor] table (TOML) here (never over an input)")
    ide.add_argument("--force", action="store_true",
                     help="let --out and --record replace a file flatstep did not write (never an input)")
    ide.add_argument("--json", action="store_true", help="print the result as JSON")
    ide.add_argument("--excite", metavar="SCENARIO", default=None,
                     help="record the suggested excitation (a move sequence) on this scenario's drive, then identify")
    ide.add_argument("--record", metavar="DATA.csv", default=None,
                     help="with --excite: write the recording here (never over the scenario)")
    ide.add_argument("--accuracy", metavar="SCENARIO", nargs="+", default=None,
                     help="excite and identify these scenarios over --seeds seeds; table against the targets")
    ide.add_argument("--seeds", type=count("seeds", "--seeds"), default=None,
                     help="with --accuracy: seeds 0..N-1 (default 10)")
    ide.add_argument("--seed", type=count("seed", "--seed"), default=None,
                     help="with --excite: the excitation's seed (default 0)")
    ide.add_argument("--duration", type=quantity("duration", "--duration"), default=None,
                     help="with --excite/--accuracy: seconds (default 1)")
    ide.add_argument("--noise", type=quantity("current_noise", "--noise"), default=None,
                     help="with --excite/--accuracy: ADC noise [A rms] instead of the scenario's sensors' own")
    ide.add_argument("--preset-plant", action="store_true",
                     help="with --excite/--accuracy: simulate the scenario's [motor], not its [plant]")
    ide.set_defaults(func=cmd_identify)
