"""Command line: ``flatstep tune``, each law's gains searched under the same caps and budget."""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Optional, Sequence

from ..control.spec import ControllerSpec
from ..json_out import strict_json
from ..studies.robustness import encoder_count
from ..studies.scenario import Scenario
from ..studies.scenario_file import ScenarioFile, read_scenario_file
from ..studies.tune import BUDGET, POPULATION, Caps, Evaluation, TuneResult, check_budget, study_of, tune
from ..studies.tune_file import TUNED_MARK, tuned_toml
from ..studies.tune_laws import law_gains
from ..validate import InputError
from ..validate.limits import check_study, estimate
from ..validate.paths import check_output
from .columns import name_width
from .flags import add_force, count, quantity
from .plan import scenario_on_drive
from .status import EXIT_LOST, EXIT_OK


class Log:
    """Progress lines on stderr, each with the time since the start (off with ``--quiet``)."""

    def __init__(self, enabled: bool, what: str = "tune") -> None:
        self.enabled, self.what, self.start = enabled, what, time.perf_counter()

    def __call__(self, line: str) -> None:
        """Print ``line`` with the time since the start."""
        if self.enabled:
            print(f"[{self.what} {time.perf_counter() - self.start:6.1f} s] {line}", file=sys.stderr, flush=True)


def laws_of(given: Optional[Sequence[str]], scenario: Scenario, flag: str = "--law") -> list[str]:
    """The controller types of ``--law`` (repeated or comma-separated), default the scenario's; each tunable."""
    names = [n.strip() for g in given for n in g.split(",")] if given else [scenario.controller_type]
    kinds = []
    for name in names:
        kind = ControllerSpec.parse(name, flag).name()
        law_gains(kind, flag)
        if kind in kinds:
            raise InputError(flag, name, f"{flag} {name}: given twice; name each law once")
        try:
            replace(scenario, controller_type=kind).controller()  # before any work: a type the file cannot build
        except ValueError as exc:
            raise InputError(flag, name, f"{flag} {name}: {exc}") from None
        kinds.append(kind)
    return kinds


def caps_of(args: argparse.Namespace) -> Caps:
    """The caps of ``--peak-voltage``, ``--copper`` and ``--settling`` (none given: the defaults of Caps)."""
    return Caps(peak_voltage=args.peak_voltage, copper=args.copper, settling=args.settling)


def out_files(out: Optional[str], kinds: Sequence[str], inputs: Sequence[str], force: bool) -> dict[str, Path]:
    """Where each law's tuned file goes: ``out`` for one law (a .toml), ``out/KIND.toml`` for several; checked."""
    if out is None:
        return {}
    path = Path(out)
    if path.suffix == ".toml":
        if len(kinds) > 1:
            raise InputError("--out", out, f"--out {out}: one file holds one law's table, and {len(kinds)} laws are "
                             f"tuned ({', '.join(kinds)}): give a directory (one KIND.toml each) or one --law")
        return {kinds[0]: check_output(path, "--out", inputs=inputs, force=force, marks=(TUNED_MARK,))}
    if path.exists() and not path.is_dir():
        raise InputError("--out", out, f"--out {out}: exists and is not a directory; give a .toml file (one --law) "
                         "or a directory")
    files = {}
    for kind in kinds:
        target = path / f"{kind.replace('+', '_')}.toml"
        files[kind] = check_output(target, "--out", inputs=inputs, force=force, marks=(TUNED_MARK,)) \
            if path.is_dir() else target
    return files


def check_work(scenario: Scenario, sf: ScenarioFile, budget: int) -> None:
    """Refuse a search whose runs exceed the study limit (:func:`flatstep.validate.limits.check_study`).

    One search (one law under one set of caps) is the unit: each law and each cap of a frontier is one more.
    """
    loop = scenario.loop
    if loop is None:
        raise InputError("scenario", str(sf.path), f"{sf.path} has no [drive] control_rate: the tuner runs the "
                         "sampled drive loop on the C engine")
    plants = len(study_of(scenario, sf.robustness))
    try:
        check_study(budget * plants, estimate(scenario.t_end, control_period=loop.control_period,
                                              substeps=loop.substeps),
                    what=f"one search ({budget} evaluations of {plants} plants)")
    except InputError as exc:
        raise InputError("--budget", budget, f"--budget {budget}: {exc}; or lower --budget") from None


def row(label: str, ev: Evaluation, count: Optional[float], extra: str = "", width: int = 40) -> str:
    """One line of the table: worst move error, peak voltage, copper, settling, plants not ok (label ``width`` wide)."""
    move = f"{ev.move_max / count:11.3f}" if count else f"{ev.move_max:11.3e}"
    settling = f"{ev.settling * 1e3:11.3g}" if ev.settling is not None else f"{'unsettled':>11}"
    return (f"{label:<{width}}{move}{ev.peak_voltage:11.3g}{ev.copper * 1e3:11.4g}{settling}"
            f"{ev.bad_plants:>7}/{ev.plants:<3}{extra}").rstrip()


def header(count: Optional[float], width: int = 40) -> str:
    """The table's header (its first column ``width`` wide, as :func:`row`'s)."""
    unit = "counts" if count else "rad"
    return (f"{'law':<{width}}{'worst move':>11}{'peak |v|':>11}{'copper':>11}{'settling':>11}{'not ok':>11}"
            f"   [{unit}, V, mJ, ms]")


