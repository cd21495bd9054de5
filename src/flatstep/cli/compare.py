"""Command line: ``flatstep compare SCENARIO.toml``: every controller on the same plant, drive and sensors."""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from typing import Any, Literal, Optional, Sequence

from ..control.spec import ControllerSpec, is_controller
from ..control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES, LABELS, SMC_TYPES
from ..json_out import strict_json
from ..studies.calibrate import calibration_horizon
from ..studies.compare import bandwidth_sweep, check_calibrate, compare, compare_worst, default_band, scenario_kinds
from ..studies.robustness import encoder_count, perturbed, plant_errors
from ..studies.scenario import Scenario
from ..studies.scenario_file import Robustness, read_scenario_file
from ..validate import InputError, check_quantity
from ..validate.limits import check_study, estimate
from ..validate.paths import PNG_MARK, check_output_dir, json_marks
from .columns import name_width
from .flags import add_force, count, out_dir, quantity
from .plan import scenario_on_drive
from .status import EXIT_STOPPED, exit_code, warn
from .tune import add_tune_flags

#: (metric, column head, scale of the printed value: "angle" uses counts or rad)
COLUMNS: tuple[tuple[str, str, float | Literal["angle"]], ...] = (
    ("move_max", "max err", "angle"), ("move_rms", "rms err", "angle"), ("final", "final", "angle"),
    ("settling_time", "settle[ms]", 1e3), ("peak_voltage", "peak V", 1.0), ("peak_current", "peak A", 1.0),
    ("rms_current", "rms A", 1.0), ("copper_loss", "Cu [mJ]", 1e3))


def _cell(value: Optional[float], scale: float | Literal["angle"], count: Optional[float]) -> str:
    """One table cell: ``value`` times ``scale``, or an angle in counts (rad without ``count``), 11 wide."""
    if value is None:
        return f"{'unsettled':>11}"
    if scale == "angle":
        return f"{value / count:>11.3f}" if count else f"{value:>11.3e}"
    return f"{value * scale:>11.4g}"


def table(rows: dict[str, dict[str, Optional[float]]], count: Optional[float]) -> str:
    """The metrics as a fixed-width table, one row per controller (angles in encoder counts when ``count``)."""
    unit = "counts" if count else "rad"
    width = name_width((LABELS.get(kind, kind) for kind in rows), "controller", 22)
    lines = [f"{'controller':<{width}}" + "".join(f"{head:>11}" for _, head, _ in COLUMNS) + f"   [angles in {unit}]"]
    for kind, m in rows.items():
        lines.append(f"{LABELS.get(kind, kind):<{width}}" + "".join(_cell(m[k], s, count) for k, _, s in COLUMNS))
    return "\n".join(lines)


def _target_line(rows: dict[str, dict[str, Optional[float]]], count: Optional[float]) -> Optional[str]:
    """The targets, the best flatness row against the plain cascade, met or missed; None without both.

    The best flatness row is the one with the smallest max error during the move among the types whose label begins
    with "flatness". Targets: at most 1/3 of the cascade's error and (with an encoder) 1 count, at most 1.2x its
    copper loss, no higher peak voltage.
    """
    flat = [k for k in rows if LABELS.get(k, k).startswith("flatness") and rows[k]]
    if not flat or not rows.get("cascade"):
        return None
    c = rows["cascade"]
    best = min(flat, key=lambda k: rows[k]["move_max"] or 0.0)
    s = rows[best]
    s_max, c_max, s_peak, c_peak = s["move_max"], c["move_max"], s["peak_voltage"], c["peak_voltage"]
    s_cu, c_cu = s["copper_loss"], c["copper_loss"]
    # only settling_time is ever None (flatstep.studies.compare.metrics)
    assert s_max is not None and c_max is not None and s_peak is not None and c_peak is not None
    assert s_cu is not None and c_cu is not None
    checks = [(f"max error during the move x{s_max / c_max:.3g} of the cascade's (<= 1/3)", s_max <= c_max / 3)]
    if count:
        checks.append((f"{s_max / count:.3g} counts (<= 1)", s_max <= count))
    checks += [(f"copper loss x{s_cu / c_cu:.3g} (<= 1.2)", s_cu <= 1.2 * c_cu),
               (f"peak voltage {s_peak:.3g} V vs {c_peak:.3g} V (no higher)", s_peak <= c_peak)]
    return (f"targets, {LABELS.get(best, best)} against {LABELS['cascade']}: "
            + "; ".join(f"{what}: {'met' if ok else 'missed'}" for what, ok in checks))


