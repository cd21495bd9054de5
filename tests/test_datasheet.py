"""A motor from its datasheet: the derivation, its conventions, the file keys, the refusals and ``flatstep motor``."""
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import flatstep as fs
from flatstep.model.datasheet import (
    B_DEFAULT,
    REQUIRED,
    from_datasheet,
    motor_from_table,
    rotor_teeth,
    torque_constant,
)
from flatstep.model.motor import torque
from flatstep.studies.scenario_file import read_scenario_file as load_plan_file
from flatstep.studies.scenario_file import load_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

MOTORS = sorted((Path(__file__).parent.parent / "examples" / "motors").glob("*.toml"))
# The user's NEMA 17: 1.68 A, 1.65 ohm, 2.8 mH, 0.44 N m holding, 68 g cm^2, 200 steps a turn.
NEMA17 = dict(step_angle=1.8, rated_current=1.68, holding_torque=0.44, resistance=1.65, inductance=2.8e-3,
              rotor_inertia=68e-7)
NEMA17_TOML = """[motor]
step_angle = 1.8
rated_current = 1.68
holding_torque = 0.44
resistance = 1.65
inductance = 2.8e-3
rotor_inertia = 68e-7
"""


def test_nema17_against_hand_computed_values():
    m = from_datasheet(**NEMA17)
    p = m.params
    # Km = 0.44 / (sqrt(2) * 1.68) = 0.44 / 2.375878785 = 0.185194633 N m/A, by hand
    assert p.Km == pytest.approx(0.185194633, rel=1e-8)
    assert (p.R, p.L, p.J, p.Nr) == (1.65, 2.8e-3, 68e-7, 50)
    assert p.B == B_DEFAULT == 1e-4
    assert m.rated_rho == pytest.approx(2.375878785, rel=1e-9)
    assert m.rated_torque == pytest.approx(0.44, rel=1e-12)
    assert m.time_constant == pytest.approx(2.8e-3 / 1.65)
    assert m.electrical_hz_per_rad_s == pytest.approx(50 / (2 * math.pi))
    assert m.back_emf_per_rad_s == p.Km
    assert fs.MotorParams.from_datasheet(**NEMA17) == p


def test_km_reproduces_the_holding_torque_through_the_model_torque():
    """Both phases at rated DC current: the peak of eq. (1)'s torque over theta is the datasheet's holding torque."""
    m = from_datasheet(**NEMA17)
    current = NEMA17["rated_current"]
    theta = np.linspace(0.0, 2 * math.pi / m.params.Nr, 20001)
    two = torque(np.array([np.full_like(theta, -current), np.full_like(theta, current), 0 * theta, theta]), m.params)
    one = torque(np.array([0 * theta, np.full_like(theta, current), 0 * theta, theta]), m.params)
    assert two.max() == pytest.approx(0.44, rel=1e-7)
    assert one.max() == pytest.approx(0.44 / math.sqrt(2), rel=1e-7)  # one phase: 1/sqrt(2) of it


def test_the_sqrt2_of_two_phases_symbolically():
    Km, current, x = sp.symbols("K_m I x", positive=True)
    tau = Km * (current * sp.cos(x) + current * sp.sin(x))  # ia = -I, ib = I in eq. (1)'s torque, x = Nr theta
    peak = sp.simplify(tau.subs(x, sp.solve(sp.diff(tau, x), x)[0]))
    assert sp.simplify(peak - sp.sqrt(2) * Km * current) == 0
    hold = sp.Symbol("T", positive=True)  # Km = T / (sqrt(2) I) puts the peak back at the holding torque
    assert sp.simplify(peak.subs(Km, hold / (sp.sqrt(2) * current)) - hold) == 0
    km, rho = torque_constant(0.44, 1.68)
    assert float((hold / (sp.sqrt(2) * current)).subs({hold: 0.44, current: 1.68})) == pytest.approx(km, rel=1e-14)
    assert rho == pytest.approx(float(sp.sqrt(2) * 1.68), rel=1e-14)


