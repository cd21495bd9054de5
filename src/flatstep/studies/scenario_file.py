"""Scenario files (TOML): one format for every command, a whole run and its plan in one file.

The tables: motor, plant, plan, limits, controller, drive, sensors, observer, load, feedforward, robustness;
docs/scenario-reference.md lists every table and key (generated from :mod:`flatstep.studies.scenario_keys`);
examples/*.toml and examples/plans/*.toml show them at work. An unknown key, an old name or a bad value is a
ValueError naming ``file:table.key``, the value, why and what is valid.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any, Optional, Union

from ..control.build import check_lambda_ts
from ..control.smc import MEASUREMENTS, SMCGains
from ..control.spec import LAW_GAINS, LAW_TABLE, OPTION_LAWS, ControllerSpec, default_type, spec_without_law
from ..control.tuning import CONTROLLER_TYPES
from ..loop.design import design_gains
from ..loop.drive import Drive
from ..loop.observers import Observer
from ..loop.reference import DriveLoop
from ..loop.sensors import Sensors
from ..model.datasheet import motor_from_table, uses_datasheet
from ..model.motor import PRESETS, MotorParams
from ..model.plant import Plant, PlantEffects
from ..model.torque_model import TorqueModel
from ..plan.d_current import DCurrentPlan
from ..plan.limits import MotorLimits
from ..plan.loss_aware import LossAwareRho
from ..plan.piecewise import PiecewisePlan
from ..plan.sequence import Step
from ..validate import InputError, check_bool, check_choice, check_count, check_quantity
from .file_values import check_keys, read_toml, value, wrap
from .scenario import Scenario
from .scenario_keys import DEFAULT_MOTOR, KEYS
from .scenario_plan import read_limits, read_plan

MOTOR_KEYS = ("preset", "R", "L", "Km", "J", "B", "Nr")
EFFECT_KEYS = ("detent_torque", "coulomb_torque", "coulomb_speed", "magnetizing_resistance")
#: The horizon after a waypoint plan's end when the file gives no t_end [s].
T_AFTER = 0.02


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


def read_motor(where: str, table: dict[str, Any], section: str, base: MotorParams) -> MotorParams:
    """The motor of a ``[motor]`` or ``[plant]`` table: ``base`` or a preset, with the given values and scales.

    The one reader of a motor table: every command's file goes through it.
    """
    values: dict[str, Any] = dict(base.as_dict())
    if "preset" in table:
        if not isinstance(table["preset"], str) or table["preset"] not in PRESETS:
            raise ValueError(f"{where}: [{section}] preset={table['preset']!r} is unknown; valid: {sorted(PRESETS)}")
        values = PRESETS[table["preset"]].as_dict()
    values.update({k: v for k, v in table.items() if k in MOTOR_KEYS[1:]})
    motor = wrap(where, section, MotorParams, **values)
    scale = table.get("scale", {})
    if not isinstance(scale, dict) or set(scale) - set(MOTOR_KEYS[1:6]):
        raise ValueError(f"{where}: [{section}] scale={scale!r} must be a table of factors on R, L, Km, J, B")
    factors = {k: value(where, f"{section}.scale", k, partial(check_quantity, "scale", as_name=k), f)
               for k, f in scale.items()}
    return wrap(where, section, motor.replace, **{k: getattr(motor, k) * f for k, f in factors.items()})


@dataclass(frozen=True)
class ScenarioFile:
    """What a scenario file holds: the run, its robustness study, and its plan as planned.

    ``limits`` (``[limits]`` on the ``[drive]`` bus) are what the plan was planned and is checked against;
    ``steps`` its moves and dwells, (label, start [s], duration [s]).
    """

    path: Path
    scenario: Scenario
    robustness: Optional[Robustness]
    planner: str
    limits: Optional[MotorLimits]
    steps: list[Step]

    @property
    def name(self) -> str:
        """The scenario's name."""
        return self.scenario.name

    @property
    def motor(self) -> MotorParams:
        """The controller's (and the planner's) model of the motor."""
        return self.scenario.motor

    @property
    def plan(self) -> PiecewisePlan:
        """The plan as a segment table (the paper's move as one segment)."""
        return self.scenario.plan.to_table()

    @property
    def v_bus(self) -> Optional[float]:
        """The drive's bus [V], ``None`` without a drive (continuous-time control)."""
        loop = self.scenario.loop
        return loop.drive.v_bus if loop is not None and loop.drive is not None else None

    @property
    def control_rate(self) -> Optional[float]:
        """The drive's control rate [Hz], ``None`` for continuous-time control."""
        period = self.scenario.control_period
        return None if period is None else 1.0 / period


def load_scenario(path: Union[str, Path]) -> tuple[Scenario, Optional[Robustness]]:
    """Read a scenario file; returns the :class:`Scenario` and its robustness study (or ``None``)."""
    sf = read_scenario_file(path)
    return sf.scenario, sf.robustness