class _Log:
    """Progress of the comparison's stages on stderr, each with the time since the start."""

    def __init__(self, enabled: bool) -> None:
        self.enabled, self.start = enabled, time.perf_counter()

    def __call__(self, what: str) -> None:
        if self.enabled:
            print(f"[compare {time.perf_counter() - self.start:6.1f} s] {what}", file=sys.stderr, flush=True)


def _scales(text: str) -> list[float]:
    """The factors of ``--scales`` (``0.5,2``), each a number in (0, 1000]."""
    try:
        return [check_quantity("scale", float(x), as_name="--scales") for x in text.split(",")]
    except ValueError as exc:
        raise ValueError(f"--scales {text!r}: give factors in (0, 1000] separated by commas ({exc})") from None


def _check_work(scenario: Scenario, study: Optional[Robustness], kinds: Sequence[str],
                args: argparse.Namespace) -> None:
    """Refuse a comparison whose runs would exceed the study limit (:func:`flatstep.validate.limits.check_study`)."""
    loop = scenario.loop
    assert loop is not None  # checked by the caller
    drive = loop.drive
    pwm = drive.pwm_periods(loop.control_period) if drive is not None and drive.pwm == "switched" else 0
    cost = estimate(scenario.t_end, control_period=loop.control_period, substeps=loop.substeps, pwm_per_period=pwm)
    if study is not None and not args.no_robustness:
        study = replace(study, samples=args.samples) if args.samples is not None else study
    plants = len(plant_errors(study)) if study is not None and not args.no_robustness else 0
    scales = len(args.scales.split(",")) if args.scales else 0
    baselines = [k for k in kinds if k not in SMC_TYPES]
    runs = len(kinds) * (1 + plants) + scales * len(baselines) * max(plants, 1)
    if args.calibrate_each:  # per plant and the scenario's, once and again per scale at most; each as many runs
        calibration = estimate(calibration_horizon(scenario), control_period=loop.control_period,
                               substeps=loop.substeps, pwm_per_period=pwm)
        runs += (1 + scales) * (1 + plants) * math.ceil(calibration.steps / max(cost.steps, 1))
    check_study(runs, cost, engine=args.engine, what=f"the comparison of {len(kinds)} controllers on {plants} plants"
                + (" with each calibrated" if args.calibrate_each else ""))


def _plant_names(scenario: Scenario, study: Robustness) -> list[str]:
    """The name of each plant of the study's calibrations, in order (those of :func:`compare_worst`)."""
    return [p.name for p in perturbed(scenario, plant_errors(study), "/calibration")]


#: The files ``flatstep compare --out`` writes, and the first bytes that make an existing one flatstep's.
COMPARE_FILES = {"overlay.png": PNG_MARK, "plants.png": PNG_MARK, "compare.json": json_marks("name", "scenario")}