@pytest.mark.parametrize("current, phases, km, rho", [
    ("rms", 2, 0.44 / (math.sqrt(2) * 1.68), math.sqrt(2) * 1.68),
    ("peak", 2, 0.44 / 1.68, 1.68),
    ("rms", 1, 0.44 / 1.68, math.sqrt(2) * 1.68),         # one-phase figure: sqrt(2) x it is the two-phase one
    ("peak", 1, math.sqrt(2) * 0.44 / 1.68, 1.68),
])
def test_current_and_phase_conventions(current, phases, km, rho):
    assert torque_constant(0.44, 1.68, current=current, holding_torque_phases=phases) == pytest.approx((km, rho))
    m = from_datasheet(**NEMA17, current=current, holding_torque_phases=phases)
    assert m.params.Km == pytest.approx(km)
    assert m.defaults == {"holding_torque_rating": "typical", "viscous_friction": 1e-4}


def test_defaults_are_said_and_given_values_are_not_defaulted():
    m = from_datasheet(**NEMA17)
    assert m.defaults == {"current": "rms", "holding_torque_phases": 2, "holding_torque_rating": "typical",
                          "viscous_friction": 1e-4}
    defaulted = {a.parameter for a in m.assumptions if a.defaulted}
    assert defaulted == {"i_max", "Km", "B"}
    given = from_datasheet(**NEMA17, viscous_friction=3e-4, current="rms", holding_torque_phases=2,
                           holding_torque_rating="minimum")
    assert given.defaults == {} and given.params.B == 3e-4
    assert not any(a.defaulted for a in given.assumptions)
    assert any("minimum" in a.what and "lower bound" in a.what for a in given.assumptions)
    uncertain = {a.parameter: a.relative for a in m.assumptions if a.relative is not None}
    assert uncertain == {"Km": 0.10, "R": 0.10, "L": 0.20}


@pytest.mark.parametrize("angle, teeth", [(1.8, 50), (0.9, 100), (7.5, 12), (3.6, 25), (90.0, 1)])
def test_rotor_teeth(angle, teeth):
    assert rotor_teeth(angle) == teeth


@pytest.mark.parametrize("angle, match", [(1.7, "not a whole number"), (0.0, "out of range"), (-1.8, "out of range"),
                                          (float("nan"), "not finite"), (True, "not a number"),
                                          (0.05, "Nr = 90/step_angle")])
def test_rotor_teeth_refusals(angle, match):
    with pytest.raises(ValueError, match=match):
        rotor_teeth(angle)


def test_nema17_preset_is_the_beckhoff_datasheet():
    """The preset's comment says how it was derived; the derivation and the example file give it exactly."""
    path = [p for p in MOTORS if p.name == "beckhoff-as1010-0000.toml"][0]
    table = tomllib.loads(path.read_text())["motor"]
    assert motor_from_table(table, str(path)).params == fs.MotorParams.preset("nema17")


@pytest.mark.parametrize("change, match", [
    ({"holding_torque": 0.0}, "holding_torque=0.0 N m must be > 0"),
    ({"rated_current": -1.0}, "rated_current=-1.0 A is out of range"),
    ({"resistance": float("inf")}, "resistance=inf is not finite"),
    ({"inductance": "2.8 mH"}, "inductance='2.8 mH' is not a number"),
    ({"rotor_inertia": 1e3}, "rotor_inertia=1000.0 kg m.2 is out of range"),
    ({"current": "avg"}, r"current='avg' is not one of \['rms', 'peak'\]"),
    ({"holding_torque_phases": 3}, "holding_torque_phases=3 must be an integer in"),
    ({"holding_torque_rating": "max"}, "holding_torque_rating='max' is not one of"),
    ({"viscous_friction": -1e-4}, "viscous_friction=-0.0001 N m s/rad is out of range"),
    ({"holding_torque": 500.0, "rated_current": 1e-5}, "Km = .* derived from holding_torque"),
])
def test_api_refusals_name_the_key(change, match):
    with pytest.raises(ValueError, match=match):
        from_datasheet(**{**NEMA17, **change})