def _design_load(where: str, load: float, effects: Optional[PlantEffects]) -> float:
    """The torque the design allows for: the load, the detent and the Coulomb friction, named by their keys."""
    parts = {"load.torque": load}
    if effects is not None:
        parts.update({"plant.detent_torque": effects.detent_torque, "plant.coulomb_torque": effects.coulomb_torque})
    total = abs(parts["load.torque"]) + sum(v for k, v in parts.items() if k != "load.torque")
    try:
        return check_quantity("load", total, as_name="design load torque")
    except InputError as exc:
        key = max(parts, key=lambda k: abs(parts[k]))
        raise InputError(key.split(".")[1], parts[key], f"{where}:{key}: {key}={parts[key]!r} N m: the designed gains "
                         f"allow for {' + '.join(parts)} = {total:g} N m, {exc}") from None


def read_scenario_file(path: Union[str, Path]) -> ScenarioFile:
    """Read and plan a scenario file (module docstring); a bad file is a ValueError naming ``file:table.key``."""
    path = Path(path)
    where = str(path)
    doc = read_toml(path)
    check_keys(where, doc, "")
    for key in ("name", "description"):
        if key in doc and not isinstance(doc[key], str):
            raise InputError(key, doc[key], f"{where}:{key}: {key}={doc[key]!r} must be a string")
    sec = {name: check_keys(where, doc.get(name, {}), name) for name in KEYS if name}
    motor = (motor_from_table(sec["motor"], where).params if uses_datasheet(sec["motor"])
             else read_motor(where, sec["motor"], "motor", MotorParams.preset(DEFAULT_MOTOR)))
    plant_t = {k: v for k, v in sec["plant"].items() if k not in EFFECT_KEYS}
    plant = read_motor(where, plant_t, "plant", motor) if plant_t else None
    effects_t = {k: v for k, v in sec["plant"].items() if k in EFFECT_KEYS}
    effects = wrap(where, "plant", PlantEffects, **effects_t) if effects_t else None
    load = value(where, "load", "torque", lambda v: check_quantity("load", v, as_name="torque"),
                 sec["load"].get("torque", 0.0))

    drive_t = dict(sec["drive"])
    rate = drive_t.pop("control_rate", None)
    substeps = drive_t.pop("substeps", 4)
    compute_delay = drive_t.pop("compute_delay", False)
    if rate is None and (drive_t or sec["sensors"] or sec["observer"] or compute_delay):
        raise ValueError(f"{where}: [drive] control_rate is needed for a drive, sensors or an observer "
                         "(without it the law runs in continuous time, as in the paper)")
    if rate is not None:
        rate = value(where, "drive", "control_rate", lambda v: check_quantity("rate", v, as_name="control_rate"),
                     rate)
    compute_delay = value(where, "drive", "compute_delay", lambda v: check_bool("compute_delay", v), compute_delay)
    period = None if rate is None else 1.0 / rate
    drive = wrap(where, "drive", Drive, **drive_t) if rate is not None else None
    limits = read_limits(where, sec["limits"], drive.v_bus if drive is not None and "v_bus" in drive_t else None)
    planned = read_plan(where, sec["plan"], motor, limits, has_motor="motor" in doc, control_rate=rate)
    plan = planned.plan
    offset = sec["sensors"].get("current_offset")
    if offset is not None and not (isinstance(offset, list) and len(offset) == 2):
        raise InputError("current_offset", offset, f"{where}:sensors.current_offset: current_offset={offset!r} must "
                                                   "be two offsets [ia, ib] in A")
    sensors = wrap(where, "sensors", Sensors, **{**sec["sensors"], **(
        {"current_offset": tuple(offset)} if offset is not None else {})}) if sec["sensors"] else None

    ctrl = dict(sec["controller"])
    spec_keys = {k: ctrl.pop(k) for k in ("law", *OPTION_LAWS) if k in ctrl}
    if spec_keys and "type" in ctrl:
        raise InputError("type", ctrl["type"], f"{where}:controller: give the controller by type={ctrl['type']!r} or "
                         f"by law and options ({sorted(spec_keys)}), not both")
    if spec_keys and "law" not in spec_keys:  # options over the default law (docs/controllers.md)
        controller_type = spec_without_law(spec_keys, default_type(sampled=period is not None,
                                                                   torques="feedforward" in doc),
                                           f"{where}:controller").name()
    elif spec_keys:
        controller_type = ControllerSpec.parse(spec_keys, f"{where}:controller").name()
    else:
        given = ctrl.pop("type", None)
        if given is None:  # the default law (docs/comparison.md, "The default controller")
            given = default_type(sampled=period is not None, torques="feedforward" in doc)
        if not isinstance(given, str):
            raise InputError("type", given, f"{where}:controller.type: type={given!r} is unknown; valid: "
                             f"{list(CONTROLLER_TYPES)}, or law+option+...")
        controller_type = ControllerSpec.parse(given, f"{where}:controller.type: type").name()
    bandwidth_scale = ctrl.pop("bandwidth_scale", 1.0)
    design = value(where, "controller", "design", lambda v: check_bool("design", v), ctrl.pop("design", False))
    uncertainty = value(where, "controller", "uncertainty",
                        lambda v: check_quantity("relative", v, as_name="uncertainty"), ctrl.pop("uncertainty", 0.1))
    measurement = ctrl.pop("measurement", None)
    if measurement is not None:
        measurement = value(where, "controller", "measurement", partial(check_choice, "measurement",
                                                                        valid=MEASUREMENTS), measurement)
    weakening = {k: ctrl.pop(k) for k in ("weakening", "weakening_speed") if k in ctrl}
    d_current = wrap(where, "controller", DCurrentPlan, **weakening)
    if planned.d_current is not None:  # a field-weakening plan brings its d current, for the d-q law alone
        if weakening or not controller_type.startswith("dq_smc"):
            raise InputError("type", controller_type, f"{where}:controller: a field-weakening plan is tracked by a "
                             "dq_smc controller type with the plan's d current (no weakening keys); give type = "
                             "\"dq_smc\" or another dq_smc type")
        d_current = planned.d_current
    rho_keys = {"rho_margin": "margin", "rho_hold": "rho_hold"}
    given = {rho_keys[k]: ctrl.pop(k) for k in rho_keys if k in ctrl}
    loss_aware = wrap(where, "controller", LossAwareRho, **{"rho_hold": 0.5 * min(plan.rho1, plan.rho2), **given}
                      ) if given else None
    lambda_ts = ctrl.pop("lambda_ts", None)
    if lambda_ts is not None:
        lambda_ts = value(where, "controller", "lambda_ts", check_lambda_ts, lambda_ts)
    law = ControllerSpec.parse(controller_type).law
    sliding_keys, law_gains = (ctrl, None) if LAW_TABLE[law].sliding else ({}, ctrl)
    for key in ctrl:
        if key not in LAW_GAINS[law]:
            unnamed = "" if "law" in spec_keys or "type" in sec["controller"] else (
                f" (the file names no type: {controller_type!r} is the default; type = \"smc\" for the paper's law)")
            raise InputError(key, ctrl[key], f"{where}:controller.{key}: {key} is not a gain of law {law!r}{unnamed}; "
                             f"its gains: {list(LAW_GAINS[law])}")
    observer = None
    if design:
        if period is None or drive is None:  # no control_rate: neither a period nor a drive
            raise ValueError(f"{where}: [controller] design = true needs [drive] control_rate")
        d = wrap(where, "controller", design_gains, motor=motor, plan=plan, control_period=period,
                 v_bus=drive.v_bus, load_torque=_design_load(where, load, effects),
                 uncertainty=uncertainty, compute_delay=compute_delay,
                 encoder_counts=sensors.encoder_counts if sensors else None,
                 current_step=sensors.current_step if sensors else 0.0)
        gains = wrap(where, "controller", lambda **kw: replace(d.gains, **kw), **sliding_keys)
        observer = d.observer if sensors else None
    else:
        gains = wrap(where, "controller", SMCGains, **sliding_keys)
    if sec["observer"]:
        observer = wrap(where, "observer", Observer, **{**(observer.as_dict() if observer else {}), **sec["observer"]})
    if measurement is None:  # what the drive can give: an observer's estimate, the model, or the truth
        measurement = "observer" if observer else "model" if sensors else "ideal"
    loop = None if period is None else wrap(where, "drive", DriveLoop, control_period=period, substeps=substeps,
                                            compute_delay=compute_delay, drive=drive, sensors=sensors,
                                            observer=observer)
    torques = wrap(where, "feedforward", TorqueModel, **sec["feedforward"]) if "feedforward" in doc else None
    simulated = wrap(where, "plant", Plant, motor=plant if plant is not None else motor, effects=effects, load=load)
    t_end = doc.get("t_end", 0.06 if planned.planner == "rest_to_rest" else plan.tf + T_AFTER)
    scenario = wrap(where, "scenario", Scenario, name=str(doc.get("name", path.stem)), motor=motor, plan=plan,
                    gains=gains, measurement=measurement, t_end=t_end, plant=simulated,
                    loop=loop, controller_type=controller_type, bandwidth_scale=bandwidth_scale, torques=torques,
                    lambda_ts=lambda_ts, law_gains={law: law_gains} if law_gains else None,
                    d_current=d_current, loss_aware=loss_aware)
    robustness = wrap(where, "robustness", Robustness, **sec["robustness"]) if "robustness" in doc else None
    return ScenarioFile(path, scenario, robustness, planned.planner, planned.limits, planned.steps)