def cmd_compare(args: argparse.Namespace) -> int:
    """``flatstep compare``: every controller on the scenario's plant, its robustness study and bandwidth sweep."""
    if args.tuned is not None or args.held_out:
        from .compare_tuned import cmd_compare_tuned

        return cmd_compare_tuned(args)
    if args.out:  # before any work
        check_output_dir(args.out, "--out", COMPARE_FILES, inputs=[args.scenario], force=args.force)
    sf = read_scenario_file(args.scenario)
    scenario, study = scenario_on_drive(sf, skip=args.no_verify), sf.robustness
    if args.clean:  # the plant equal to the model: no load, no effects, so nothing to feed forward
        scenario = replace(scenario, name=f"{scenario.name} (clean)", plant=None, torques=None,
                           controller_type=ControllerSpec.parse(scenario.controller_type).without_torques().name())
    if scenario.control_period is None:
        raise ValueError(f"{args.scenario} has no [drive] control_rate: the baselines run on the sampled drive loop")
    if args.samples is not None and (study is None or args.no_robustness):
        why = "--no-robustness skips it" if args.no_robustness else f"{args.scenario} has no [robustness] table"
        raise InputError("--samples", args.samples, f"--samples {args.samples} sets the plants of the [robustness] "
                         f"study, and {why}: drop --samples")
    mode = "each" if args.calibrate_each else None
    every = CONTROLLER_TYPES if mode == "each" else scenario_kinds(scenario)  # each unit brings its own table
    kinds = tuple(k.strip() for k in args.controllers.split(",")) if args.controllers else every
    unknown = [k for k in kinds if not is_controller(k)]
    if unknown or not kinds or len(set(kinds)) != len(kinds):
        raise ValueError(f"--controllers {args.controllers!r}: give distinct names among {list(CONTROLLER_TYPES)} "
                         "(or law+option+...), separated by commas")
    if args.band is not None and args.band <= 0:
        raise ValueError(f"--band {args.band!r}: the settling band must be > 0 rad")
    band = args.band if args.band is not None else default_band(scenario)
    if args.scales and all(k in SMC_TYPES for k in kinds):
        raise ValueError(f"--scales {args.scales!r} sweeps the baselines' bandwidth, and --controllers "
                         f"{args.controllers!r} names none: add one of "
                         f"{[k for k in CONTROLLER_TYPES if k not in SMC_TYPES]}, or drop --scales")
    scales = _scales(args.scales) if args.scales else []
    try:
        check_calibrate(mode, scenario, kinds)
    except ValueError as exc:
        raise ValueError(f"--calibrate-each: {exc}") from None
    _check_work(scenario, study, kinds, args)
    count = encoder_count(scenario)
    log = _Log(enabled=not args.quiet)
    nominal = compare(scenario, kinds, band=band, engine=args.engine, calibrate=mode)
    log(f"{len(nominal)} controllers on the scenario's plant{', calibrated on its drive' if mode else ''}")
    report: dict[str, Any] = {"scenario": scenario.name, "band_rad": band, "count_rad": count, "calibrate": mode,
                              "controllers": {k: {"label": LABELS[k], "metrics": v["metrics"], "faults": v["faults"],
                                                  "status": v["status"], "lost_at": v["lost_at"], "error": v["error"],
                                                  "gains": v["result"].meta["gains"] if v["result"] else None,
                                                  "engine": v["result"].meta["engine"] if v["result"] else None}
                                              for k, v in nominal.items()}}
    worst = None
    if study is not None and not args.no_robustness:
        study = replace(study, samples=args.samples) if args.samples is not None else study
        worst = compare_worst(scenario, study, kinds, band=band, engine=args.engine, progress=not args.quiet,
                              log=log, calibrate=mode)
        units = next((v["calibrations"] for v in worst.values() if v["calibrations"] is not None), None)
        report["robustness"] = {"relative_error": study.relative_error, "parameters": list(study.parameters),
                                "plants": len(next(iter(worst.values()))["rows"]), "calibrate": mode,
                                "calibrations": None if units is None else [
                                    {"plant": u.source, "feedforward": u.torques.as_dict(), "Km": u.estimates["Km"]}
                                    if not isinstance(u, str) else {"plant": p, "error": u}
                                    for p, u in zip(_plant_names(scenario, study), units, strict=True)],
                                "worst": {k: {"metrics": v["worst"], "failed": v["failed"], "failures": v["failures"],
                                              "statuses": v["statuses"]} for k, v in worst.items()}}
    if scales:
        baselines = [k for k in kinds if k not in SMC_TYPES]
        calibrated = mode if any(k in FEEDFORWARD_TYPES for k in baselines) else None  # cascade_ff, cascade_model
        sweep = bandwidth_sweep(scenario, baselines, scales, study=study if worst is not None else None, band=band,
                                engine=args.engine, progress=not args.quiet, log=log, calibrate=calibrated)
        report["bandwidth_sweep"] = {str(s): v for s, v in sweep.items()}
    if args.out:
        from .plots_compare import plot_overlay, plot_plants

        out = out_dir(args.out)
        plot_overlay({LABELS[k]: v["result"] for k, v in nominal.items() if v["result"] is not None}, scenario.plan,
                     count,
                     title=f"{scenario.name}: every controller on the scenario's plant", path=out / "overlay.png")
        if worst is not None:
            plot_plants(worst, LABELS, scenario.plan, count, path=out / "plants.png",
                        title=f"{scenario.name}: {report['robustness']['plants']} plants, parameters off by "
                              f"+-{report['robustness']['relative_error']:.0%}")
        (out / "compare.json").write_text(strict_json(report, indent=2) + "\n")
    statuses = [v["status"] for v in nominal.values()]
    if worst is not None:
        statuses += [s for v in worst.values() for s, n in v["statuses"].items() for _ in range(n)]
    failed = sum(v["error"] is not None for v in nominal.values()) + (
        sum(v["failed"] for v in worst.values()) if worst is not None else 0)
    code = EXIT_STOPPED if failed else exit_code(statuses)  # a row without a result is the worst outcome
    if args.json:
        print(strict_json(report, indent=2))
        return code
    print(f"{scenario.name}: the scenario's plant (settling band {band:.3g} rad)"
          + (", calibrated on its own drive" if mode else ""))
    rows = {k: v["metrics"] for k, v in nominal.items() if v["metrics"] is not None}
    print(table(rows, count))
    print("status: " + ", ".join(f"{LABELS[k]} {v['status']}" for k, v in nominal.items()))
    for kind, v in nominal.items():
        if v["error"] is not None:
            print(f"flatstep: warning: {LABELS[kind]}: did not run: {v['error']}", file=sys.stderr)
        else:
            warn(LABELS[kind], {"status": v["status"], "lost_at": v["lost_at"], "controller_faults": v["faults"]})
    line = _target_line(rows, count)
    if worst is not None:
        r = report["robustness"]
        print(f"\nworst over {r['plants']} plants, {', '.join(r['parameters'])} off by +-{r['relative_error']:.0%}"
              + (", each calibrated on its own drive" if mode else ""))
        rows = {k: v["worst"] for k, v in worst.items() if v["worst"]}
        print(table(rows, count))
        print("status over the plants: " + ", ".join(
            f"{LABELS[k]} {v['statuses']['ok']} ok/{v['statuses']['lost']} lost/{v['statuses']['fault']} faulted"
            + (f"/{v['failed']} failed" if v["failed"] else "") for k, v in worst.items()))
        for kind, v in worst.items():
            if v["failed"]:
                print(f"flatstep: warning: {LABELS[kind]}: {v['failed']} of {v['runs']} plants have no result: "
                      f"{v['failures'][0]}", file=sys.stderr)
            if v["statuses"]["lost"] or v["statuses"]["fault"]:
                print(f"flatstep: warning: {LABELS[kind]}: {v['statuses']['lost']} of {v['runs']} plants lost the "
                      f"move, {v['statuses']['fault']} faulted", file=sys.stderr)
        line = _target_line(rows, count) or line
    if args.scales:
        where = "worst over the plants" if worst is not None else "the scenario's plant"
        print(f"\nbaselines with every bandwidth scaled ({where}): max error during the move, peak voltage")
        sweep = report["bandwidth_sweep"]
        w = name_width((LABELS[k] for res in sweep.values() for k in res), "", 24)
        for s, res in sweep.items():
            print(f"  x{float(s):<5g}" + "".join(f"{LABELS[k]:>{w}}: {_cell(m['move_max'], 'angle', count).strip():>8}"
                                                 f" {m['peak_voltage']:6.3g} V" if m else f"{LABELS[k]:>{w}}: no result"
                                                 for k, m in res.items()))
    if line:
        print("\n" + line)
    return code