def caps_line(caps: Caps) -> str:
    """The caps in words."""
    return (f"caps: peak voltage {caps.peak_voltage:.3g} V, copper "
            + (f"{caps.copper * 1e3:.4g} mJ" if caps.copper is not None else "none")
            + (f", settled within {caps.settling * 1e3:.3g} ms of the move's end" if caps.settling is not None else ""))


def cmd_tune(args: argparse.Namespace) -> int:
    """``flatstep tune``: each law's gains tuned on the scenario's plants; the tuned [controller] tables."""
    sf = read_scenario_file(args.scenario)  # the laws are checked against it before the outputs
    kinds = laws_of(args.law, sf.scenario)
    files = out_files(args.out, kinds, [args.scenario], args.force)
    budget, population = check_budget(args.budget, args.population, "--budget")
    caps = caps_of(args)
    scenario = scenario_on_drive(sf, skip=args.no_verify)
    check_work(scenario, sf, budget)
    log = Log(enabled=not args.quiet)
    results: dict[str, TuneResult] = {}
    for kind in kinds:
        results[kind] = tune(scenario, kind, budget=budget, seed=args.seed, caps=caps, study=sf.robustness,
                             population=population, log=log)
    text = Path(args.scenario).read_text()
    written = []
    for kind, res in results.items():
        if kind in files and res.feasible:
            note = (f"{kind} tuned on {sf.name}, {res.best.plants} plants, budget {budget}, seed {args.seed}; "
                    f"worst move error {res.best.move_max:.6g} rad, peak {res.best.peak_voltage:.4g} V")
            files[kind].parent.mkdir(parents=True, exist_ok=True)
            files[kind].write_text(tuned_toml(text, kind, res.gains, note))
            written.append(str(files[kind]))
    code = EXIT_OK if all(r.feasible for r in results.values()) else EXIT_LOST
    if args.json:
        print(strict_json({"scenario": scenario.name, "results": {k: r.as_dict() for k, r in results.items()},
                           "written": written}, indent=2))
    else:
        report(scenario, results, budget, args.seed)
        for path in written:
            print(f"wrote {path}")
    for kind, res in results.items():
        if not res.feasible:
            print(f"flatstep: warning: {kind}: no candidate of {len(res.evaluations)} met the caps on every plant "
                  f"({res.best.bad_plants} plants lost, faulted or failed at the best); no table written",
                  file=sys.stderr)
    return code


def report(scenario: Scenario, results: dict[str, TuneResult], budget: int, seed: int) -> None:
    """Print the scenario's gains and the tuned ones per law, with their wall time."""
    count = encoder_count(scenario)
    first = next(iter(results.values()))
    print(f"{scenario.name}: {first.best.plants} plants, {budget} evaluations per law, seed {seed}")
    print(caps_line(first.caps))
    width = name_width((f"{kind} (scenario's gains)" for kind in results), "law", 40)
    print(header(count, width))
    for kind, res in results.items():
        print(row(f"{kind} (scenario's gains)", res.start, count, width=width))
        print(row(f"{kind} tuned", res.best, count, f"  {res.wall_time:.1f} s", width))
        print("  " + ", ".join(f"{k} = {v:.5g}" for k, v in res.gains.items()))


def add_tune_flags(parser: argparse.ArgumentParser) -> None:
    """The tuner's flags, shared by ``flatstep tune`` and ``flatstep compare --tuned``."""
    parser.add_argument("--budget", type=int, default=BUDGET,
                        help=f"evaluations per law, each on every plant (default {BUDGET}; the same for every law)")
    parser.add_argument("--seed", type=count("seed", "--seed"), default=0, help="the search's seed (default 0)")
    parser.add_argument("--population", type=int, default=POPULATION,
                        help=f"candidates per generation (default {POPULATION}, at least 5)")
    parser.add_argument("--peak-voltage", type=quantity("v_bus", "--peak-voltage"), default=None,
                        help="cap on the worst-of-plants peak phase voltage [V] (default: the drive's bus)")
    parser.add_argument("--copper", type=quantity("gain", "--copper"), default=None,
                        help="cap on the worst-of-plants copper loss from the move's start [J] (default: none)")
    parser.add_argument("--settling", type=quantity("t_end", "--settling"), default=None,
                        help="cap on the worst-of-plants settling time after the move into one encoder count [s] "
                        "(default: settled before the horizon's end)")


def add_tune_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep tune`` to the subcommands ``sub``."""
    p = sub.add_parser("tune", help="tune a law's gains on the scenario's plants under caps",
                       description="Search each law's gains (SciPy's differential evolution, seeded, the same "
                       "budget of evaluations for every law) for the least worst-of-plants max error during the move "
                       "over the file's [robustness] plants (default the +-10 % corners of R, L, Km, J, B), under "
                       "caps on peak voltage, copper loss and settling (penalties in the search; the answer meets "
                       "them on every plant). Prints the scenario's gains and the tuned ones; --out writes the "
                       "scenario with the tuned [controller] table. Exit 3 if no candidate of a law met the caps.")
    p.add_argument("scenario", help="a scenario file (TOML) with a [drive]")
    p.add_argument("--law", action="append", default=None,
                   help="a controller type or law+option+... to tune (repeat, or separate by commas; default: the "
                   "file's [controller])")
    add_tune_flags(p)
    p.add_argument("--out", default=None, help="write the scenario with the tuned [controller] table: a .toml file "
                   "for one law, or a directory (one KIND.toml per law)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--no-verify", action="store_true", help="run a plan made against [limits] as the file gives it, "
                   "without the check on the drive 'flatstep plan' runs")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    add_force(p)
    p.set_defaults(func=cmd_tune)
