"""Command line: ``flatstep motor FILE.toml``, the model of a file's ``[motor]``, what was assumed and how sure it is.

The ``[motor]`` table is a datasheet (docs/motors.md: step_angle, rated_current, holding_torque, resistance,
inductance, rotor_inertia, ...) or the model itself (``preset`` and/or R, L, Km, J, B, Nr). Prints R, L, Km, J, B,
Nr, the derived figures (L/R, the electrical frequency and the back-EMF per rad/s, the rated current-vector norm
and torque), every assumption with its uncertainty, and every key that was filled in because the file did not give
it. ``--json`` prints the same as JSON.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, Optional

from ..json_out import strict_json
from ..model.datasheet import MODEL_KEYS, Assumption, MotorModel, motor_from_table, uses_datasheet
from ..model.motor import PRESETS, MotorParams
from ..studies.file_values import read_toml
from ..validate import InputError
from .flags import quantity

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - Python 3.10
    pass

#: The model's parameters: unit and meaning.
PARAMS = {"R": ("ohm", "winding resistance per phase"), "L": ("H", "winding inductance per phase"),
          "Km": ("N m/A", "torque constant of the current-vector norm (= back-EMF constant, V s/rad)"),
          "J": ("kg m^2", "rotor inertia"), "B": ("N m s/rad", "viscous friction"), "Nr": ("", "rotor teeth")}


def _table(path: Path) -> dict[str, Any]:
    """The ``[motor]`` table of the TOML file at ``path``; a ValueError names the file and why."""
    where = str(path)
    doc = read_toml(path)
    table = doc.get("motor")
    if not isinstance(table, dict) or not table:
        raise ValueError(f"{where}: no [motor] table: give the motor by its datasheet keys (docs/motors.md) or by "
                         "preset / R, L, Km, J, B, Nr")
    return table


def _model(table: dict[str, Any], where: str) -> MotorParams:
    """A ``[motor]`` table of model keys: a preset with changes, or all six parameters."""
    unknown = sorted(set(table) - set(MODEL_KEYS))
    if unknown:
        raise ValueError(f"{where}:motor: unknown key(s) {unknown}; valid: {list(MODEL_KEYS)}, or the datasheet keys "
                         "(docs/motors.md)")
    values = dict(table)
    preset = values.pop("preset", None)
    if preset is not None and (not isinstance(preset, str) or preset not in PRESETS):
        raise ValueError(f"{where}:motor.preset: preset={preset!r} is unknown; valid: {sorted(PRESETS)}")
    missing = [k for k in PARAMS if k not in values]
    if preset is None and missing:
        raise ValueError(f"{where}:motor: {missing} missing: give all of R, L, Km, J, B, Nr, a preset, or the "
                         "datasheet keys (docs/motors.md)")
    try:
        return PRESETS[preset].replace(**values) if preset is not None else MotorParams(**values)
    except InputError as exc:
        raise exc.at(f"{where}:motor.{exc.name}") from None


def describe(path: str | Path, v_bus: Optional[float] = None) -> dict[str, Any]:
    """What ``flatstep motor`` prints, as a dict: the parameters, derived figures, assumptions and defaults.

    ``v_bus`` [V]: also the speed at which the back-EMF amplitude alone reaches the bus, ``v_bus / Km``.
    """
    path = Path(path)
    table = _table(path)
    out: dict[str, Any] = {"file": str(path)}
    model: Optional[MotorModel] = None
    if uses_datasheet(table):
        model = motor_from_table(table, str(path))
        params = model.params
        out["given_as"] = "datasheet"
        out["datasheet"] = model.datasheet
    else:
        params = _model(table, str(path))
        out["given_as"] = "model parameters"
    out["params"] = params.as_dict()
    derived: dict[str, Any] = {"L_over_R": params.L / params.R,
                               "electrical_hz_per_rad_s": params.Nr / (2.0 * math.pi),
                               "back_emf_per_rad_s": params.Km}
    if model is not None:
        derived.update(rated_rho=model.rated_rho, rated_torque=model.rated_torque)
        if model.datasheet.get("detent_torque") is not None:
            derived["detent_torque"] = model.datasheet["detent_torque"]
    out["derived"] = derived
    notes = model.assumptions if model is not None else (
        Assumption("all", "the model parameters are taken as given" + (f", preset {table['preset']!r} for the keys "
                   "not given" if "preset" in table else ""), "that of the source of the figures"),)
    out["assumptions"] = [a.as_dict() for a in notes]
    out["defaults"] = model.defaults if model is not None else {}
    if v_bus is not None:
        derived["v_bus"] = v_bus
        derived["speed_at_bus"] = v_bus / params.Km
    return out


def _text(d: dict[str, Any]) -> str:
    """The report of :func:`describe` as text."""
    sheet = d.get("datasheet", {})
    name = " ".join(str(sheet[k]) for k in ("maker", "part") if k in sheet)
    lines = [f"{d['file']}: {name or 'motor'} (given as {d['given_as']})", "model (eq. (1)):"]
    for key, (unit, what) in PARAMS.items():
        lines.append(f"  {key:<3}{d['params'][key]:>12.6g} {unit:<10} {what}")
    x = d["derived"]
    lines += ["derived:",
              f"  L/R                          {1e3 * x['L_over_R']:>10.4g} ms",
              f"  electrical frequency         {x['electrical_hz_per_rad_s']:>10.4g} Hz per rad/s (Nr / 2 pi)",
              f"  back-EMF                     {x['back_emf_per_rad_s']:>10.4g} V per rad/s (Km, per phase amplitude)"]
    if "rated_rho" in x:
        lines += [f"  rated current-vector norm    {x['rated_rho']:>10.4g} A (i_max of a plan's [limits])",
                  f"  rated torque                 {x['rated_torque']:>10.4g} N m (Km x rated norm)"]
    if "v_bus" in x:
        lines.append(f"  back-EMF reaches {x['v_bus']:g} V at  {x['speed_at_bus']:>10.4g} rad/s "
                     f"({x['speed_at_bus'] * 60 / (2 * math.pi):.4g} rpm: the no-load limit; torque falls well before)")
    if "detent_torque" in x:
        lines.append(f"  detent torque                {x['detent_torque']:>10.4g} N m (not in eq. (1): [plant] "
                     "detent_torque)")
    lines.append("assumptions (uncertainty):")
    for a in d["assumptions"]:
        mark = " [defaulted]" if a["defaulted"] else ""
        lines.append(f"  {a['parameter']}{mark}: {a['what']}\n      uncertainty: {a['uncertainty']}")
    taken = ", ".join(f"{k} = {json.dumps(v)}" for k, v in d["defaults"].items()) or "none"
    lines.append(f"defaulted (not in the file): {taken}")
    return "\n".join(lines)


def _rows(reports: list[dict[str, Any]]) -> str:
    """Several motors, one row each: the datasheet's figures and the model's Km, L/R and rated norm."""
    head = (f"{'file':<40}{'A':>6}{'ohm':>7}{'mH':>7}{'N m':>7}{'g cm^2':>8}{'Km':>8}{'L/R ms':>8}{'i_max':>7}"
            f"{'Nr':>4}  defaulted")
    rows = [head]
    for d in reports:
        p, x, s = d["params"], d["derived"], d.get("datasheet", {})
        amps = f"{s['rated_current']:>6.3g}" if s else f"{'-':>6}"
        torque = f"{s['holding_torque']:>7.3g}" if s else f"{'-':>7}"
        norm = f"{x['rated_rho']:>7.3g}" if "rated_rho" in x else f"{'-':>7}"
        rows.append(f"{Path(d['file']).name:<40}{amps}{p['R']:>7.3g}{1e3 * p['L']:>7.3g}{torque}{1e7 * p['J']:>8.4g}"
                    f"{p['Km']:>8.4g}{1e3 * x['L_over_R']:>8.3g}{norm}{p['Nr']:>4}  {', '.join(d['defaults'])}")
    return "\n".join(rows)


def cmd_motor(args: argparse.Namespace) -> int:
    """``flatstep motor FILE.toml ...``: the model of each file's ``[motor]``, its assumptions and uncertainty."""
    reports = [describe(path, args.v_bus) for path in args.file]  # every file checked before anything is printed
    if args.json:
        print(strict_json(reports[0] if len(reports) == 1 else reports, indent=2))
    else:
        print(_text(reports[0]) if len(reports) == 1 else _rows(reports))
    return 0


def add_motor_command(sub: Any) -> None:
    """Register ``flatstep motor`` on the subcommand parser ``sub``."""
    p = sub.add_parser("motor", help="a motor from its datasheet: the model, the assumptions, their uncertainty",
                       description="Print the model of a file's [motor] table (datasheet keys, or preset / R, L, "
                       "Km, J, B, Nr): R, L, Km, J, B, Nr, L/R, the electrical frequency and back-EMF per rad/s, "
                       "the rated current-vector norm and torque, every assumption made with the uncertainty it "
                       "carries, and what was defaulted (docs/motors.md). Several files: one row each.")
    p.add_argument("file", nargs="+", help="a TOML file with a [motor] table (examples/motors/*.toml, a scenario or "
                   "a plan file); several files: one row each (the full report with --json)")
    p.add_argument("--v-bus", type=quantity("v_bus", "--v-bus"), default=None, metavar="V",
                   help="a bus voltage [V]: also print the speed at which the back-EMF alone reaches it")
    p.add_argument("--json", action="store_true", help="print the same as JSON")
    p.set_defaults(func=cmd_motor)
