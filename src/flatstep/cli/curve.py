"""Command line: ``flatstep curve``, the pull-out torque against speed of a scenario's motor on its drive."""
from __future__ import annotations

import argparse
import math
from typing import Any, Optional

import numpy as np

from ..json_out import strict_json
from ..model.datasheet import motor_from_table, uses_datasheet
from ..model.pullout import (
    DRIVE_KINDS,
    SQUARE_VECTOR,
    convention_band,
    corner_speed,
    electrical_speed_limit,
    pullout_torque,
    top_speed,
)
from ..studies.file_values import read_toml
from ..studies.scenario_file import read_scenario_file
from ..validate import InputError
from ..validate.paths import PNG_MARK, check_output
from .flags import add_force, count, quantity

RPM = 60.0 / (2.0 * math.pi)


def _bus(args: argparse.Namespace, file_bus: Optional[float]) -> float:
    """The bus [V]: ``--v-bus``, else the file's ``[drive] v_bus``; refused if neither gives one."""
    if args.v_bus is not None:
        return float(args.v_bus)
    if file_bus is None:
        raise InputError("--v-bus", None, f"{args.scenario}: the file has no [drive] v_bus: give the bus with --v-bus "
                         "(the curve depends on it)")
    return file_bus


def _rho(args: argparse.Namespace, plan_rho: float, doc: dict[str, Any]) -> float:
    """The current-vector norm the driver holds [A].

    ``--current`` read as ``--setting``; else the file's plan's run current; else, for a motor given by its datasheet,
    the rated current-vector norm; else the default plan's.
    """
    if args.current is not None:
        return float(args.current) * (math.sqrt(2.0) if args.setting == "rms" else 1.0)
    table = doc.get("motor", {})
    if "plan" not in doc and uses_datasheet(table):
        return motor_from_table(table, str(args.scenario)).rated_rho
    return plan_rho


def curve_report(args: argparse.Namespace) -> dict[str, Any]:
    """The curve of ``flatstep curve``: speeds, torques per drive kind, the band, the landmarks."""
    sf = read_scenario_file(args.scenario)
    doc = read_toml(sf.path)
    motor, v_bus = sf.motor, _bus(args, sf.v_bus)
    rho = _rho(args, sf.scenario.plan.rho1, doc)
    kinds = DRIVE_KINDS if args.drive == "all" else (args.drive,)
    w_top = args.w_max if args.w_max is not None else 1.5 * top_speed(motor, "foc_weakening", v_bus, rho, 0.0)
    speeds = np.linspace(0.0, w_top, args.points)
    report: dict[str, Any] = {
        "scenario": str(args.scenario), "motor": motor.as_dict(), "v_bus": v_bus, "current": rho,
        "speeds_rad_s": speeds.tolist(), "speeds_rpm": (speeds * RPM).tolist(),
        "torque": {k: pullout_torque(motor, k, v_bus, rho, speeds).tolist() for k in kinds},
        "corner_speed": corner_speed(motor, v_bus, rho),
        "top_speed": {k: top_speed(motor, k, v_bus, rho, args.load) for k in kinds}, "load": args.load,
    }
    if sf.control_rate is not None:
        report["electrical_speed_limit"] = electrical_speed_limit(motor, sf.control_rate)
    table = doc.get("motor", {})
    if args.current is not None and uses_datasheet(table):
        model = motor_from_table(table, str(sf.path))
        report["band"] = {k: [b.tolist() for b in convention_band(model, k, v_bus, args.current, speeds)]
                          for k in kinds}
    if args.engine:
        from ..studies.pullout import engine_pullout

        check = np.linspace(0.0, w_top, args.engine + 2)[1:-1]
        rate = sf.control_rate or 20e3
        report["engine"] = {"speeds_rad_s": check.tolist(), "control_rate": rate,
                            "torque": engine_pullout(motor, v_bus, rho, check, control_rate=rate,
                                                     progress=False).tolist(),
                            "model_chopper": pullout_torque(motor, "chopper", v_bus, rho, check).tolist(),
                            "model_chopper_drive_square": pullout_torque(motor, "chopper", v_bus, rho, check,
                                                                         voltage_factor=SQUARE_VECTOR).tolist()}
    return report


