"""Command line: ``flatstep calibrate``, the detent, Coulomb friction and load from the drive's own sensors.

* ``flatstep calibrate SCENARIO [--out TABLE.toml] [--merge NEW.toml]``: calibrate the scenario's plant and print
  the ``[feedforward]`` table; ``--merge`` writes the scenario file with its table replaced by the calibrated one;
* ``flatstep calibrate SCENARIO --accuracy``: calibrate every plant of its ``[robustness]`` study with the nominal
  model, and the errors against the true plants and the targets.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ..control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES
from ..json_out import strict_json
from ..studies.robustness import plant_errors
from ..studies.scenario_file import Robustness, load_scenario
from .flags import count, quantity
from .status import EXIT_REFUSED

#: Most plants ``--accuracy`` calibrates (about 0.15 s each: 20 s).
MAX_CALIBRATED_PLANTS = 128


def _accuracy(args: argparse.Namespace) -> int:
    """``--accuracy``: the table of :func:`~flatstep.studies.calibrate_accuracy.accuracy_table`."""
    from ..studies.calibrate_accuracy import accuracy, accuracy_table, meets_targets, worst

    scenario, study = load_scenario(args.scenario)
    plants = len(plant_errors(study or Robustness()))
    if plants > MAX_CALIBRATED_PLANTS:
        raise ValueError(f"{args.scenario}: [robustness] has {plants} plants; --accuracy calibrates at most "
                         f"{MAX_CALIBRATED_PLANTS} (about 0.15 s each): lower [robustness] samples")
    rows = accuracy(scenario, study or Robustness(), controller=args.controller, periods=args.periods,
                    peak_speed=args.speed, detent_harmonic=args.harmonic, current_noise=args.noise)
    met = meets_targets(rows)
    if args.json:
        print(strict_json({"scenario": scenario.name, "rows": rows, "worst": worst(rows), "targets_met": met},
                         indent=2))
    else:
        print(f"{scenario.name}: calibration errors on {len(rows)} plants (the nominal model calibrates each)")
        print(accuracy_table(rows))
        print("targets: " + ", ".join(f"{k} {'met' if ok else 'MISSED'}" for k, ok in met.items()))
    return 0 if all(met.values()) else EXIT_REFUSED


def cmd_calibrate(args: argparse.Namespace) -> int:
    """``flatstep calibrate``: one of the two uses of the module docstring."""
    for flag, path in (("--out", args.out), ("--merge", args.merge)):
        if path is not None and Path(path).is_dir():
            raise ValueError(f"{flag} {path}: is a directory; give a file name")
    if args.accuracy:
        if args.out or args.merge:
            raise ValueError("--accuracy calibrates every plant of the study: it writes no table (drop --out/--merge)")
        return _accuracy(args)
    from ..studies.calibrate import calibrate, merged_scenario

    scenario, _ = load_scenario(args.scenario)
    cal = calibrate(scenario, controller=args.controller, periods=args.periods, peak_speed=args.speed,
                    detent_harmonic=args.harmonic, coulomb_speed=args.coulomb_speed, current_noise=args.noise)
    if args.json:
        print(strict_json(cal.as_dict(), indent=2))
    else:
        s = cal.settings
        print(f"{scenario.name}: {s['samples']} samples, {s['controller']} over {s['periods']} detent periods each "
              f"way at {s['peak_speed']:.4g} rad/s peak")
        for key, value in cal.estimates.items():
            print(f"  {key:<16}{value:>14.6g}  +- {cal.std[key]:.2g}")
        print(cal.as_toml(), end="")
    if args.out:
        Path(args.out).write_text(cal.as_toml())
    if args.merge:
        Path(args.merge).write_text(merged_scenario(Path(args.scenario).read_text(encoding="utf-8"), cal))
    if not args.json:
        for path in (args.out, args.merge):
            if path:
                print(f"wrote {path}")
    return 0


DESCRIPTION = """Calibrate the detent (amplitude, phase), the Coulomb friction and the load of a scenario's plant
from a slow move there and back on its drive, read by its own sensors (encoder, current ADC); the result is the
scenario's [feedforward] table, which the _ff controllers and the cascade's anti-cogging read.

  flatstep calibrate SCENARIO [--out TABLE.toml] [--merge NEW.toml]
      calibrate the scenario's plant; print the table, write it, or write the scenario with it merged
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
    cal.add_argument("--speed", type=float, default=None,
                     help="peak speed [rad/s] (default: the detent frequency at a quarter of the loop's omega_n)")
    cal.add_argument("--harmonic", type=count("detent_harmonic", "--harmonic"),
                     default=4, help="detent periods per electrical period (default 4)")
    cal.add_argument("--coulomb-speed", type=quantity("coulomb_speed", "--coulomb-speed"), default=0.1,
                     help="omega_s [rad/s] of the table's smooth Coulomb sign (default 0.1)")
    cal.add_argument("--noise", type=quantity("current_noise", "--noise"), default=None,
                     help="ADC noise [A rms] instead of the scenario's sensors' own")
    cal.add_argument("--out", default=None, help="write the [feedforward] table (TOML) here")
    cal.add_argument("--merge", metavar="NEW.toml", default=None,
                     help="write the scenario file here with its [feedforward] replaced by the calibrated table")
    cal.add_argument("--accuracy", action="store_true",
                     help="calibrate every plant of the [robustness] study; errors against the targets")
    cal.add_argument("--json", action="store_true", help="print the result as JSON")
    cal.set_defaults(func=cmd_calibrate)
