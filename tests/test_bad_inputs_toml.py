"""Bad input in scenario files: every key refuses a bad value with a ValueError naming ``file:table.key`` and the value.

A table of (table, key, bad TOML value), each written into a file that is otherwise valid (a 20 kHz drive with
sensors where the table needs one).
"""
from __future__ import annotations

import sys

import pytest

from flatstep.studies.scenario_file import load_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: TOML values that are not numbers, or not finite
NOT_A_NUMBER = ["nan", "inf", "-inf", '"1.0"', "true", "[1.0]", "{ a = 1 }", "1979-05-27"]
#: integers' extra bad values
NOT_AN_INTEGER = ["1.5", "-1", "1e30"]
#: what each key refuses besides NOT_A_NUMBER
KEYS: dict[str, dict[str, list[str]]] = {
    "motor": {"R": ["0", "-8.4", "1e300"], "L": ["0.0", "-0.01", "1e300"], "Km": ["0", "-1"], "J": ["0", "-3.6e-6"],
              "B": ["-1e-4", "1e300"], "Nr": ["0", "-50", "50.5", "1e10", "10000000000"]},
    "plant": {"R": ["0", "-1"], "Km": ["-0.05"], "detent_torque": ["-1e-3", "1e300"], "coulomb_torque": ["-1"],
              "coulomb_speed": ["0", "-0.01"], "magnetizing_resistance": ["0", "-50"]},
    "plan": {"theta1": ["1e300"], "theta2": ["-1e300"], "rho1": ["0", "-0.4"], "rho2": ["0.0", "1e300"],
             "t0": ["-0.01", "1e300"], "tf": ["0.0", "0.01", "1e300"]},
    "controller": {"W1": ["0", "-100"], "W2": ["0"], "eps1": ["0", "-1"], "eps2": ["-0.005"], "xi": ["0", "-0.8"],
                   "wn": ["0", "-10"], "hold_damping": ["0", "-0.7"], "bandwidth_scale": ["0", "-1"],
                   "uncertainty": ["-0.1", "0.5", "2"]},
    "drive": {"control_rate": ["0", "-20000", "10", "1e12"], "substeps": ["0", "2.5", "1000000000"],
              "v_bus": ["0", "-24", "1e9"], "f_pwm": ["0", "-40000", "1e12"], "dead_time": ["-1e-6", "1.0"]},
    "sensors": {"encoder_counts": ["0", "3", "2.5", "1e12"], "current_bits": ["1", "64", "12.5"],
                "current_range": ["0", "-2"], "current_noise": ["-0.1"], "delay": ["-1", "1000000", "0.5"],
                "seed": ["-1", "1.5"], "encoder_offset": ["0.5", "-0.6"]},
    "observer": {"bandwidth": ["0", "-1500", "1e300"], "load_states": ["3", "-1", "1.5"]},
    "load": {"torque": ["1e300", "-1e300", "1e4"]},
    "robustness": {"relative_error": ["0", "0.5", "-0.1"], "samples": ["-1", "1.5", "1e9"], "seed": ["-1", "0.5"]},
    "": {"t_end": ["0", "-0.06", "0.03", "1e9", "1e300"]},
}
INTEGER_KEYS = {"Nr", "substeps", "encoder_counts", "current_bits", "delay", "seed", "load_states", "samples"}
#: keys whose value is not a number: their own bad values
OTHER: list[tuple[str, str, str]] = [
    ("motor", "preset", v) for v in ('"nema99"', "1", "true", '["paper"]')
] + [
    ("controller", "type", v) for v in ('"pid"', "1", "[]")
] + [
    ("controller", "measurement", v) for v in ('"perfect"', "1", "true")
] + [
    ("controller", "design", v) for v in ("1", '"yes"')
] + [
    ("drive", "pwm", v) for v in ('"pwm"', "1", "true")
] + [
    ("drive", "compute_delay", v) for v in ("1", '"yes"', "0")
] + [
    ("sensors", "edge_timing", v) for v in ("1", '"yes"')
] + [
    ("observer", "torque_ramp", v) for v in ("1", '"yes"')
] + [
    ("sensors", "current_offset", v) for v in ("[0.0]", "[0.0, nan]", '[0.0, "x"]', "0.1", "[0.0, 1e9]")
] + [
    ("robustness", "parameters", v) for v in ('"RL"', "[]", '["R", "Q"]', '["R", "R"]', "[1]", "5")
] + [
    ("", "name", v) for v in ("1", "[1]")
] + [
    ("plant", "scale", v) for v in ("{ R = 0 }", "{ R = -1.1 }", '{ R = "x" }', "{ Nr = 2 }", "1.1")
]
#: what a table needs to be valid around the bad key
CONTEXT = {"drive": "", "sensors": "[drive]\ncontrol_rate = 20000.0\n",
           "observer": "[drive]\ncontrol_rate = 20000.0\n[controller]\nmeasurement = \"observer\"\n"}
