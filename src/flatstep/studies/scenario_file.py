"""Scenario files (TOML): motor, plan, controller, drive, sensors, observer, load, robustness.

See examples/*.toml for every key; an unknown key or a bad value is a ValueError naming the file and key.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any, Callable, Optional, TypeVar

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..control.design import design_gains
from ..control.smc import MEASUREMENTS, SMCGains
from ..control.tuning import CONTROLLER_TYPES
from ..loop.drive import Drive
from ..loop.observers import Observer
from ..loop.reference import DriveLoop
from ..loop.sensors import Sensors
from ..model.datasheet import DATASHEET_KEYS, motor_from_table, uses_datasheet
from ..model.motor import PRESETS, MotorParams
from ..model.plant import Plant, PlantEffects
from ..model.torque_model import TorqueModel
from ..plan.d_current import DCurrentPlan
from ..plan.loss_aware import LossAwareRho
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from ..validate import InputError, check_bool, check_choice, check_count, check_quantity
from .scenario import Scenario

MOTOR_KEYS = ("preset", "R", "L", "Km", "J", "B", "Nr")
EFFECT_KEYS = ("detent_torque", "coulomb_torque", "coulomb_speed", "magnetizing_resistance")
T = TypeVar("T")
SECTIONS: dict[str, tuple[str, ...]] = {
    "": ("name", "description", "t_end", "motor", "plant", "plan", "controller", "drive", "sensors", "observer",
         "load", "feedforward", "robustness"),
    "motor": MOTOR_KEYS + tuple(DATASHEET_KEYS),
    "plant": MOTOR_KEYS + ("scale",) + EFFECT_KEYS,
    "plan": ("theta1", "theta2", "rho1", "rho2", "t0", "tf"),
    "controller": ("type", "bandwidth_scale", "measurement", "W1", "W2", "eps1", "eps2", "xi", "wn", "hold_damping",
                   "design", "uncertainty", "weakening", "weakening_speed", "rho_margin", "rho_hold"),
    "drive": ("control_rate", "substeps", "compute_delay", "v_bus", "pwm", "f_pwm", "dead_time"),
    "sensors": ("encoder_counts", "encoder_offset", "current_bits", "current_range", "current_offset",
                "current_noise", "delay", "seed"),
    "observer": ("bandwidth", "load_states"),
    "load": ("torque",),
    "feedforward": ("detent_torque", "detent_harmonic", "detent_phase", "coulomb_torque", "coulomb_speed", "load",
                    "load_step", "load_t0", "load_tf"),
    "robustness": ("relative_error", "parameters", "samples", "seed"),
}


@dataclass(frozen=True)
class Robustness:
    """A parameter-error study on the plant's ``parameters``.

    It runs every sign combination of +-``relative_error`` (``samples = 0``) or a seeded uniform random sample
    of ``samples`` plants in the same box.
    """

    relative_error: float = 0.1
    parameters: tuple[str, ...] = ("R", "L", "Km", "J", "B")
    samples: int = 0
    seed: int = 0

    def __post_init__(self) -> None:
        err = check_quantity("relative", self.relative_error, as_name="relative_error")
        if not 0.0 < err < 0.5:
            raise InputError("relative_error", err, f"relative_error={err!r} must be in (0, 0.5): a relative error "
                                                    "(0 is a study of no error, one run)")
        object.__setattr__(self, "relative_error", err)
        params = self.parameters
        valid = MOTOR_KEYS[1:6]
        if isinstance(params, str) or not isinstance(params, (list, tuple)) or not params or any(
                not isinstance(p, str) or p not in valid for p in params) or len(set(params)) != len(params):
            raise InputError("parameters", params, f"parameters={params!r} must be a non-empty list of distinct names "
                                                   f"among {list(valid)}")
        object.__setattr__(self, "parameters", tuple(params))
        object.__setattr__(self, "samples", check_count("samples", self.samples,
                                                        why="0: every sign combination; else random plants"))
        object.__setattr__(self, "seed", check_count("seed", self.seed))


def _check_keys(where: str, table: Any, section: str) -> dict[str, Any]:
    """``table`` if it is a table of known keys of ``section``, else a ValueError naming the file and key."""
    if not isinstance(table, dict):
        raise ValueError(f"{where}: [{section}] must be a table, got {table!r}")
    unknown = sorted(set(table) - set(SECTIONS[section]))
    if unknown:
        label = f"[{section}]" if section else "the top level"
        raise ValueError(f"{where}: unknown key(s) {unknown} in {label}; valid: {list(SECTIONS[section])}")
    return table


#: Where a value refused by a constructor was given in a scenario file, when its name is not its key.
_SOURCES = {"control_period": "drive.control_rate", "t0": "plan.t0", "tf": "plan.tf", "t_end": "t_end",
            "substeps": "drive.substeps", "bandwidth_scale": "controller.bandwidth_scale",
            "measurement": "controller.measurement", "controller_type": "controller.type"}


def _source(where: str, section: str, name: str, keys: Any) -> str:
    """``file:table.key`` of the value ``name`` refused in ``[section]`` (whose keys are ``keys``)."""
    if section == "scenario" and name in _SOURCES:  # the Scenario's fields come from several tables
        return f"{where}:{_SOURCES[name]}"
    if name in keys:
        return f"{where}:{section + '.' if section else ''}{name}"
    if name in _SOURCES:
        return f"{where}:{_SOURCES[name]}"
    return f"{where}:{section}" if section else where


def _wrap(where: str, section: str, build: Callable[..., T], **kwargs: Any) -> T:
    """``build(**kwargs)``, its errors raised again as a ValueError naming the file, table and key."""
    try:
        return build(**kwargs)
    except InputError as exc:
        raise exc.at(_source(where, section, exc.name, kwargs)) from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: [{section}] {exc}") from None


def _value(where: str, section: str, key: str, check: Callable[[Any], T], value: Any) -> T:
    """``check(value)`` for the value of ``key`` in ``[section]``, its error naming ``file:section.key``."""
    try:
        return check(value)
    except InputError as exc:
        raise exc.at(_source(where, section, key, (key,))) from None


def _read(path: Path) -> dict[str, Any]:
    """The TOML document at ``path``, or a ValueError naming the file and why it cannot be read."""
    where = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ValueError(f"{where}: no such scenario file") from None
    except IsADirectoryError:
        raise ValueError(f"{where}: is a directory, not a scenario file (give a .toml file)") from None
    except PermissionError:
        raise ValueError(f"{where}: cannot read the scenario file (permission denied)") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not a text file (UTF-8): {exc.reason} at byte {exc.start}") from None
    except OSError as exc:
        raise ValueError(f"{where}: cannot read the scenario file: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML: {exc}") from None


def _motor(where: str, table: dict[str, Any], section: str, base: MotorParams) -> MotorParams:
    """The motor of a ``[motor]`` or ``[plant]`` table: ``base`` or a preset, with the given values and scales."""
    values: dict[str, Any] = dict(base.as_dict())
    if "preset" in table:
        if not isinstance(table["preset"], str) or table["preset"] not in PRESETS:
            raise ValueError(f"{where}: [{section}] preset={table['preset']!r} is unknown; valid: {sorted(PRESETS)}")
        values = PRESETS[table["preset"]].as_dict()
    values.update({k: v for k, v in table.items() if k in MOTOR_KEYS[1:]})
    motor = _wrap(where, section, MotorParams, **values)
    scale = table.get("scale", {})
    if not isinstance(scale, dict) or set(scale) - set(MOTOR_KEYS[1:6]):
        raise ValueError(f"{where}: [{section}] scale={scale!r} must be a table of factors on R, L, Km, J, B")
    factors = {k: _value(where, f"{section}.scale", k, partial(check_quantity, "scale", as_name=k), f)
               for k, f in scale.items()}
    return _wrap(where, section, motor.replace, **{k: getattr(motor, k) * f for k, f in factors.items()})


def load_scenario(path: str | Path) -> tuple[Scenario, Optional[Robustness]]:
    """Read a scenario file; returns the :class:`Scenario` and its robustness study (or ``None``)."""
    path = Path(path)
    where = str(path)
    doc = _read(path)
    _check_keys(where, doc, "")
    for key in ("name", "description"):
        if key in doc and not isinstance(doc[key], str):
            raise InputError(key, doc[key], f"{where}:{key}: {key}={doc[key]!r} must be a string")
    sec = {name: _check_keys(where, doc.get(name, {}), name) for name in SECTIONS if name}
    motor = (motor_from_table(sec["motor"], where).params if uses_datasheet(sec["motor"])
             else _motor(where, sec["motor"], "motor", MotorParams.preset("paper")))
    plant_t = {k: v for k, v in sec["plant"].items() if k not in EFFECT_KEYS}
    plant = _motor(where, plant_t, "plant", motor) if plant_t else None
    effects_t = {k: v for k, v in sec["plant"].items() if k in EFFECT_KEYS}
    effects = _wrap(where, "plant", PlantEffects, **effects_t) if effects_t else None
    plan = _wrap(where, "plan", RestToRest, **{**PAPER_PLAN.as_dict(), **sec["plan"]})
    load = _value(where, "load", "torque", lambda v: check_quantity("load", v, as_name="torque"),
                  sec["load"].get("torque", 0.0))

    drive_t = dict(sec["drive"])
    rate = drive_t.pop("control_rate", None)
    substeps = drive_t.pop("substeps", 4)
    compute_delay = drive_t.pop("compute_delay", False)
    if rate is None and (drive_t or sec["sensors"] or sec["observer"] or compute_delay):
        raise ValueError(f"{where}: [drive] control_rate is needed for a drive, sensors or an observer "
                         "(without it the law runs in continuous time, as in the paper)")
    if rate is not None:
        rate = _value(where, "drive", "control_rate", lambda v: check_quantity("rate", v, as_name="control_rate"),
                      rate)
    compute_delay = _value(where, "drive", "compute_delay", lambda v: check_bool("compute_delay", v), compute_delay)
    period = None if rate is None else 1.0 / rate
    drive = _wrap(where, "drive", Drive, **drive_t) if rate is not None else None
    offset = sec["sensors"].get("current_offset")
    if offset is not None and not (isinstance(offset, list) and len(offset) == 2):
        raise InputError("current_offset", offset, f"{where}:sensors.current_offset: current_offset={offset!r} must "
                                                   "be two offsets [ia, ib] in A")
    sensors = _wrap(where, "sensors", Sensors, **{**sec["sensors"], **(
        {"current_offset": tuple(offset)} if offset is not None else {})}) if sec["sensors"] else None

    ctrl = dict(sec["controller"])
    controller_type = ctrl.pop("type", "smc")
    if not isinstance(controller_type, str) or controller_type not in CONTROLLER_TYPES:
        raise ValueError(f"{where}: [controller] type={controller_type!r} is unknown; valid: {list(CONTROLLER_TYPES)}")
    bandwidth_scale = ctrl.pop("bandwidth_scale", 1.0)
    design = _value(where, "controller", "design", lambda v: check_bool("design", v), ctrl.pop("design", False))
    uncertainty = _value(where, "controller", "uncertainty",
                         lambda v: check_quantity("relative", v, as_name="uncertainty"), ctrl.pop("uncertainty", 0.1))
    measurement = ctrl.pop("measurement", None)
    if measurement is not None:
        measurement = _value(where, "controller", "measurement", partial(check_choice, "measurement",
                                                                         valid=MEASUREMENTS), measurement)
    weakening = {k: ctrl.pop(k) for k in ("weakening", "weakening_speed") if k in ctrl}
    d_current = _wrap(where, "controller", DCurrentPlan, **weakening)
    rho_keys = {"rho_margin": "margin", "rho_hold": "rho_hold"}
    given = {rho_keys[k]: ctrl.pop(k) for k in rho_keys if k in ctrl}
    loss_aware = _wrap(where, "controller", LossAwareRho, **{"rho_hold": 0.5 * min(plan.rho1, plan.rho2), **given}
                       ) if given else None
    observer = None
    if design:
        if period is None or drive is None:  # no control_rate: neither a period nor a drive
            raise ValueError(f"{where}: [controller] design = true needs [drive] control_rate")
        d = _wrap(where, "controller", design_gains, motor=motor, plan=plan, control_period=period,
                  v_bus=drive.v_bus,
                  load_torque=load + (effects.detent_torque + effects.coulomb_torque if effects else 0.0),
                  uncertainty=uncertainty, compute_delay=compute_delay,
                  encoder_counts=sensors.encoder_counts if sensors else None,
                  current_step=sensors.current_step if sensors else 0.0)
        gains = _wrap(where, "controller", lambda **kw: replace(d.gains, **kw), **ctrl)
        observer = d.observer if sensors else None
    else:
        gains = _wrap(where, "controller", SMCGains, **ctrl)
    if sec["observer"]:
        observer = _wrap(where, "observer", Observer, **{**(observer.as_dict() if observer else {}), **sec["observer"]})
    if measurement is None:  # what the drive can give: an observer's estimate, the model, or the truth
        measurement = "observer" if observer else "model" if sensors else "ideal"
    loop = None if period is None else _wrap(where, "drive", DriveLoop, control_period=period, substeps=substeps,
                                             compute_delay=compute_delay, drive=drive, sensors=sensors,
                                             observer=observer)
    torques = _wrap(where, "feedforward", TorqueModel, **sec["feedforward"]) if "feedforward" in doc else None
    simulated = _wrap(where, "plant", Plant, motor=plant if plant is not None else motor, effects=effects, load=load)
    scenario = _wrap(where, "scenario", Scenario, name=str(doc.get("name", path.stem)), motor=motor, plan=plan,
                     gains=gains, measurement=measurement, t_end=doc.get("t_end", 0.06), plant=simulated,
                     loop=loop, controller_type=controller_type, bandwidth_scale=bandwidth_scale, torques=torques,
                     d_current=d_current, loss_aware=loss_aware)
    robustness = _wrap(where, "robustness", Robustness, **sec["robustness"]) if "robustness" in doc else None
    return scenario, robustness
