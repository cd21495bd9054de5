"""Command line: ``flatstep compare --tuned``, the tuned laws side by side and their frontiers."""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional

from ..control.spec import LAWS, ControllerSpec, default_type
from ..json_out import strict_json
from ..studies.frontier import Frontier, FrontierPoint, check_fractions, frontier, outside_layer
from ..studies.held_out import held_out, held_out_mean, held_out_runs
from ..studies.robustness import encoder_count
from ..studies.scenario import Scenario
from ..studies.scenario_file import Robustness, read_scenario_file
from ..studies.tune import Caps, Evaluation, evaluate, study_of
from ..studies.tune_file import read_tuned
from ..studies.tune_laws import law_gains
from ..validate import InputError
from ..validate.paths import PNG_MARK, check_output_dir, json_marks
from .columns import name_width
from .flags import out_dir
from .plan import scenario_on_drive
from .status import EXIT_LOST, EXIT_OK
from .tune import Log, caps_line, caps_of, check_work, header, laws_of, row

#: The files ``flatstep compare --tuned --out`` writes.
TUNED_FILES = {"frontier.png": PNG_MARK, "tuned.json": json_marks("scenario")}


def _refuse_other_flags(args: argparse.Namespace) -> None:
    """``--tuned`` runs its own study: the bandwidth sweep, the calibration and the Python engine do not apply."""
    for flag, given in (("--scales", args.scales), ("--calibrate-each", args.calibrate_each),
                        ("--band", args.band is not None), ("--no-robustness", args.no_robustness),
                        ("--engine python", args.engine != "c")):
        if given:
            raise InputError(flag, given, f"{flag} does not apply with --tuned (the tuner runs every plant of the "
                             "study on the C engine, one encoder count as the settling band); drop it")


def read_gains(path: str, source: str = "--tuned") -> dict[str, tuple[dict[str, float], str]]:
    """Each law's tuned gains at ``path`` and where they come from, by controller type.

    ``path`` is a tuned scenario file or a directory of them (``flatstep tune --out``), or the ``tuned.json`` of
    ``flatstep compare --tuned --out`` (each law's answer at the full cap).
    """
    if Path(path).suffix != ".json":
        files = read_tuned(path, source)
        return {kind: (law_gains(kind).read(sf.scenario), str(sf.path)) for kind, sf in files.items()}
    try:
        report = json.loads(Path(path).read_text())
        points = {kind: f["points"][-1]["best"] for kind, f in report["frontiers"].items()}
    except (OSError, ValueError, KeyError, IndexError, TypeError, AttributeError) as exc:
        raise InputError(source, path, f"{source} {path}: not a tuned.json of 'flatstep compare --tuned --out' "
                         f"({type(exc).__name__}: {exc})") from None
    out = {}
    for kind, best in points.items():
        if best is not None:
            law_gains(kind, source)
            out[kind] = ({k: float(v) for k, v in best["gains"].items()}, path)
    if not out:
        raise InputError(source, path, f"{source} {path}: no law in it met the caps; nothing to read")
    return out


