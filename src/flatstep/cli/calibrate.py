"""Command line: ``flatstep calibrate``, the detent, Coulomb friction and load from the drive's own sensors.

* ``flatstep calibrate SCENARIO [--out TABLE.toml] [--merge NEW.toml | --in-place]``: calibrate the scenario's plant
  and print the ``[feedforward]`` table; ``--merge`` writes a copy of the scenario file with its table replaced by
  the calibrated one (edited as TOML, :func:`~flatstep.studies.calibrate.merged_scenario`), ``--in-place`` the
  scenario file itself (the one case in which an input is replaced, and only when asked for);
* ``flatstep calibrate SCENARIO --accuracy``: calibrate every plant of its ``[robustness]`` study with the nominal
  model, and the errors against the true plants and the targets.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any, Optional

from ..control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES
from ..json_out import strict_json
from ..studies.calibrate import calibration_horizon
from ..studies.robustness import plant_errors
from ..studies.scenario import Scenario
from ..studies.scenario_file import Robustness, load_scenario
from ..validate import InputError, check_positive
from ..validate.limits import check_resources, estimate
from ..validate.paths import check_output
from .flags import count, quantity
from .status import EXIT_REFUSED

#: Most plants ``--accuracy`` calibrates (about 0.15 s each: 20 s).
MAX_CALIBRATED_PLANTS = 128


def _accuracy(args: argparse.Namespace, scenario: Scenario, study: Optional[Robustness]) -> int:
    """``--accuracy``: the table of :func:`~flatstep.studies.calibrate_accuracy.accuracy_table`."""
    from ..studies.calibrate_accuracy import accuracy, accuracy_table, meets_targets, worst

    plants = len(plant_errors(study or Robustness()))
    if plants > MAX_CALIBRATED_PLANTS:
        raise ValueError(f"{args.scenario}: [robustness] has {plants} plants; --accuracy calibrates at most "
                         f"{MAX_CALIBRATED_PLANTS} (about 0.15 s each): lower [robustness] samples")
    rows = accuracy(scenario, study or Robustness(), coulomb_speed=args.coulomb_speed, **_options(args))
    met = meets_targets(rows)
    if args.json:
        print(strict_json({"scenario": scenario.name, "rows": rows, "worst": worst(rows), "targets_met": met},
                         indent=2))
    else:
        print(f"{scenario.name}: calibration errors on {len(rows)} plants (the nominal model calibrates each)")
        print(accuracy_table(rows))
        print("targets: " + ", ".join(f"{k} {'met' if ok else 'MISSED'}" for k, ok in met.items()))
    return 0 if all(met.values()) else EXIT_REFUSED


#: The first bytes of the table ``--out`` writes; a file that holds this line is one ``calibrate`` wrote.
TABLE_MARK = b"# calibrated by 'flatstep calibrate'"
#: The flags ``--accuracy`` does not read (it writes no table and calibrates with the defaults of its own move).
NOT_WITH_ACCURACY = ("--out", "--merge", "--in-place", "--force")
#: Which flag sets each keyword of :func:`~flatstep.studies.calibrate.calibrate`, for messages.
FLAG_OF = {"peak_speed": "--speed", "periods": "--periods", "detent_harmonic": "--harmonic",
           "coulomb_speed": "--coulomb-speed", "current_noise": "--noise", "controller": "--controller"}


def _speed(text: str) -> float:
    """``--speed``: a finite number > 0 [rad/s] (the move it makes is checked against the drive later)."""
    try:
        return check_positive("speed", float(text), unit=" rad/s")
    except (ValueError, OverflowError) as exc:
        raise argparse.ArgumentTypeError(f"--speed {text!r}: give a peak speed > 0 rad/s ({exc})") from None


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """The keywords of the calibration's move that the flags set."""
    return {"controller": args.controller, "periods": args.periods, "peak_speed": args.speed,
            "detent_harmonic": args.harmonic, "current_noise": args.noise}


def _check_move(scenario: Scenario, args: argparse.Namespace) -> None:
    """Refuse the move's flags before any work: each named by its flag, the move's cost within the limits."""
    try:
        horizon = calibration_horizon(scenario, periods=args.periods, peak_speed=args.speed,
                                      detent_harmonic=args.harmonic)
    except InputError as exc:
        raise exc.at(FLAG_OF[exc.name]) if exc.name in FLAG_OF else exc from None
    loop = scenario.loop
    assert loop is not None  # calibration_horizon checked the drive
    check_resources(estimate(horizon, control_period=loop.control_period, substeps=loop.substeps),
                    what=f"the calibration move of {horizon:.4g} s ({args.periods} detent periods each way"
                    + (f" at --speed {args.speed:g} rad/s)" if args.speed is not None else ")"))


def _owned(path: str) -> bool:
    """Whether ``path`` holds a table 'flatstep calibrate' wrote (a merged scenario holds it at its end)."""
    try:
        return TABLE_MARK in Path(path).read_bytes()
    except OSError:
        return False