def add_compare_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep compare`` to the subcommands ``sub``."""
    cmp_ = sub.add_parser("compare", help="every controller (flatness + SMC and the baselines) on one scenario",
                          description="Run every controller type on one scenario's drive (the flatness laws and "
                          "the baselines: open-loop microstepping, cascaded FOC, exact linearization) and print "
                          "tracking error (encoder counts), settling time [ms], peak voltage [V], current [A] and "
                          "copper loss [mJ]; then the worst of each over the file's [robustness] plants.")
    cmp_.add_argument("scenario", help="a scenario file (TOML) with a [drive]; its [robustness], if any, is run too")
    cmp_.add_argument("--controllers", default=None,
                      help=f"comma-separated controller types (default: all of {','.join(CONTROLLER_TYPES)})")
    cmp_.add_argument("--band", type=quantity("angle", "--band"), default=None,
                      help="settling band [rad] (default: one encoder count)")
    cmp_.add_argument("--clean", action="store_true", help="no load, no plant effects, the plant equal to the "
                      "model, no [feedforward] (the file's drive, sensors and gains otherwise)")
    cmp_.add_argument("--no-robustness", action="store_true", help="skip the file's [robustness] study")
    cmp_.add_argument("--samples", type=count("samples", "--samples"), default=None,
                      help="random plants instead of all sign combinations")
    cmp_.add_argument("--scales", default=None, help="also run the baselines with every bandwidth scaled by these "
                      "comma-separated factors (e.g. 0.5,2): the check that their tuning does not cripple them")
    cmp_.add_argument("--calibrate-each", action="store_true",
                      help="calibrate each plant on its own drive first ('flatstep calibrate' on it, as firmware "
                      "calibrates each unit) and run the types that read a calibration "
                      f"({','.join(FEEDFORWARD_TYPES)}) with that plant's [feedforward] table and back-EMF Km in "
                      "their model; the other types run as without it. Needs [sensors]")
    cmp_.add_argument("--engine", choices=("c", "python"), default="c",
                      help="who runs the loops: the C core (default) or the Python reference loop (slow)")
    cmp_.add_argument("--quiet", action="store_true", help="no progress on stderr")
    cmp_.add_argument("--no-verify", action="store_true", help="run a plan made against [limits] as the file gives "
                     "it, without the check on the drive 'flatstep plan' runs (by default the plan plan reports "
                     "feasible: backed off if the drive would lose it, refused if no back-off keeps it)")
    cmp_.add_argument("--out", default=None, help="write overlay.png, plants.png and compare.json here")
    add_force(cmp_)
    cmp_.add_argument("--json", action="store_true", help="print the report as JSON")
    cmp_.add_argument("--tuned", nargs="?", const="", default=None, metavar="PATH",
                      help="compare the laws each tuned by 'flatstep tune' (the same budget, seed and caps; "
                      "--controllers default: one type per law), or read from PATH (a tuned file, or a directory "
                      "of them); prints the tuned rows, the frontier and how often a sliding law's |s| is outside "
                      "its boundary layer; --out writes frontier.png and tuned.json")
    cmp_.add_argument("--held-out", action="store_true",
                      help="with --tuned PATH: re-run the read gains, and the default controller at its rule gains, "
                      "on runs they were not tuned on (32 random plants, the move 1 and 2 %% shorter and longer) "
                      "and print each law's mean over them (docs/comparison.md)")
    cmp_.add_argument("--frontier", default="0.5,0.75,1", metavar="FRACTIONS",
                      help="with --tuned: the peak-voltage caps of the frontier, fractions of the bus separated by "
                      "commas (default 0.5,0.75,1; each is a search)")
    add_tune_flags(cmp_)
    cmp_.set_defaults(func=cmd_compare)