def cmd_compare_tuned(args: argparse.Namespace) -> int:
    """``flatstep compare --tuned [PATH]``: each law tuned (or read from PATH), its frontier, its layer share."""
    _refuse_other_flags(args)
    if args.out:  # before any work
        check_output_dir(args.out, "--out", TUNED_FILES, inputs=[args.scenario], force=args.force)
    sf = read_scenario_file(args.scenario)
    names = [k.strip() for k in args.controllers.split(",")] if args.controllers else list(LAWS)
    kinds = laws_of(names, sf.scenario, "--controllers")
    given = read_gains(args.tuned) if args.tuned else {}
    if args.held_out and args.out:
        raise InputError("--out", args.out, "--out does not apply with --held-out (it prints its table); drop it")
    if args.held_out:
        missing = [k for k in kinds if k not in given]
        if not given or missing:
            raise InputError("--held-out", args.tuned or "", "--held-out re-runs gains read from --tuned PATH, and "
                             + (f"{', '.join(missing)} is not in {args.tuned}" if given else "no PATH is given")
                             + "; give PATH (a tuned.json, a tuned file or a directory of them) and name its laws")
    fractions = check_fractions([float(f) for f in args.frontier.split(",")] if args.frontier else [1.0],
                                "--frontier") if not given else (1.0,)
    caps = caps_of(args)
    scenario = scenario_on_drive(sf, skip=args.no_verify)
    if args.clean:
        scenario = replace(scenario, name=f"{scenario.name} (clean)", plant=None, torques=None,
                           controller_type=ControllerSpec.parse(scenario.controller_type).without_torques().name())
    study = sf.robustness
    if args.samples is not None:
        study = replace(study, samples=args.samples) if study is not None else None
    check_work(scenario, sf, args.budget)
    if args.held_out:
        return _held_out(scenario, study, {k: given[k][0] for k in kinds}, args.json)
    log = Log(enabled=not args.quiet, what="compare --tuned")
    frontiers: dict[str, Frontier] = {}
    tuned = {}
    for kind in kinds:
        if kind in given:  # the file's gains, evaluated on these plants under these caps
            table = law_gains(kind)
            sc = table.apply(replace(scenario, controller_type=kind), given[kind][0])
            full = caps.for_scenario(sc)
            ev = evaluate([sc], study_of(sc, study), [table.read(sc)])[0]
            ok = ev.ok and full.excess(ev) == 0.0
            frontiers[kind] = Frontier(kind, [FrontierPoint(full.peak_voltage or 0.0, ev if ok else None)], [])
            tuned[kind] = sc
            log(f"{kind}: read from {given[kind][1]}, evaluated on {ev.plants} plants")
            continue
        fr = frontier(scenario, kind, fractions=fractions, caps=caps, budget=args.budget, seed=args.seed,
                      study=study, population=args.population, log=log)
        frontiers[kind] = fr
        top = fr.points[-1].best
        table = law_gains(kind)
        base = replace(scenario, controller_type=kind)
        tuned[kind] = table.apply(base, top.gains) if top is not None else base
    layers = {k: outside_layer(sc, study) for k, sc in tuned.items()}
    count = encoder_count(scenario)
    report: dict[str, Any] = {"scenario": scenario.name, "count_rad": count, "budget": args.budget,
                              "seed": args.seed, "fractions": list(fractions),
                              "caps": caps.for_scenario(scenario).as_dict(),
                              "frontiers": {k: f.as_dict() for k, f in frontiers.items()},
                              "outside_layer": layers, "read_from": {k: v[1] for k, v in given.items()}}
    if args.out:
        from .plots_frontier import plot_frontier

        out = out_dir(args.out)
        plot_frontier(frontiers, count, path=out / "frontier.png",
                      title=f"{scenario.name}: each law tuned ({args.budget} evaluations, seed {args.seed}), worst of "
                            f"{len(study_of(scenario, study))} plants")
        (out / "tuned.json").write_text(strict_json(report, indent=2) + "\n")
    missing = [k for k, f in frontiers.items() if f.points[-1].best is None]
    code = EXIT_LOST if missing else EXIT_OK
    if args.json:
        print(strict_json(report, indent=2))
    else:
        _print(scenario.name, frontiers, layers, count, caps.for_scenario(scenario), len(study_of(scenario, study)))
    for kind in missing:
        print(f"flatstep: warning: {kind}: no candidate met the caps on every plant", file=sys.stderr)
    return code


