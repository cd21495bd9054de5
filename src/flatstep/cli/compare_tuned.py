"""Command line: ``flatstep compare --tuned``, the tuned laws side by side and their frontiers."""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from typing import Any

from ..control.spec import LAWS, ControllerSpec
from ..json_out import strict_json
from ..studies.frontier import Frontier, FrontierPoint, check_fractions, frontier, outside_layer
from ..studies.robustness import encoder_count
from ..studies.scenario_file import read_scenario_file
from ..studies.tune import Caps, evaluate, study_of
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


def cmd_compare_tuned(args: argparse.Namespace) -> int:
    """``flatstep compare --tuned [PATH]``: each law tuned (or read from PATH), its frontier, its layer share."""
    _refuse_other_flags(args)
    if args.out:  # before any work
        check_output_dir(args.out, "--out", TUNED_FILES, inputs=[args.scenario], force=args.force)
    sf = read_scenario_file(args.scenario)
    names = [k.strip() for k in args.controllers.split(",")] if args.controllers else list(LAWS)
    kinds = laws_of(names, sf.scenario, "--controllers")
    given = read_tuned(args.tuned) if args.tuned else {}
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
    log = Log(enabled=not args.quiet, what="compare --tuned")
    frontiers: dict[str, Frontier] = {}
    tuned = {}
    for kind in kinds:
        if kind in given:  # the file's gains, evaluated on these plants under these caps
            table = law_gains(kind)
            sc = table.apply(replace(scenario, controller_type=kind), table.read(given[kind].scenario))
            full = caps.for_scenario(sc)
            ev = evaluate([sc], study_of(sc, study), [table.read(sc)])[0]
            ok = ev.ok and full.excess(ev) == 0.0
            frontiers[kind] = Frontier(kind, [FrontierPoint(full.peak_voltage or 0.0, ev if ok else None)], [])
            tuned[kind] = sc
            log(f"{kind}: read from {given[kind].path}, evaluated on {ev.plants} plants")
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
                              "outside_layer": layers, "read_from": {k: str(v.path) for k, v in given.items()}}
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