def _write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file beside it, so that a failed write leaves ``path`` whole."""
    tmp = path.with_name(f".{path.name}.flatstep-tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def _targets(args: argparse.Namespace) -> tuple[Optional[Path], Optional[Path]]:
    """The ``--out`` and merge files, checked (:func:`~flatstep.validate.paths.check_output`) before any work."""
    if args.in_place and args.merge:
        raise InputError("--in-place", args.merge, f"--in-place merges into {args.scenario} itself and --merge "
                         f"{args.merge} into a new file: give one of them")
    out = merge = None
    if args.out:
        out = check_output(args.out, "--out", inputs=[args.scenario, args.merge], force=args.force,
                           marks=(TABLE_MARK,))
    if args.merge:
        merge = check_output(args.merge, "--merge", inputs=[args.scenario, args.out],
                             force=args.force or _owned(args.merge), marks=(TABLE_MARK,))
    if args.in_place:  # asked for explicitly: the one case in which an input is replaced
        merge = check_output(args.scenario, "--in-place", inputs=[args.out], force=True)
    return out, merge


def cmd_calibrate(args: argparse.Namespace) -> int:
    """``flatstep calibrate``: one of the two uses of the module docstring."""
    if args.accuracy:
        given = [f for f in NOT_WITH_ACCURACY if getattr(args, f.lstrip("-").replace("-", "_")) not in (None, False)]
        if given:
            raise InputError(given[0], True, f"--accuracy calibrates every plant of the study: it writes no table "
                             f"(drop {', '.join(given)})")
        scenario, study = load_scenario(args.scenario)
        _check_move(scenario, args)
        return _accuracy(args, scenario, study)
    out, merge = _targets(args)
    from ..studies.calibrate import calibrate, merged_scenario

    scenario, _ = load_scenario(args.scenario)
    _check_move(scenario, args)
    source_text = Path(args.scenario).read_text(encoding="utf-8") if merge is not None else ""
    cal = calibrate(scenario, coulomb_speed=args.coulomb_speed, **_options(args))
    if args.json:
        print(strict_json(cal.as_dict(), indent=2))
    else:
        s = cal.settings
        print(f"{scenario.name}: {s['samples']} samples, {s['controller']} over {s['periods']} detent periods each "
              f"way at {s['peak_speed']:.4g} rad/s peak")
        for key, value in cal.estimates.items():
            print(f"  {key:<16}{value:>14.6g}  +- {cal.std[key]:.2g}")
        print(cal.as_toml(), end="")
    if out is not None:
        _write(out, cal.as_toml())
    if merge is not None:
        _write(merge, merged_scenario(source_text, cal))
    if not args.json:
        for path in (out, merge):
            if path is not None:
                print(f"wrote {path}")
    return 0


DESCRIPTION = """Calibrate the detent (amplitude, phase), the Coulomb friction and the load of a scenario's plant
from a slow move there and back on its drive, read by its own sensors (encoder, current ADC); the result is the
scenario's [feedforward] table, which the _ff controllers and the cascade's anti-cogging read.

  flatstep calibrate SCENARIO [--out TABLE.toml] [--merge NEW.toml | --in-place]
      calibrate the scenario's plant; print the table, write it, or write the scenario with it merged
      (into a new file, or into SCENARIO itself with --in-place)
  flatstep calibrate SCENARIO --accuracy
      calibrate each plant of the scenario's [robustness] study; the errors against the targets"""


def add_calibrate_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep calibrate`` to the subcommands ``sub``."""
    cal = sub.add_parser("calibrate", help="the detent, Coulomb friction and load from the drive's own sensors",
                         description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    cal.add_argument("scenario", help="a scenario file (TOML) with a sampled drive and sensors")
    types = [k for k in CONTROLLER_TYPES if k not in FEEDFORWARD_TYPES]
    cal.add_argument("--controller", choices=types, default="cascade",
                     help="the controller that runs the move (default: cascade)")
    cal.add_argument("--periods", type=count("periods", "--periods"),
                     default=16, help="detent periods covered each way (default 16)")
    cal.add_argument("--speed", type=_speed, default=None,
                     help="peak speed [rad/s] (default: the detent frequency at a quarter of the loop's omega_n)")
    cal.add_argument("--harmonic", type=count("detent_harmonic", "--harmonic"),
                     default=4, help="detent periods per electrical period (default 4)")
    cal.add_argument("--coulomb-speed", type=quantity("coulomb_speed", "--coulomb-speed"), default=0.1,
                     help="omega_s [rad/s] of the table's smooth Coulomb sign (default 0.1)")
    cal.add_argument("--noise", type=quantity("current_noise", "--noise"), default=None,
                     help="ADC noise [A rms] instead of the scenario's sensors' own")
    cal.add_argument("--out", default=None, help="write the [feedforward] table (TOML) here")
    cal.add_argument("--merge", metavar="NEW.toml", default=None,
                     help="write the scenario file here with its [feedforward] replaced by the calibrated table "
                     "(a new file: never the scenario itself)")
    cal.add_argument("--in-place", action="store_true",
                     help="replace the [feedforward] table in the scenario file itself (the only way calibrate "
                     "writes over its input)")
    cal.add_argument("--force", action="store_true",
                     help="let --out and --merge replace a file flatstep did not write (never the scenario)")
    cal.add_argument("--accuracy", action="store_true",
                     help="calibrate every plant of the [robustness] study; errors against the targets")
    cal.add_argument("--json", action="store_true", help="print the result as JSON")
    cal.set_defaults(func=cmd_calibrate)