@pytest.mark.parametrize("change, match", [
    ({"Km": 0.2}, r"f.toml:motor: the datasheet keys \[.*\] and the model keys \['Km'\] cannot be mixed"),
    ({"preset": "nema17"}, r"model keys \['preset'\] cannot be mixed"),
    ({"holding_torque": True}, r"f.toml:motor.holding_torque: holding_torque=True is not a number"),
    ({"current": "peak-to-peak"}, r"f.toml:motor.current: current='peak-to-peak' is not one of"),
    ({"step_angle": 1.7}, r"f.toml:motor.step_angle: step_angle=1.7 deg gives Nr"),
    ({"inertia": 1e-6}, r"f.toml:motor: unknown key\(s\) \['inertia'\]; valid datasheet keys"),
    ({"maker": 3}, r"f.toml:motor.maker: maker=3 must be a string"),
])
def test_table_refusals_name_file_and_key(change, match):
    with pytest.raises(ValueError, match=match):
        motor_from_table({**NEMA17, **change}, "f.toml")


@pytest.mark.parametrize("key", REQUIRED)
def test_a_missing_required_key_is_named(key):
    table = {k: v for k, v in NEMA17.items() if k != key}
    with pytest.raises(ValueError, match=rf"f.toml:motor: the datasheet key\(s\) \['{key}'\] are missing"):
        motor_from_table(table, "f.toml")