#: switched PWM so that f_pwm and dead_time are read
EXTRA = {("drive", "f_pwm"): "pwm = \"switched\"\n", ("drive", "dead_time"): "pwm = \"switched\"\n"}


def _cases() -> list[tuple[str, str, str]]:
    cases = []
    for table, keys in KEYS.items():
        for key, values in keys.items():
            extra = NOT_A_NUMBER + (NOT_AN_INTEGER if key in INTEGER_KEYS else [])
            cases += [(table, key, v) for v in dict.fromkeys(values + extra)]
    return cases + OTHER


CASES = _cases()


def _text(table: str, key: str, value: str) -> str:
    """A scenario file with ``key = value`` in ``[table]`` (or at the top level)."""
    if not table:
        return f"{key} = {value}\n"
    head = CONTEXT.get(table, "")
    rate = "control_rate = 20000.0\n" if table == "drive" and key != "control_rate" else ""
    return f"{head}[{table}]\n{rate}{EXTRA.get((table, key), '')}{key} = {value}\n"


@pytest.mark.parametrize("table, key, value", CASES, ids=[f"{t}.{k}={v}"[:50] for t, k, v in CASES])
def test_a_bad_value_names_the_file_table_key_and_value(tmp_path, table, key, value):
    """Each bad value is refused with a ValueError naming the file, the table.key and the value as written."""
    path = tmp_path / "bad.toml"
    path.write_text(_text(table, key, value))
    with pytest.raises(ValueError) as err:
        load_scenario(path)
    message = str(err.value)
    assert str(path) in message, message
    where = f"{table}.{key}" if table else key
    assert where in message or f"[{table}]" in message or (key == "t_end" and "t_end" in message), message
    shown = value.strip('"').replace(" ", "").lower()
    flat = message.replace(" ", "").lower()
    forms = {shown, shown.replace("e", "e+"), shown + ".0", shown.rstrip("0").rstrip(".")}
    parsed = tomllib.loads(f"v = {value}")["v"]
    items = parsed if isinstance(parsed, list) else list(parsed.values()) if isinstance(parsed, dict) else []
    for v in [parsed] + items:
        forms |= {repr(v).replace(" ", "").lower(), str(v).replace(" ", "").lower()}
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            forms.add(repr(float(v)))
    try:
        number = float(value)
        forms |= {repr(number).lower(), f"{number:g}", repr(int(number)) if number.is_integer() else ""}
    except ValueError:
        pass
    assert any(f and f in flat for f in forms) or key in ("tf", "t_end", "control_rate"), message


def test_the_table_is_large():
    """The table of bad values holds 300 cases or more."""
    assert len(CASES) >= 300


def test_a_valid_file_loads(tmp_path):
    """The context the cases use is valid on its own (so each case fails for its key only)."""
    for table in ("drive", "sensors", "observer"):
        path = tmp_path / f"{table}.toml"
        path.write_text(CONTEXT.get(table, "") + ("[drive]\ncontrol_rate = 20000.0\n" if table == "drive" else ""))
        scenario, _ = load_scenario(path)
        assert scenario.loop is not None and scenario.loop.control_period == pytest.approx(5e-5)
