"""The keys of a scenario file, table by table: unit, valid values, default and meaning, in one registry.

The loader (:mod:`flatstep.studies.scenario_file`) takes its tables' keys from :data:`KEYS`, the planners' keys
from :data:`PLANNER_KEYS` and the old names it refuses with their new ones from :data:`RENAMED`;
``tools/gen_scenario_reference.py`` writes docs/scenario-reference.md from the same registry
(:func:`markdown_reference`).
"""
from __future__ import annotations

from dataclasses import MISSING, dataclass, fields, replace
from typing import Any

from ..control.smc import MEASUREMENTS, SMCGains
from ..control.spec import DEFAULT_TYPE, DEFAULT_TYPE_CONTINUOUS, DEFAULT_TYPE_TORQUES, LAWS, OPTIONS
from ..control.tuning import CONTROLLER_TYPES
from ..loop.drive import PWM_MODES, Drive
from ..loop.observers import Observer
from ..loop.sensors import Sensors
from ..model.datasheet import DATASHEET_KEYS, REQUIRED
from ..model.motor import PRESETS
from ..model.plant import PlantEffects
from ..model.torque_model import TorqueModel
from ..plan.limits import MotorLimits
from ..plan.rest_to_rest import PAPER_PLAN
from ..plan.sequence import PLANNERS
from ..validate.limits import MAX_OPTIMAL_MOVES
from ..validate.ranges import INTEGER_RANGES, QUANTITIES

#: The motor every file runs on when it has no ``[motor]`` table (a waypoint plan must name its motor).
DEFAULT_MOTOR = "paper"


@dataclass(frozen=True)
class Key:
    """One key of a table: its unit, what is valid, its default and what it means."""

    unit: str
    valid: str
    default: str
    doc: str


def _q(kind: str, default: Any, doc: str) -> Key:
    """A key checked against the range ``kind`` of :data:`flatstep.validate.ranges.QUANTITIES`."""
    q = QUANTITIES[kind]
    return Key(q.unit, q.describe().replace(f" {q.unit}", "") if q.unit else q.describe(), _fmt(default), doc)


def _i(kind: str, default: Any, doc: str) -> Key:
    """An integer key checked against :data:`flatstep.validate.ranges.INTEGER_RANGES`."""
    low, high = INTEGER_RANGES[kind]
    return Key("", f"integer in [{low}, {high}]", _fmt(default), doc)