def test_scenario_file_takes_the_datasheet_keys(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(NEMA17_TOML + "[plan]\nrho1 = 1.0\nrho2 = 1.0\n")
    scenario, _ = load_scenario(path)
    assert scenario.motor == from_datasheet(**NEMA17).params
    path.write_text(NEMA17_TOML + "R = 1.0\n")
    with pytest.raises(ValueError, match=r"s.toml:motor: the datasheet keys .* and the model keys \['R'\]"):
        load_scenario(path)
    path.write_text(NEMA17_TOML.replace("holding_torque = 0.44", "holding_torque = -0.44"))
    with pytest.raises(ValueError, match=r"s.toml:motor.holding_torque: holding_torque=-0.44 N m is out of range"):
        load_scenario(path)


def test_plan_file_takes_the_datasheet_keys(tmp_path):
    text = (Path(__file__).parent.parent / "examples" / "plans" / "hermite-via.toml").read_text()
    path = tmp_path / "p.toml"
    path.write_text(text.replace('[motor]\npreset = "nema17"\n', NEMA17_TOML))
    assert load_plan_file(path).motor == from_datasheet(**NEMA17).params
    path.write_text(text.replace('[motor]\npreset = "nema17"\n', NEMA17_TOML + 'preset = "nema17"\n'))
    with pytest.raises(ValueError, match=r"p.toml:motor: the datasheet keys .* and the model keys \['preset'\]"):
        load_plan_file(path)


def test_example_motors_are_enough_and_cited():
    assert len(MOTORS) >= 33
    makers = {tomllib.loads(p.read_text())["motor"]["maker"] for p in MOTORS}
    assert len(makers) >= 7


@pytest.mark.parametrize("path", MOTORS, ids=[p.stem for p in MOTORS])
def test_every_example_motor_loads_and_is_in_range(path):
    table = tomllib.loads(path.read_text())["motor"]
    assert set(table) >= {"maker", "part", "source", *REQUIRED}
    assert "http" in table["source"]
    m = motor_from_table(table, str(path))
    assert 0.4 <= table["rated_current"] <= 2.8 and 0.7 <= table["resistance"] <= 30.0
    p = m.params
    assert p.Nr in (50, 100) and 2e-4 < p.L / p.R < 2e-2     # 1.8/0.9 deg; 0.2-20 ms: a winding, not a unit slip
    assert 1e-7 < p.J < 1e-3 and 0.05 < p.Km < 5.0            # 1-10000 g cm^2; N m/A
    assert m.rated_torque == pytest.approx(table["holding_torque"], rel=1e-12)


def test_cli_prints_the_model_assumptions_and_defaults(cli, tmp_path):
    (tmp_path / "m.toml").write_text(NEMA17_TOML)
    run = cli(["motor", "m.toml", "--v-bus", "24"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    out = run.stdout
    assert "Km     0.185195 N m/A" in out and "L/R                               1.697 ms" in out
    assert "7.958 Hz per rad/s" in out and "2.376 A (i_max of a plan's [limits])" in out
    assert "129.6 rad/s" in out                                   # 24 V / 0.1852 V s/rad
    assert "+-10% (datasheet tolerance of the holding torque)" in out and "B [defaulted]" in out
    assert ('defaulted (not in the file): current = "rms", holding_torque_phases = 2, holding_torque_rating = '
            '"typical", viscous_friction = 0.0001') in out


def test_cli_json(cli, tmp_path):
    (tmp_path / "m.toml").write_text(NEMA17_TOML + "viscous_friction = 2e-4\n")
    run = cli(["motor", "m.toml", "--json"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    d = json.loads(run.stdout)
    assert d["params"]["Km"] == pytest.approx(0.185194633) and d["params"]["B"] == 2e-4
    assert d["derived"]["rated_rho"] == pytest.approx(2.375878785)
    assert "viscous_friction" not in d["defaults"] and d["defaults"]["current"] == "rms"
    assert {a["parameter"] for a in d["assumptions"]} >= {"Km", "R", "L", "J", "B", "Nr", "i_max"}


def test_cli_model_keys_and_refusals(cli, tmp_path):
    (tmp_path / "preset.toml").write_text('[motor]\npreset = "paper"\nB = 2e-4\n')
    run = cli(["motor", "preset.toml"], cwd=tmp_path)
    assert run.returncode == 0 and "given as model parameters" in run.stdout and "preset 'paper'" in run.stdout
    (tmp_path / "mixed.toml").write_text(NEMA17_TOML + "Km = 0.2\n")
    (tmp_path / "bad.toml").write_text(NEMA17_TOML.replace("1.65", "-1.65"))
    (tmp_path / "none.toml").write_text("[plan]\nrho1 = 1.0\n")
    (tmp_path / "part.toml").write_text("[motor]\nR = 1.0\n")
    for name, match in [("mixed.toml", "mixed.toml:motor: the datasheet keys"),
                        ("bad.toml", "bad.toml:motor.resistance: resistance=-1.65 ohm is out of range"),
                        ("none.toml", "none.toml: no [motor] table"),
                        ("part.toml", "part.toml:motor: ['L', 'Km', 'J', 'B', 'Nr'] missing"),
                        ("missing.toml", "missing.toml: no such scenario file")]:
        run = cli(["motor", name], cwd=tmp_path)
        assert run.returncode == 2 and match in run.stderr and "Traceback" not in run.stderr, (name, run.stderr)
        assert run.stdout == ""
    run = cli(["motor", "preset.toml", "--v-bus", "-24"], cwd=tmp_path)
    assert run.returncode == 2 and "--v-bus" in run.stderr


def test_cli_several_files_one_row_each(cli, tmp_path):
    run = cli(["motor", *MOTORS])
    assert run.returncode == 0, run.stderr
    rows = run.stdout.splitlines()
    assert len(rows) == len(MOTORS) + 1
    as1010 = [r for r in rows if r.startswith("beckhoff-as1010-0000.toml")][0].split()
    assert as1010[1:10] == ["1", "4.1", "9.5", "0.38", "56", "0.2687", "2.32", "1.41", "50"]
    (tmp_path / "bad.toml").write_text(NEMA17_TOML.replace("step_angle = 1.8", "step_angle = 1.7"))
    run = cli(["motor", MOTORS[0], tmp_path / "bad.toml"])
    assert run.returncode == 2 and run.stdout == "" and "bad.toml:motor.step_angle: step_angle=1.7 deg" in run.stderr