def _print(report: dict[str, Any]) -> None:
    """The report as text: landmarks, then the curve every few points."""
    print(f"{report['scenario']}: v_bus {report['v_bus']:g} V, current-vector norm {report['current']:.4g} A")
    print(f"corner speed {report['corner_speed']:.4g} rad/s ({report['corner_speed'] * RPM:.4g} rpm)")
    for kind, w in report["top_speed"].items():
        print(f"top speed at {report['load']:g} N m, {kind}: {w:.4g} rad/s ({w * RPM:.4g} rpm)")
    if "electrical_speed_limit" in report:
        w = report["electrical_speed_limit"]
        print(f"electrical-frequency limit (0.1 of the control rate): {w:.4g} rad/s ({w * RPM:.4g} rpm)")
    kinds = list(report["torque"])
    print(f"{'rad/s':>9}{'rpm':>9}" + "".join(f"{k:>15}" for k in kinds) + "   [N m]")
    step = max(1, len(report["speeds_rad_s"]) // 20)
    for j in range(0, len(report["speeds_rad_s"]), step):
        w = report["speeds_rad_s"][j]
        print(f"{w:>9.4g}{w * RPM:>9.4g}" + "".join(f"{report['torque'][k][j]:>15.4g}" for k in kinds))
    if "engine" in report:
        e = report["engine"]
        print(f"C engine, open-loop microstepping at {e['control_rate']:g} Hz (largest load kept) against the model:")
        print(f"{'rad/s':>9}{'engine':>10}{'chopper':>10}{'x1.12 V':>10}   [N m]")
        for w, t, a, b in zip(e["speeds_rad_s"], e["torque"], e["model_chopper"], e["model_chopper_drive_square"],
                              strict=True):
            print(f"{w:>9.4g}{t:>10.4g}{a:>10.4g}{b:>10.4g}")


def _to_rpm(w: Any) -> Any:
    """rad/s to rpm (the figure's top axis)."""
    return np.asarray(w, dtype=float) * RPM


def _to_rad_s(n: Any) -> Any:
    """Rpm to rad/s."""
    return np.asarray(n, dtype=float) / RPM


#: The figure's legend for each drive kind, in the words of docs/curves.md.
DRIVE_LABELS = {"chopper": "open-loop chopper (step/dir driver)", "foc": "field-oriented, i_d = 0",
                "foc_weakening": "field-oriented, field weakening"}


def _plot(report: dict[str, Any]) -> Any:
    """The figure (a matplotlib ``Figure``): the curve against rad/s, with rpm on the top axis, the band shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    w = np.array(report["speeds_rad_s"])
    fig, ax = plt.subplots(figsize=(7, 4.2))
    widths = {"chopper": (3.0, "-"), "foc": (1.2, "--"), "foc_weakening": (1.5, "-")}
    for kind, t in report["torque"].items():
        line = ax.plot(w, t, label=DRIVE_LABELS[kind], lw=widths[kind][0], ls=widths[kind][1])[0]
        if "band" in report:
            lo, hi = report["band"][kind]
            ax.fill_between(w, lo, hi, color=line.get_color(), alpha=0.15)
    if "engine" in report:
        ax.plot(report["engine"]["speeds_rad_s"], report["engine"]["torque"], "ko", label="C engine (open loop)")
    ax.axvline(report["corner_speed"], color="grey", ls=":", label="corner speed")
    if "electrical_speed_limit" in report:
        ax.axvline(report["electrical_speed_limit"], color="grey", ls="--", label="electrical-frequency limit")
    ax.set_xlim(0, w[-1])
    ax.set_xlabel("speed [rad/s]")
    ax.set_ylabel("pull-out torque [N m]")
    top = ax.secondary_xaxis("top", functions=(_to_rpm, _to_rad_s))
    top.set_xlabel("speed [rpm]")
    ax.legend(fontsize=8, title=f"v_bus {report['v_bus']:g} V, {report['current']:.3g} A", title_fontsize=8)
    fig.tight_layout()
    return fig


def _figure(report: dict[str, Any], path: str) -> None:
    """Write :func:`_plot`'s figure to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fig = _plot(report)
    fig.savefig(path)
    plt.close(fig)


def cmd_curve(args: argparse.Namespace) -> int:
    """``flatstep curve``: the pull-out curve, its landmarks and band; a figure with ``--out``."""
    if args.out:  # before any work
        check_output(args.out, "--out", inputs=[args.scenario], force=args.force, marks=PNG_MARK)
    report = curve_report(args)
    if args.out:
        _figure(report, args.out)
    if args.json:
        print(strict_json(report, indent=2))
    else:
        _print(report)
        if args.out:
            print(f"wrote {args.out}")
    return 0


def add_curve_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``flatstep curve`` to the subcommands ``sub``."""
    cur = sub.add_parser("curve", help="pull-out torque against speed of a scenario's motor (docs/curves.md)",
                         description="The pull-out torque against speed of the file's motor on its bus, from the "
                         "steady-state phasor equations: an open-loop chopper (step/dir driver), field-oriented "
                         "with i_d = 0, field-oriented with field weakening; the corner speed, the top speed at a "
                         "load, the electrical-frequency limit of the drive; with --current on a motor given by its "
                         "datasheet, the band its conventions leave open (docs/curves.md).")
    cur.add_argument("scenario", help="a scenario file (TOML); a motor file of examples/motors/ with --v-bus")
    cur.add_argument("--drive", choices=(*DRIVE_KINDS, "all"), default="all", help="the drive kind (default: all)")
    cur.add_argument("--v-bus", type=quantity("v_bus", "--v-bus"), default=None,
                     help="the bus [V] (default: the file's [drive] v_bus)")
    cur.add_argument("--current", type=quantity("current", "--current"), default=None,
                     help="the driver's current setting per phase [A], read as --setting (default: the file's plan's "
                     "run current, a current-vector norm; for a motor file, its rated one)")
    cur.add_argument("--setting", choices=("rms", "peak"), default="rms", help="what --current is: the RMS (or the "
                     "DC current of a full-step drive, default) or the peak of the phase current")
    cur.add_argument("--load", type=quantity("torque_amplitude", "--load"), default=0.0,
                     help="the load [N m] for the top speed (default 0)")
    cur.add_argument("--w-max", type=quantity("speed", "--w-max"), default=None,
                     help="the highest speed [rad/s] of the curve (default 1.5 x the no-load top speed)")
    cur.add_argument("--points", type=count("samples", "--points"), default=201, help="speeds on the curve")
    cur.add_argument("--engine", type=count("samples", "--engine"), default=0,
                     help="check the chopper's curve at this many speeds on the C engine (open-loop drive)")
    cur.add_argument("--out", default=None, help="write the figure (PNG) here")
    cur.add_argument("--json", action="store_true", help="print the curve as JSON")
    add_force(cur)
    cur.set_defaults(func=cmd_curve)
