"""Command line: ``flatstep robustness``, a scenario under plant parameter errors."""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from typing import Any

from ..json_out import strict_json
from ..studies.robustness import REST_AFTER, encoder_count, plant_errors, run_study
from ..studies.scenario_file import Robustness, read_scenario_file
from ..validate.limits import check_study, estimate
from ..validate.paths import PNG_MARK, check_output_dir, json_marks
from .flags import add_force, count, out_dir
from .plan import scenario_on_drive
from .status import EXIT_STOPPED, exit_code

#: The files ``flatstep robustness --out`` writes, and the first bytes that make an existing one flatstep's.
ROBUSTNESS_FILES = {"robustness.png": PNG_MARK, "robustness.json": json_marks("scenario")}


def cmd_robustness(args: argparse.Namespace) -> int:
    """``flatstep robustness``: the scenario on every plant of its study, worst errors per gain set."""
    if args.out:  # before any work
        check_output_dir(args.out, "--out", ROBUSTNESS_FILES, inputs=[args.scenario], force=args.force)
    sf = read_scenario_file(args.scenario)
    scenario, study = scenario_on_drive(sf, skip=args.no_verify), sf.robustness
    study = study or Robustness()
    if args.samples is not None:
        study = replace(study, samples=args.samples)
    if scenario.loop is not None:
        loop = scenario.loop
        check_study(len(plant_errors(study)) * (1 if args.no_paper_gains else 2),
                    estimate(scenario.t_end, control_period=loop.control_period, substeps=loop.substeps),
                    what=f"the robustness study of {len(plant_errors(study))} plants")
    result = run_study(scenario, study, with_paper_gains=not args.no_paper_gains, progress=args.progress)
    count = encoder_count(scenario)
    sets = {label: {k: v for k, v in s.items() if k != "rows"} for label, s in result["sets"].items()}
    report: dict[str, Any] = {"scenario": scenario.name, "relative_error": study.relative_error,
                              "parameters": list(study.parameters), "runs_per_set": len(result["errors"]),
                              "rest_starts_after_tf_s": REST_AFTER, "sets": sets}
    if args.out:
        from .plots import plot_robustness

        out = out_dir(args.out)
        plot_robustness(result, count, scenario.plan, title=f"{scenario.name}: plant parameters off by "
                        f"+-{study.relative_error:.0%} ({len(result['errors'])} plants)", path=out / "robustness.png")
        (out / "robustness.json").write_text(strict_json(report, indent=2) + "\n")
    own = report["sets"]["scenario"]
    code = exit_code(["lost"] * own["statuses"]["lost"] + ["fault"] * own["statuses"]["fault"])
    if own["failed"]:  # a plant whose run stopped before its end (non-finite state, ...): no result to trust
        code = EXIT_STOPPED
    if args.json:
        print(strict_json(report, indent=2))
        return code
    unit = "counts" if count else "rad"
    print(f"{scenario.name}: {len(result['errors'])} plants, parameters off by +-{study.relative_error:.0%}")
    print(f"{'gains':<14}{'runs ok':>9}{'lost':>6}{'fault':>6}{'worst move':>14}{'worst rest':>14}{'final':>12}"
          f"{'peak |v|':>11}  [{unit}, V]")
    for label, s in report["sets"].items():
        w, wv, st = s.get("worst_counts", s["worst_rad"]), s["worst_rad"], s["statuses"]
        print(f"{label:<14}{st['ok']:>5}/{s['runs']:<3}{st['lost']:>6}{st['fault']:>6}"
              f"{w.get('move', float('nan')):>14.3f}{w.get('rest', float('nan')):>14.3f}"
              f"{w.get('final', float('nan')):>12.3f}{wv.get('peak_voltage', float('nan')):>11.3g}")
    if own["failed"] or code:
        print(f"flatstep: warning: the scenario's gains: {own['statuses']['lost']} of {own['runs']} plants lost the "
              f"move, {own['statuses']['fault']} faulted, {own['failed']} failed", file=sys.stderr)
    return code


def add_robustness_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep robustness`` to the subcommands ``sub``."""
    rob = sub.add_parser("robustness", help="a scenario under plant parameter errors ([robustness] of the file)",
                         description="Run a scenario on plants whose parameters are off (every sign combination "
                         "of the file's [robustness] relative_error on its parameters, default +-10 % on R, L, Km, "
                         "J, B), the controller keeping the nominal model; with its own gains and the paper's. "
                         "Prints each gain set's runs ok, lost and faulted, and its worst errors (encoder counts, or "
                         "rad without an encoder) and peak voltage [V].")
    rob.add_argument("scenario", help="a scenario file (TOML)")
    rob.add_argument("--samples", type=count("samples", "--samples"), default=None,
                     help="random plants instead of all sign combinations")
    rob.add_argument("--no-paper-gains", action="store_true", help="skip the paper's gains on the same drive")
    rob.add_argument("--progress", action="store_true", default=None, help="draw a progress bar")
    rob.add_argument("--no-verify", action="store_true", help="run a plan made against [limits] as the file gives "
                     "it, without the check on the drive 'flatstep plan' runs (by default the plan plan reports "
                     "feasible: backed off if the drive would lose it, refused if no back-off keeps it)")
    rob.add_argument("--out", default=None, help="write robustness.png and robustness.json here")
    rob.add_argument("--json", action="store_true", help="print the report as JSON")
    add_force(rob)
    rob.set_defaults(func=cmd_robustness)
