"""Command line: ``flatstep plan FILE.toml``, a waypoint plan, its margins, plan.png and plan.json."""
from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from ..json_out import strict_json
from ..model.flat import flat_to_state
from ..plan.margins import plan_margins
from ..validate.paths import PNG_MARK, check_output_dir, json_marks
from .flags import add_force, out_dir
from .status import EXIT_OK, EXIT_REFUSED, exit_code, warn

if TYPE_CHECKING:  # the planners and Matplotlib load when the command runs, not with the command line
    from ..engine.result import SimResult
    from ..plan.sequence import Step
    from ..studies.scenario import Scenario
    from ..studies.scenario_file import ScenarioFile

#: The controller types that follow a scenario plan's rho* (the others plan their own currents or ignore it).
PLAN_RHO_TYPES = ("smc", "smc_ff", "smc_ff_hold")
MARGINS = ("voltage", "current", "torque_angle", "speed", "acceleration", "jerk")
#: The files ``flatstep plan --out`` writes, and the first bytes that make an existing one flatstep's.
PLAN_FILES = {"plan.png": PNG_MARK, "plan.json": json_marks("name")}


def _count(n: int, noun: str) -> str:
    """``n noun``, plural unless n is 1."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def plot_plan(pf: "ScenarioFile", path: Path, v_bus: Optional[float] = None) -> None:
    """plan.png: angle, speed, phase voltage demand against the bus, current magnitude against its limit.

    ``v_bus``: the bus to draw when the file has no [limits] (its drive's).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plan = pf.plan
    t = np.linspace(plan.t0, plan.tf, 4001)
    f = plan.flag(t)
    _, v = flat_to_state(f, pf.motor)
    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    ax[0].plot(t, f.theta)
    ax[0].set_ylabel(r"$\theta^*$ [rad]")
    ax[1].plot(t, f.dtheta)
    ax[1].set_ylabel(r"$\dot\theta^*$ [rad/s]")
    # the vector's magnitude: each phase voltage reaches it once per electrical turn
    ax[2].plot(t, np.hypot(v[0], v[1]), label=r"$|v|$ (phase peak)")
    ax[3].plot(t, f.rho, label=r"$\rho^* = |i|$")
    if pf.limits is not None:
        ax[2].axhline(pf.limits.v_bus, color="k", ls="--", lw=1, label="$V_{bus}$")
        ax[3].axhline(pf.limits.i_max, color="k", ls="--", lw=1, label="$i_{max}$")
    elif v_bus is not None:
        ax[2].axhline(v_bus, color="k", ls="--", lw=1, label="$V_{bus}$")
    ax[2].set_ylabel("voltage demand [V]")
    ax[3].set_ylabel("current [A]")
    ax[3].set_xlabel("t [s]")
    for a in ax[2:]:
        a.legend(loc="upper right", fontsize=8)
    for _, start, _ in pf.steps:
        for a in ax:
            a.axvline(start, color="0.8", lw=0.5, zorder=0)
    fig.suptitle(f"{pf.name}: {_count(len(pf.steps), 'step')}, {plan.tf - plan.t0:.4g} s")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _tracking(pf: "ScenarioFile", r: "SimResult") -> dict[str, Any]:
    """The tracking figures of a run of the plan (plan.json's ``tracking``)."""
    err = np.abs(r.theta - r.theta_ref)
    full_step = 2 * np.pi / (4 * pf.motor.Nr)
    return dict(control_rate=pf.control_rate, max_abs_theta_error=float(err.max()), full_step=full_step,
                lost_step=bool(err.max() >= full_step), final_error=float(r.theta[-1] - pf.plan.theta2),
                peak_phase_voltage=float(np.max(np.abs([r.va, r.vb]))), v_bus=pf.v_bus,
                controller_faults=int(r.meta.get("controller_faults", 0)), status=r.status, lost_at=r.lost_at)


def _margins_line(pf: "ScenarioFile") -> tuple[dict[str, float], list[str]]:
    """The plan's margins against its limits and the names of the limits it exceeds (none: feasible)."""
    assert pf.limits is not None
    m = plan_margins(pf.plan, pf.motor, pf.limits)
    return m, [k for k in MARGINS if m[k] > 1]


def _print_steps(pf: "ScenarioFile") -> None:
    """The plan's one-line summary and its moves and dwells."""
    plan = pf.plan
    print(f"{pf.name}: {_count(len(pf.steps), 'step')} in {_count(plan.n, 'segment')}, {plan.tf - plan.t0:.6g} s "
          f"(t = {plan.t0:g} .. {plan.tf:.6g} s)")
    _print_step_rows(pf.steps)


def _print_step_rows(steps: "list[Step]") -> None:
    """One line per move or dwell: its label, start and duration."""
    width = max([14] + [len(label) for label, _, _ in steps])
    for label, start, duration in steps:
        print(f"  {label:<{width}} start {start:10.6f} s  duration {duration:10.6f} s")


def check_plan_file(sf: "ScenarioFile", show_steps: bool = True) -> "ScenarioFile":
    """``sf``, refused if its plan exceeds its [limits] (nothing is run); a waypoint plan's steps printed first.

    ``show_steps``: print a waypoint plan's moves and dwells (the paper's move is one step).

    Raises
    ------
    ValueError
        The plan exceeds a limit of the file's [limits].
    """
    if show_steps and sf.planner != "rest_to_rest":
        _print_steps(sf)
    if sf.limits is not None:
        _, over = _margins_line(sf)
        if over:
            raise ValueError(f"{sf.path}: the plan exceeds its limits ({', '.join(over)}): nothing was run; "
                             "'flatstep plan' shows the margins")
    return sf


def _check_scenario(sf: "ScenarioFile") -> dict[str, Any]:
    """The paper's move checked against the law and the drive's bus (plan.json's ``scenario``).

    The check is :func:`~flatstep.plan.feasibility.check_feasibility` with the plant's constant load and the
    drive's bus (none without a [drive]); without [limits] there is no current limit.
    """
    from ..plan.feasibility import check_feasibility

    scenario = sf.scenario
    constant = scenario.plant.constant_load if scenario.plant is not None else 0.0
    load = constant if constant is not None else 0.0  # a time-varying load: the check without it
    check = check_feasibility(scenario.plan, scenario.motor, load_torque=load, v_max=sf.v_bus)
    return dict(controller=scenario.controller_type, load_torque=load, v_bus=sf.v_bus, check=check.as_dict())


def _cmd_plan_scenario(args: argparse.Namespace, pf: "ScenarioFile") -> int:
    """``flatstep plan FILE.toml`` on the paper's move without [limits]: its check against the law and the bus."""
    info = _check_scenario(pf)
    _print_steps(pf)
    check = info["check"]
    print(f"  the paper's law on this move (constant load {info['load_torque']:g} N m): torque demand at most "
          f"{check['torque_ratio']:.3f} of Km rho* (1 = the law's singularity)")
    if info["controller"] not in PLAN_RHO_TYPES:
        print(f"  (the scenario's controller {info['controller']} does not follow the plan's rho*: the currents and "
              "voltages below are the paper's law's)")
    if check["peak_voltage"] == check["peak_voltage"]:  # not NaN: the plan is regular
        bus = f" of the {info['v_bus']:g} V bus" if info["v_bus"] is not None else " (no [drive]: no bus)"
        print(f"  peaks: feedforward phase voltage {check['peak_voltage']:.4g} V{bus}, "
              f"phase current {check['peak_current']:.4g} A")
    if not check["feasible"]:
        print("  infeasible: " + "; ".join(check["violations"]))
    report: dict[str, Any] = dict(name=pf.name, total_duration=pf.plan.tf - pf.plan.t0, t0=pf.plan.t0,
                                  tf=pf.plan.tf, segments=pf.plan.n,
                                  steps=[dict(step=s, start=a, duration=d) for s, a, d in pf.steps],
                                  scenario=info, feasible=check["feasible"])
    if args.simulate and check["feasible"]:
        report["tracking"] = _simulated(pf)
    out = out_dir(args.out)
    (out / "plan.json").write_text(strict_json(report, indent=2) + "\n")
    if check["torque_margin"] > 0 and check["min_rho"] > 0:
        plot_plan(pf, out / "plan.png", v_bus=info["v_bus"])
        print(f"  wrote {out / 'plan.png'} and {out / 'plan.json'}")
    else:
        print(f"  wrote {out / 'plan.json'}; no plan.png: the flat maps are singular on this move")
    return _exit(pf, report)


def _exit(pf: "ScenarioFile", report: dict[str, Any]) -> int:
    """The exit code: refused (2) for an infeasible plan, else the run's status as 'flatstep simulate' gives it."""
    if not report.get("feasible", True):
        return EXIT_REFUSED
    if "tracking" not in report:
        return EXIT_OK
    warn(pf.name, report["tracking"])  # the run's status and exit code, as 'flatstep simulate FILE.toml' gives them
    return exit_code([report["tracking"]["status"]])


def _simulated(pf: "ScenarioFile") -> dict[str, Any]:
    """Run the file's scenario (its drive, sensors, observer, controller) and print and return its tracking."""
    tr = _tracking(pf, pf.scenario.run())
    drive = f"on the {tr['control_rate']:g} Hz drive" if tr["control_rate"] else "in continuous time"
    print(f"  {drive}: max |theta - theta*| {tr['max_abs_theta_error']:.3g} rad "
          f"(a full step is {tr['full_step']:.4g} rad), peak phase voltage {tr['peak_phase_voltage']:.4g} V, "
          f"final error {tr['final_error']:.3g} rad, status {tr['status']}")
    return tr


def cmd_plan(args: argparse.Namespace) -> int:
    """``flatstep plan FILE.toml``; with ``--json`` the text goes to stderr and plan.json to stdout."""
    if not getattr(args, "json", False):
        return _cmd_plan(args)
    with contextlib.redirect_stdout(sys.stderr):
        code = _cmd_plan(args)
    print((out_dir(args.out) / "plan.json").read_text(), end="")
    return code


def _cmd_plan(args: argparse.Namespace) -> int:
    """``flatstep plan FILE.toml``: plan the waypoints, print the steps and margins, write plan.png, plan.json."""
    from ..studies.scenario_file import read_scenario_file
    check_output_dir(args.out, "--out", PLAN_FILES, inputs=[args.file], force=args.force)  # before any work
    pf = read_scenario_file(args.file)
    if pf.limits is None and pf.planner == "rest_to_rest":
        return _cmd_plan_scenario(args, pf)
    plan = pf.plan
    _print_steps(pf)
    report: dict[str, Any] = dict(name=pf.name, total_duration=plan.tf - plan.t0, t0=plan.t0, tf=plan.tf,
                                  segments=plan.n,
                                  steps=[dict(step=s, start=a, duration=d) for s, a, d in pf.steps])
    if pf.limits is not None:
        m, over = _margins_line(pf)
        report["limits"], report["margins"] = pf.limits.as_dict(), m
        print("  worst use of each limit (1 = at the limit): " +
              ", ".join(f"{k} {m[k]:.3f}" for k in MARGINS if m[k] > 0))
        print(f"  peaks: voltage demand |v| {m['v_peak']:.4g} V of {pf.limits.v_bus:g} V, "
              f"current {m['rho_peak']:.4g} A of {pf.limits.i_max:g} A, speed {m['speed_peak']:.4g} rad/s")
        report["feasible"] = not over
        if over:
            print(f"  infeasible: the plan exceeds {', '.join(over)} (not simulated)")
        else:
            pf = verify_on_drive(pf, report, skip=args.no_verify)
    if args.simulate and report.get("feasible", True):
        report["tracking"] = _simulated(pf)
    out = out_dir(args.out)
    plot_plan(pf, out / "plan.png", v_bus=pf.v_bus)
    (out / "plan.json").write_text(strict_json(report, indent=2) + "\n")
    print(f"  wrote {out / 'plan.png'} and {out / 'plan.json'}")
    return _exit(pf, report)


def verify_on_drive(pf: "ScenarioFile", report: dict[str, Any], skip: bool = False) -> "ScenarioFile":
    """``flatstep plan``'s check: fill plan.json's ``duration`` and ``verify``, print one line, return the plan file.

    The check runs the file's scenario as ``flatstep simulate`` runs it (its controller, drive, sensors, observer,
    plant and load) on its plant and the corners of ``[limits] uncertainty``. A plan within its limits that the
    drive does not keep on every case is refused (``report["feasible"]`` set to false) with what binds and what to
    change; a time-optimal sequence is backed off first
    (:func:`~flatstep.studies.backoff.check_on_drive`). ``skip`` (``--no-verify``) says so and leaves the plan
    unverified.
    """
    from ..studies.backoff import check_on_drive

    if skip:
        report.update(duration=pf.plan.tf - pf.plan.t0, verify=dict(skipped=True))
        print("  not verified on the drive (--no-verify)")
        return pf
    planner = pf.planner
    before = pf.plan.tf - pf.plan.t0
    pf, info = check_on_drive(pf, str(planner))
    report.update(duration=pf.plan.tf - pf.plan.t0, verify=info, feasible=bool(info["verified"]),
                  total_duration=pf.plan.tf - pf.plan.t0, tf=pf.plan.tf, segments=pf.plan.n,
                  steps=[dict(step=s, start=a, duration=d) for s, a, d in pf.steps])
    cases = info["cases"]
    bad = [c for c in cases if c["status"] != "ok"]
    where = f"{info['controller']} on {info['plants']}, {info['seconds']:.2f} s"
    if info["verified"]:
        slower = (f"; backed off from {before:.6g} s to {pf.plan.tf - pf.plan.t0:.6g} s"
                  if info["backed_off"] else "")
        print(f"  verified on the drive: {where}, every run ok, worst |theta - theta*| "
              f"{info['worst_error']:.3g} rad{slower}")
        if info["backed_off"]:
            lim = info["limits"]
            print("  the verified plan, within " + ", ".join(f"{k} = {lim[k]:.4g}" for k in
                                                            ("torque_angle_max", "v_use", "speed_max") if lim[k]))
            _print_step_rows(pf.steps)
    else:
        tried = f" after {len(info['rounds'])} plans" if info["rounds"] else ""
        print(f"  not verified on the drive: {where}; {len(bad)} ended {', '.join(sorted({c['status'] for c in bad}))} "
              f"(worst |theta - theta*| {info['worst_error']:.3g} rad){tried}; "
              f"{info['binds']} binds: {info['advice']}")
        if "suggested_limits" in info:
            lim = info["suggested_limits"]
            print("  limits derived for this drive (MotorLimits.for_drive): " +
                  ", ".join(f"{k} = {lim[k]:.4g}" for k in ("i_hold", "speed_corner", "torque_angle_max", "v_use",
                                                           "speed_max")))
    return pf


def scenario_on_drive(sf: "ScenarioFile", skip: bool = False) -> "Scenario":
    """The file's scenario with the plan ``flatstep plan`` reports feasible: checked on the drive, backed off.

    A plan made against ``[limits]`` runs only once the check of :func:`~flatstep.studies.backoff.check_on_drive`
    keeps it, with the file's own controller, on its plant and the corners of ``[limits] uncertainty`` (a time-optimal
    plan backed off as ``flatstep plan`` backs it off);
    a plan the drive would lose is refused with what binds. ``skip`` (``--no-verify``) runs the file's plan as it is.
    """
    from ..studies.backoff import check_on_drive

    if skip or sf.limits is None:
        return sf.scenario
    checked, info = check_on_drive(sf, sf.planner)
    if not info["verified"]:
        raise ValueError(f"{sf.path}: the plan is not kept on the drive ({info['controller']} on {info['plants']}; "
                         f"worst |theta - theta*| {info['worst_error']:.3g} rad): "
                         f"{info['binds']} binds: {info['advice']}; 'flatstep plan' shows the check, --no-verify "
                         "runs the plan anyway")
    if info["backed_off"]:
        print(f"flatstep: {sf.name}: the plan within [limits] is not kept on every plant; running the backed-off "
              f"plan ({checked.plan.tf - checked.plan.t0:.6g} s instead of "
              f"{sf.plan.tf - sf.plan.t0:.6g} s), as 'flatstep plan' reports it", file=sys.stderr)
    return checked.scenario


def add_plan_command(sub: Any) -> None:
    """Register ``flatstep plan`` on the subcommand parser ``sub``."""
    p = sub.add_parser("plan", help="plan a scenario file's move or waypoint sequence under its limits "
                       "(docs/planning.md)",
                       description="Plan a scenario file's [plan] (the paper's move, the fastest moves its motor's "
                       "[limits] allow, or a segment family): print each move's and dwell's start and duration and "
                       "the worst use of each limit, write plan.png and plan.json; with --simulate, also run the "
                       "file's scenario on its drive ('flatstep simulate FILE.toml' runs it alone and prints the "
                       "run's summary and status). Exit 2 when the plan exceeds a limit, a path is refused, or the "
                       "drive does not keep it with the file's controller on its plant and the corners of +-[limits] "
                       "uncertainty (10 % by default) on R, L, Km, J (the check; --no-verify skips it), 3 "
                       "when the --simulate run loses the move, 4 when its controller faulted (as 'flatstep simulate "
                       "FILE.toml').")
    p.add_argument("file", help="a scenario file (TOML, docs/scenario-reference.md; examples/plans/*.toml): a "
                   "waypoint plan against its [limits], or the paper's move checked against the law's singularity "
                   "and the drive's bus")
    p.add_argument("--out", default=".", help="where plan.png and plan.json go (default: .)")
    p.add_argument("--simulate", action="store_true",
                   help="also run the file's scenario (its drive, sensors, observer and controller)")
    p.add_argument("--no-verify", action="store_true",
                   help="skip the check on the drive (the file's scenario on its plant and the +-[limits] uncertainty "
                        "corners; docs/planning.md)")
    p.add_argument("--json", action="store_true", help="print plan.json to stdout (the text goes to stderr)")
    add_force(p)
    p.set_defaults(func=cmd_plan)