def _fmt(value: Any) -> str:
    """A default as it would be written in TOML (``-`` for none)."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"' if value else '""'
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).replace("(", "[").replace(")", "]").replace("'", '"')


def _default(cls: type, name: str) -> Any:
    """The default of field ``name`` of the dataclass ``cls``."""
    for f in fields(cls):
        if f.name == name:
            return None if f.default is MISSING else f.default
    raise KeyError(name)


_MOTOR = {k: _q(k, None, f"the motor's {what} (default: the preset's)") for k, what in (
    ("R", "phase resistance"), ("L", "phase inductance"), ("Km", "torque constant"), ("J", "rotor and load inertia"),
    ("B", "viscous friction"))}
_MOTOR["Nr"] = _i("Nr", None, "rotor teeth (default: the preset's)")
_EFFECTS = {k: _q(kind, _default(PlantEffects, k), doc) for k, kind, doc in (
    ("detent_torque", "torque_amplitude", "the plant's detent (cogging) torque amplitude"),
    ("coulomb_torque", "torque_amplitude", "the plant's Coulomb friction"),
    ("coulomb_speed", "coulomb_speed", "the speed scale of the plant's smooth Coulomb sign"),
    ("magnetizing_resistance", "magnetizing_resistance", "the plant's iron-loss resistance (none: no iron loss)"))}
_LIMIT_DOCS = {
    "i_max": ("A", "> 0", "largest current-vector magnitude rho the plan may ask (required with [limits])"),
    "i_hold": ("A", "(0, i_max)", "current across the torque axis at rest (the holding current)"),
    "i_run": ("A", "(0, i_hold]", "current across the torque axis at speed (none: i_hold throughout)"),
    "speed_corner": ("rad/s", "> 0", "speed at which the across-axis current is halfway from i_hold to i_run"),
    "torque_angle_max": ("rad", "(0, pi/2)", "largest torque angle the plan may ask"),
    "v_use": ("", "(0, 1]", "fraction of [drive] v_bus the plan's feedforward may use"),
    "speed_max": ("rad/s", "> 0", "speed cap of the margins (none: no cap)"),
    "accel_max": ("rad/s^2", "> 0", "acceleration cap of the margins (none: no cap)"),
    "jerk_max": ("rad/s^3", "> 0", "jerk cap of the margins (none: no cap)"),
    "uncertainty": ("", "[0, 0.5)", "relative error of R, L, Km and J: flatstep plan checks the plan with the file's "
                                    "controller and drive on the plant and the 16 corners of +-uncertainty "
                                    "(0: the plant only; docs/planning.md section 7)"),
}

#: Every table's keys (``""``: the top level).
KEYS: dict[str, dict[str, Key]] = {
    "": {
        "name": Key("", "string", "the file's stem", "a label for tables, rows and figures"),
        "description": Key("", "string", '""', "free text"),
        "t_end": replace(_q("t_end", None, "the run's horizon from t = 0, at least the plan's end"),
                         default="0.06 (rest_to_rest); the plan's end + 0.02 (waypoints)"),
        **{t: Key("", "table", "-", f"the [{t}] table") for t in (
            "motor", "plant", "plan", "limits", "controller", "drive", "sensors", "observer", "load", "feedforward",
            "robustness")},
    },
    "motor": {"preset": Key("", ", ".join(f'"{p}"' for p in sorted(PRESETS)), f'"{DEFAULT_MOTOR}"',
                            "the motor the other keys start from (a waypoint plan must give [motor])"),
              **_MOTOR,
              **{k: Key(unit, "docs/motors.md", "required" if k in REQUIRED else "docs/motors.md",
                        f"datasheet figure (instead of preset and R, L, Km, J, B, Nr; flatstep motor FILE shows "
                        f"the model): {k.replace('_', ' ')}") for k, unit in DATASHEET_KEYS.items()}},
    "plant": {"preset": Key("", "as [motor] preset", "[motor]", "the simulated motor, when it is not the model"),
              **_MOTOR, "scale": Key("", "table of factors in (0, 1000] on R, L, Km, J, B", "-",
                                     "the simulated motor's parameters as factors on [motor]'s"),
              **_EFFECTS},
    "plan": {
        "planner": Key("", ", ".join(f'"{p}"' for p in PLANNERS), '"rest_to_rest"',
                       "how the move is planned (required with waypoints)"),
        **{k: _q(kind, getattr(PAPER_PLAN, k), doc) for k, kind, doc in (
            ("theta1", "angle", "rest_to_rest: start angle"), ("theta2", "angle", "rest_to_rest: end angle"),
            ("rho1", "current", "rest_to_rest: start current magnitude"),
            ("rho2", "current", "rest_to_rest: end current magnitude"),
            ("t0", "time", "when the move (or the sequence) starts; 0 for the waypoint planners"),
            ("tf", "time", "rest_to_rest: when the move ends, > t0"))},
        "waypoints": Key("rad", f"list of 2 to {MAX_OPTIMAL_MOVES + 1} angles or tables {{theta, velocity, dwell}}",
                         "-", "the angles to pass, in order; velocity [rad/s] (hermite, spline: at a via point; "
                              "none: the planner's choice), dwell [s] (a rest there)"),
        "through": Key("", "true, false", "false", "time_optimal: pass a waypoint at speed where the motion keeps "
                                                     "its direction"),
        "field_weakening": Key("", "true, false", "false", "time_optimal: one move in the d-q flat outputs with "
                                                             "field weakening, tracked by a dq_smc controller type"),
        "voltage": Key("", '"phase", "vector"', '"phase"', "time_optimal with field_weakening: the bus limit on "
                                                           "each phase or on the voltage vector"),
        "rho": Key("A", "> 0", "0.5", "psi, hermite, spline, scurve: the constant current magnitude"),
        "durations": Key("s", "list of one duration > 0 per move", "-",
                         "psi, hermite, spline: each move's duration (or caps)"),
        "caps": Key("", "table {speed_max [rad/s], accel_max [rad/s^2], jerk_max [rad/s^3]}, each > 0", "-",
                    "psi, hermite, spline, scurve: the caps that set the durations not given (scurve needs them)"),
    },
    "limits": {k: Key(*_LIMIT_DOCS[k][:2], _fmt(_default(MotorLimits, k)), _LIMIT_DOCS[k][2])
               for k in _LIMIT_DOCS},
    "controller": {
        "type": Key("", ", ".join(f'"{c}"' for c in CONTROLLER_TYPES) + ", or law+option+...",
                    f'"{DEFAULT_TYPE}"; "{DEFAULT_TYPE_TORQUES}" with [feedforward]; "{DEFAULT_TYPE_CONTINUOUS}" '
                    "without [drive] control_rate",
                    "the controller by name (flatstep.control.spec: each name is a law and its options; the default "
                    "is the law docs/comparison.md recommends)"),
        "law": Key("", ", ".join(f'"{c}"' for c in LAWS), "the default type's law",
                   "the control law, with the options below (instead of type); options without a law are set over "
                   "the default type's law and options, and one that law does not take is refused"),
        **{k: Key("", ", ".join(f'"{v}"' for v in opt.values) if opt.values else "true, false",
                  f'"{opt.values[0]}"' if opt.values else "false", f"with law: {opt.doc} ({', '.join(opt.laws)})")
           for k, opt in OPTIONS.items()},
        "bandwidth_scale": _q("scale", 1.0, "multiplies every bandwidth of a baseline"),
        "lambda_ts": Key("", "(0, 1]", "0.3 (0.15 with compute_delay)",
                         "every law: the current loop's speed times the control period (a baseline's current "
                         "bandwidth, a sliding law's W/eps)"),
        "current_bandwidth": Key("rad/s", "> 0", "lambda_ts / Ts", "cascade, microstep: the current loops' bandwidth"),
        "position_bandwidth": Key("rad/s", "> 0", "lambda / 4",
                                  "cascade: w of the rule k_theta = w/3, k_omega = 2.25 w, ki_omega = 0.75 w^2"),
        "k_theta": Key("1/s", "> 0", "w / 3", "cascade: position gain"),
        "k_omega": Key("1/s", "> 0", "2.25 w", "cascade: velocity gain"),
        "ki_omega": Key("1/s^2", ">= 0", "0.75 w^2", "cascade: velocity integral gain"),
        "decoupling": Key("", "true, false", "true", "cascade: cancel the axes' coupling and the back EMF"),
        "p3": Key("rad/s", "> 0", "lambda", "exact_linearization: the angle error's real pole"),
        "pd": Key("rad/s", "> 0", "lambda", "exact_linearization: the d current's pole"),
        "measurement": Key("", ", ".join(f'"{m}"' for m in MEASUREMENTS), "what the drive gives",
                           "where the law's speed and acceleration come from (observer with an observer, model with "
                           "sensors, else ideal)"),
        **{k: _q("gain", _default(SMCGains, k), f"the sliding law's {k}") for k in ("W1", "W2", "eps1", "eps2")},
        "wn": _q("gain", _default(SMCGains, "wn"), "the theta error dynamics' natural frequency (sliding laws; "
                 "exact_linearization: lambda / 4 by rule)"),
        "xi": _q("damping", _default(SMCGains, "xi"), "damping of the theta error dynamics (exact_linearization: 0.9 "
                 "by rule)"),
        "hold_damping": _q("damping", None, "from tf on, hold the target's detent with this damping (none: track)"),
        "design": Key("", "true, false", "false", "design the gains for the drive (needs [drive] control_rate)"),
        "uncertainty": _q("relative", 0.1, "the relative parameter error the design allows"),
        "weakening": Key("A s/rad", ">= 0", "0", "d-q types: field weakening slope"),
        "weakening_speed": Key("rad/s", ">= 0", "0", "d-q types: speed above which the d current weakens"),
        "rho_margin": Key("rad", "(0, pi/2)", "0.785398", "smc_la types: the loss-aware rho*'s angle margin"),
        "rho_hold": Key("A", "> 0", "half the smaller of rho1, rho2", "smc_la types: the held current"),
    },
    "drive": {
        "control_rate": _q("rate", None, "the sampled controller's rate (none: continuous-time control, as in the "
                                         "paper; needed by every other [drive] key, [sensors] and [observer])"),
        "substeps": _i("substeps", 4, "plant integration steps per control period"),
        "compute_delay": Key("", "true, false", "false", "apply each period's voltages one period late"),
        "v_bus": _q("v_bus", _default(Drive, "v_bus"), "the bus voltage: the drive saturates each phase at it, the "
                                                       "design and the planners read it (required with [limits])"),
        "pwm": Key("", ", ".join(f'"{m}"' for m in PWM_MODES), _fmt(_default(Drive, "pwm")), "the drive's PWM model"),
        "f_pwm": _q("rate", _default(Drive, "f_pwm"), "switched PWM: the PWM frequency"),
        "dead_time": Key("s", "[0, half a PWM period)", _fmt(_default(Drive, "dead_time")), "switched PWM: dead time"),
    },
    "sensors": {
        "encoder_counts": _i("encoder_counts", _default(Sensors, "encoder_counts"), "counts per revolution"),
        "encoder_offset": Key("counts", "[-0.5, 0.5)", _fmt(_default(Sensors, "encoder_offset")),
                              "where the count edges sit"),
        "current_bits": _i("current_bits", _default(Sensors, "current_bits"), "current ADC bits"),
        "current_range": _q("current_range", _default(Sensors, "current_range"), "current ADC full scale"),
        "current_offset": Key("A", "two offsets [ia, ib], each in [-1000, 1000]",
                              _fmt(_default(Sensors, "current_offset")), "current sensor offsets"),
        "current_noise": _q("current_noise", _default(Sensors, "current_noise"), "current noise standard deviation"),
        "delay": _i("delay", _default(Sensors, "delay"), "measurement delay in control periods"),
        "seed": _i("seed", _default(Sensors, "seed"), "the noise's seed"),
        "edge_timing": Key("", "true, false", _fmt(_default(Sensors, "edge_timing")),
                           "the encoder latches its last count edge's time (a capture timer); the observer corrects "
                           "with that edge's angle"),
    },
    "observer": {"bandwidth": _q("bandwidth", _default(Observer, "bandwidth"), "the observer's bandwidth"),
                 "load_states": _i("load_states", _default(Observer, "load_states"), "load states estimated"),
                 "torque_ramp": Key("", "true, false", _fmt(_default(Observer, "torque_ramp")),
                                    "predict with the torque ramping over the period by its last change")},
    "load": {"torque": _q("load", 0.0, "a constant load torque on the plant")},
    "feedforward": {
        **{k: Key("N m", ">= 0", _fmt(_default(TorqueModel, k)), doc) for k, doc in (
            ("detent_torque", "known detent amplitude"), ("coulomb_torque", "known Coulomb friction"),
            ("load_step", "known load step"))},
        "detent_harmonic": Key("", "integer >= 1", _fmt(_default(TorqueModel, "detent_harmonic")),
                               "the detent's harmonic of Nr theta"),
        "detent_phase": Key("rad", "finite", _fmt(_default(TorqueModel, "detent_phase")), "the detent's phase"),
        "coulomb_speed": Key("rad/s", "> 0", _fmt(_default(TorqueModel, "coulomb_speed")),
                             "the known friction's speed scale"),
        "load": Key("N m", "finite", _fmt(_default(TorqueModel, "load")), "known constant load"),
        "load_t0": Key("s", "finite", _fmt(_default(TorqueModel, "load_t0")), "when the known load step starts"),
        "load_tf": Key("s", "finite", _fmt(_default(TorqueModel, "load_tf")), "when the known load step ends"),
    },
    "robustness": {
        "relative_error": Key("", "(0, 0.5)", "0.1", "the parameter error of the study"),
        "parameters": Key("", "non-empty list of distinct names among R, L, Km, J, B", '["R", "L", "Km", "J", "B"]',
                          "the parameters that err"),
        "samples": _i("samples", 0, "0: every sign combination; else random plants"),
        "seed": _i("seed", 0, "the random plants' seed"),
    },
}

#: The [plan] keys each planner takes.
PLANNER_KEYS: dict[str, tuple[str, ...]] = {
    "rest_to_rest": ("planner", "theta1", "theta2", "rho1", "rho2", "t0", "tf"),
    "time_optimal": ("planner", "waypoints", "t0", "through", "field_weakening", "voltage"),
    "psi": ("planner", "waypoints", "t0", "rho", "durations", "caps"),
    "hermite": ("planner", "waypoints", "t0", "rho", "durations", "caps"),
    "spline": ("planner", "waypoints", "t0", "rho", "durations", "caps"),
    "scurve": ("planner", "waypoints", "t0", "rho", "caps"),
}
#: The keys of [plan] caps, and their old names.
CAPS = ("speed_max", "accel_max", "jerk_max")
OLD_CAPS = {"v_max": "speed_max", "a_max": "accel_max", "j_max": "jerk_max"}
_BUS = "the bus voltage has one name, [drive] v_bus (beside [drive] control_rate): rename it"
#: Old names, ``(table, key)`` (``"*"``: any table), and what to write instead.
RENAMED: dict[tuple[str, str], str] = {
    ("limits", "v_bus"): "the bus voltage moved to [drive] v_bus (beside [drive] control_rate): move it there",
    **{("*", k): _BUS for k in ("v_limit", "v_max", "v_hold", "c_v_limit")},
    ("", "simulate"): "the [simulate] table is gone: its control_rate is [drive] control_rate, its t_after is "
                      "the top-level t_end (the horizon from t = 0: the plan's end + t_after)",
}


def markdown_reference() -> str:
    """docs/scenario-reference.md: every table and key with its unit, valid values, default and meaning."""
    lines = ["# Scenario file reference", "",
             "Generated by `tools/gen_scenario_reference.py` from `flatstep.studies.scenario_keys`; "
             "`tests/test_scenario_reference.py` checks that this page matches the code. docs/planning.md and the "
             "files in examples/ show the format at work.", "",
             "One TOML format for every command that takes a file (`flatstep simulate`, `plan`, `compare`, "
             "`robustness`, `calibrate`, `design`, `identify`). Every table is optional. A key not listed here is "
             "refused, and so is a key the chosen planner does not take; a bad value is refused with "
             "`file:table.key`, the value, why and what is valid (exit 2, nothing is run).", "",
             f"Without `[motor]` the motor is the preset `\"{DEFAULT_MOTOR}\"` (the paper's), for the paper's "
             "rest_to_rest move; a file with `waypoints` must give `[motor]`.", "",
             "## Planners and their `[plan]` keys", "", "| planner | keys |", "|---|---|"]
    lines += [f"| `{p}` | {', '.join(f'`{k}`' for k in keys)} |" for p, keys in PLANNER_KEYS.items()]
    lines += ["", "`rest_to_rest` is the planner when `planner` is not given (the paper's move: its keys default to "
              "Fig. 1's). `time_optimal` needs `[limits]`; `[limits]` needs `[drive] v_bus` (the planner and the "
              "margins read the bus there)."]
    for table, keys in KEYS.items():
        lines += ["", f"## {'The top level' if not table else f'[{table}]'}", "",
                  "| key | unit | valid | default | meaning |", "|---|---|---|---|---|"]
        lines += [f"| `{k}` | {key.unit} | {key.valid} | {key.default} | {key.doc} |" for k, key in keys.items()]
    lines += ["", "## Old names", "", "A file that uses an old name is refused with its new one:", "",
              "| old | new |", "|---|---|"]
    names = {"": "[{k}]", "*": "{k} (in any table)"}
    lines += [f"| `{names.get(t, '[' + t + '] {k}').format(k=k)}` | {why} |" for (t, k), why in RENAMED.items()]
    lines += [f"| `[plan] caps.{old}` | `caps.{new}` |" for old, new in OLD_CAPS.items()]
    lines += ["| `[plan] waypoints` without `planner` | give `planner` (plan files planned `\"time_optimal\"`) |",
              "| `[plan] waypoints` without `[motor]` | give `[motor]` (plan files ran on `\"nema17\"`) |"]
    return "\n".join(lines) + "\n"