def _print(name: str, frontiers: dict[str, Frontier], layers: dict[str, Any], count: Any, caps: Caps,
           plants: int) -> None:
    """The tuned laws at the full cap, then each law's frontier and the sliding laws' share outside the layer."""
    print(f"{name}: each law tuned, worst of {plants} plants")
    print(caps_line(caps))
    width = name_width(frontiers, "law", 40)
    print(header(count, width))
    for kind, fr in frontiers.items():
        best = fr.points[-1].best
        if best is None:
            print(f"{kind:<{width}}{'no candidate met the caps':>40}")
            continue
        print(row(kind, best, count, f"  {fr.wall_time:.1f} s" if fr.results else "  (read)", width))
        print("  " + ", ".join(f"{k} = {v:.5g}" for k, v in best.gains.items()))
    if any(len(f.points) > 1 for f in frontiers.values()):
        unit = "counts" if count else "rad"
        print(f"\nfrontier: worst-of-plants max error during the move [{unit}] (copper [mJ]) under each peak-voltage "
              "cap")
        caps_v = [p.cap for p in next(iter(frontiers.values())).points]
        width = name_width(frontiers, "law", 30)
        print(f"{'law':<{width}}" + "".join(f"{f'<= {c:.3g} V':>22}" for c in caps_v))
        for kind, fr in frontiers.items():
            cells = []
            for p in fr.points:
                if p.best is None:
                    cells.append(f"{'none':>22}")
                else:
                    e = p.best.move_max / count if count else p.best.move_max
                    cells.append(f"{f'{e:.3f} ({p.best.copper * 1e3:.4g})':>22}")
            print(f"{kind:<{width}}" + "".join(cells))
    for kind, share in layers.items():
        if share is not None:
            print(f"{kind}: |s| outside its boundary layer at {share['either']:.1%} of the control instants from t0 "
                  f"on (s1 {share['s1']:.1%}, s2 {share['s2']:.1%}; max |s1|/eps1 {share['max_s1_over_eps1']:.3g}, "
                  f"|s2|/eps2 {share['max_s2_over_eps2']:.3g})")


def _held_out(scenario: Scenario, study: Optional[Robustness], laws: dict[str, dict[str, float]],
              as_json: bool) -> int:
    """``--held-out``: each law's read gains and the default at its rule gains on the held-out runs (printed)."""
    default = default_type(sampled=True, torques=scenario.torques is not None)
    every: dict[str, Optional[dict[str, float]]] = {**laws}
    label = {k: k for k in laws}
    if default not in every:
        every[default] = None
        label[default] = f"{default} (rule gains)"
    results = held_out(scenario, study, every)
    runs = [r.label for r in held_out_runs(scenario, study)]
    count = encoder_count(scenario)
    means = {k: held_out_mean(evs) for k, evs in results.items()}
    if as_json:
        print(strict_json({"scenario": scenario.name, "count_rad": count, "runs": runs,
                           "laws": {k: {"evaluations": [e.as_dict() for e in evs],
                                        "held_out_mean": means[k]} for k, evs in results.items()}}, indent=2))
        return EXIT_OK if all(math.isfinite(m) for m in means.values()) else EXIT_LOST
    unit = count or 1.0
    print(f"{scenario.name}: the read gains re-run on the held-out runs (flatstep.studies.held_out), worst of the "
          f"plants: max error during the move [{'counts' if count else 'rad'}] (peak |v| [V])")
    width = name_width(label.values(), "law", 30)
    print(f"{'law':<{width}}" + "".join(f"{r:>19}" for r in runs) + f"{'held-out mean':>15}")
    for kind, evs in results.items():
        cells = "".join(f"{_cell(e, unit):>19}" for e in evs)
        mean = means[kind]
        print(f"{label[kind]:<{width}}{cells}{(f'{mean / unit:.3f}' if math.isfinite(mean) else 'failed'):>15}")
    ranked = [k for k in laws if math.isfinite(means[k])]
    if ranked and math.isfinite(means[default]):
        first = min(laws, key=lambda k: results[k][0].move_max)
        best = min(ranked, key=lambda k: means[k])
        tuned = results[default][0].move_max / results[first][0].move_max
        print(f"as tuned, the best law is {first}: default / best {tuned:.2f}; held out, {best}: default / best "
              f"{means[default] / means[best]:.2f}")
    return EXIT_OK if all(math.isfinite(m) for m in means.values()) else EXIT_LOST


def _cell(ev: Evaluation, unit: float) -> str:
    """One run's worst-of-plants error and peak voltage, or what went wrong."""
    if not ev.ok:
        return f"{ev.bad_plants} lost"
    text = f"{ev.move_max / unit:.3f} ({ev.peak_voltage:.3g})"
    return text if ev.settling is not None else text + "u"
