"""Bad input at the command line: exit code 2, one line naming the flag or key and the value, never a traceback.

The cases run in this process through ``flatstep.cli.main.main`` (the ``cli`` fixture's runner, no interpreter
start-up per case), all in one fixture; each parametrized test checks its own case. test_cli.py keeps the few
subprocess smoke tests (the installed entry point, signals).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from conftest import run_cli

SIM_FLAGS = ["--theta1", "--theta2", "--rho1", "--rho2", "--t0", "--tf", "--t-end", "--load-torque", "--W1", "--W2",
             "--eps1", "--eps2", "--xi", "--wn", "--hold-damping"]
NOT_A_NUMBER = ["nan", "inf", "-inf", "abc", "1e400", "", "0x10", "1,5"]
#: (flag, values out of its range)
SIM_RANGES = [("--rho1", ["0", "-1", "1e300"]), ("--rho2", ["0", "-0.4"]), ("--t0", ["-0.01", "1e300"]),
              ("--tf", ["1e300", "0.01", "-1"]), ("--t-end", ["0", "-1", "0.03", "1e9"]),
              ("--load-torque", ["1e300", "-1e300", "1e4"]), ("--theta1", ["1e300"]), ("--theta2", ["-1e300"]),
              ("--W1", ["0", "-100"]), ("--W2", ["0"]), ("--eps1", ["-1"]), ("--eps2", ["0"]), ("--xi", ["0", "-1"]),
              ("--wn", ["0"]), ("--hold-damping", ["0", "-0.7"])]
DESIGN = [("--control-rate", ["0", "-20000", "nan", "abc", "1e12", "inf", ""]),
          ("--v-bus", ["0", "-24", "inf", "x", "nan", ""]), ("--current-range", ["0", "-2", "nan", "inf"]),
          ("--uncertainty", ["-0.1", "0.5", "nan", "2", "inf"]), ("--load-torque", ["nan", "1e300", "inf", "x"]),
          ("--encoder-counts", ["0", "3", "1.5", "abc", "-16384", ""]), ("--current-bits", ["1", "64", "12.5", "x"])]


CALIBRATE = [("--periods", ["0", "-1", "1e9", "abc", "100000"]), ("--harmonic", ["0", "2.5", "x"]),
             ("--coulomb-speed", ["0", "-1", "nan"]), ("--noise", ["-1", "nan", "x"]),
             ("--controller", ["smc_ff", "pid"])]
#: (plan file key, bad value, what the error must show)
PLAN_CASES = [("waypoints", "[0.0, nan]", "nan"), ("waypoints", "[0.0]", "1 waypoint"),
              ("waypoints", "[]", "0 waypoint"),
              ("waypoints", "[0.0, 1e9]", "1000000000.0"), ("waypoints", '[0.0, "x"]', "'x'"),
              ("waypoints", "[0.0, 1e-9]", "1e-09"), ("waypoints", "[0.0, 1e5]", "100000"),
              ("waypoints", "[0.0, {theta = 1.0, dwell = -1}]", "dwell=-1.0"),
              ("waypoints", "[0.0, {theta = 1.0, dwell = 1e9}]", "dwell=1000000000.0"),
              ("waypoints", "5.0", "waypoints"), ("planner", '"bogus"', "'bogus'"), ("t0", "-1", "t0=-1.0"),
              ("t0", "nan", "t0=nan"), ("t0", "true", "t0=True"),
              ("waypoints", "[" + ", ".join(str(float(i % 2)) for i in range(1010)) + "]", "1009 moves"),
              ("waypoints", '[0.0, "1.0"]', "'1.0'"), ("waypoints", "[0.0, true]", "True"),
              ("caps", "{speed_max = 1.0, accel_max = 1.0, jerk_max = 1.0}", "does not take caps"),
              ("through", '"yes"', "through='yes'")]


#: (scenario file text, what the error must show), run through ``flatstep simulate``
SIM_FILES = [(f"[{t}]\n{k} = {v}\n", f"{t}.{k}") for t, k, v in [
    ("motor", "R", "nan"), ("motor", "L", "-1"), ("motor", "Km", '"0.05"'), ("motor", "J", "true"),
    ("motor", "B", "[1]"),
    ("motor", "Nr", "50.5"), ("plan", "rho1", "0"), ("plan", "theta2", "inf"), ("plan", "tf", "1e300"),
    ("controller", "W1", "-1"), ("controller", "xi", "0"), ("controller", "measurement", '"perfect"'),
    ("load", "torque", "1e300"), ("load", "torque", '"1e-5"'), ("plant", "detent_torque", "-1"),
    ("plant", "coulomb_speed", "0"), ("robustness", "relative_error", "0.7")]] + [
    ("[drive]\ncontrol_rate = 20000.0\n" + (f"[{t}]\n" if t != "drive" else "") + f"{k} = {v}\n", f"{t}.{k}")
    for t, k, v in [
        ("drive", "v_bus", "0"), ("drive", "substeps", "0"), ("drive", "f_pwm", "1e12"), ("drive", "pwm", '"pwm"'),
        ("drive", "compute_delay", "1"), ("sensors", "encoder_counts", "3"), ("sensors", "current_bits", "64"),
        ("sensors", "delay", "-1"), ("sensors", "seed", "1.5"), ("sensors", "current_noise", "-1"),
        ("observer", "load_states", "3"), ("observer", "bandwidth", "0")]]


def _plan_file(key: str, value: str) -> str:
    """A time-optimal waypoint plan on the NEMA 17 preset with ``key = value`` in its [plan] table."""
    plan = {"planner": '"time_optimal"', "waypoints": "[0.0, 2.0]"}
    plan[key] = value
    body = "".join(f"{k} = {v}\n" for k, v in plan.items())
    return (f"[motor]\npreset = \"nema17\"\n[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n[limits]\ni_max = 1.0\n"
            f"[plan]\n{body}")


def _named(flag: str) -> tuple[str, str]:
    """A flag's error names it as the flag or as its keyword (``--t-end`` or ``t_end``): either will do."""
    return flag, flag.lstrip("-").replace("-", "_")


def _cases(tmp: Path) -> list[tuple[str, list[str], int, list[str]]]:
    """(id, argv, exit code, strings stderr must contain)."""
    cases = []
    for flag in SIM_FLAGS:
        for v in NOT_A_NUMBER:
            cases.append((f"simulate {flag}={v!r}", ["simulate", f"{flag}={v}"], 2, [flag]))
    for flag, values in SIM_RANGES:
        for v in values:
            cases.append((f"simulate {flag}={v}", ["simulate", f"{flag}={v}"], 2, [_named(flag)]))
    cases += [
        ("t0 after tf", ["simulate", "--t0", "0.05"], 2, ["tf=0.04", "t0=0.05"]),
        ("t_end before tf", ["simulate", "--tf", "0.05", "--t-end", "0.045"], 2, ["t_end=0.045"]),
        ("x0 nan", ["simulate", "--x0", "nan", "0", "0", "0"], 2, ["x0=", "nan"]),
        ("x0 huge", ["simulate", "--x0", "1e300", "0", "0", "0"], 2, ["x0=", "1e+300"]),
        ("x0 three", ["simulate", "--x0", "0", "0", "0"], 2, ["--x0"]),
        ("x0 word", ["simulate", "--x0", "a", "0", "0", "0"], 2, ["--x0", "'a'"]),
        ("measurement", ["simulate", "--measurement", "perfect"], 2, ["'perfect'"]),
        ("missing file", ["simulate", str(tmp / "missing.toml")], 2, ["missing.toml", "no such"]),
        ("directory", ["simulate", str(tmp)], 2, [str(tmp), "directory"]),
        ("binary file", ["simulate", str(tmp / "binary.toml")], 2, ["binary.toml", "UTF-8"]),
        ("bad toml", ["simulate", str(tmp / "broken.toml")], 2, ["broken.toml", "not valid TOML"]),
        ("out is a file", ["simulate", "--out", str(tmp / "afile")], 2, ["--out", "afile", "not a directory"]),
        ("file and flags", ["simulate", str(tmp / "rate10.toml"), "--tf", "0.05"], 2, ["--tf"]),
        ("slow control", ["simulate", str(tmp / "rate10.toml")], 2, ["rate10.toml:drive.control_rate"]),
        ("bool rate", ["simulate", str(tmp / "boolrate.toml")], 2, ["drive.control_rate", "True"]),
        ("string bus", ["simulate", str(tmp / "vbus.toml")], 2, ["drive.v_bus", "'24'"]),
        ("huge horizon", ["simulate", str(tmp / "long.toml")], 2, ["long.toml:t_end", "1000000000.0"]),
        ("horizon cost", ["simulate", str(tmp / "costly.toml")], 2, ["integration steps", "MAX_STEPS"]),
        ("pwm cost", ["simulate", str(tmp / "pwm.toml")], 2, ["PWM periods"]),
        ("unknown key", ["simulate", str(tmp / "key.toml")], 2, ["key.toml", "'Rx'"]),
        ("no command", [], 2, ["COMMAND"]),
        ("unknown command", ["bogus"], 2, ["'bogus'"]),
        ("unknown flag", ["simulate", "--bogus", "1"], 2, ["--bogus"]),
        ("bench which", ["bench", "--which", "z"], 2, ["'z'"]),
        ("bench repeat", ["bench", "--repeat", "0"], 2, ["--repeat"]),
        ("bench repeat word", ["bench", "--repeat", "x"], 2, ["--repeat", "'x'"]),
        ("robustness missing", ["robustness", str(tmp / "missing.toml")], 2, ["missing.toml"]),
        ("robustness samples", ["robustness", str(tmp / "rate10.toml"), "--samples", "-1"], 2, ["--samples"]),
        ("robustness samples float", ["robustness", str(tmp / "rate10.toml"), "--samples", "1.5"], 2, ["'1.5'"]),
        ("robustness parameters", ["robustness", str(tmp / "params.toml")], 2, ["robustness.parameters", "'RL'"]),
        ("robustness negative", ["robustness", str(tmp / "samples.toml")], 2, ["robustness.samples", "-1"]),
        ("compare no drive", ["compare", str(tmp / "nodrive.toml")], 2, ["control_rate"]),
        ("compare controllers", ["compare", str(tmp / "drive.toml"), "--controllers", "pid"], 2, ["'pid'"]),
        ("compare band", ["compare", str(tmp / "drive.toml"), "--band", "-1"], 2, ["--band", "-1"]),
        ("compare band nan", ["compare", str(tmp / "drive.toml"), "--band", "nan"], 2, ["--band", "nan"]),
        ("compare scales", ["compare", str(tmp / "drive.toml"), "--scales", "a,b"], 2, ["--scales", "'a,b'"]),
        ("compare scales zero", ["compare", str(tmp / "drive.toml"), "--scales", "0"], 2, ["--scales"]),
        ("compare scales no baseline", ["compare", str(tmp / "drive.toml"), "--controllers", "smc,dq_smc", "--scales",
                                        "2"], 2, ["--scales", "'smc,dq_smc'", "cascade"]),
        ("compare samples", ["compare", str(tmp / "drive.toml"), "--samples", "-3"], 2, ["--samples", "-3"]),
        ("compare calibrate-each no sensors", ["compare", str(tmp / "drive.toml"), "--calibrate-each"], 2,
         ["--calibrate-each", "no [sensors]"]),
        ("compare calibrate-each nothing calibrated", ["compare", str(tmp / "nema.toml"), "--controllers",
                                                       "cascade,microstep", "--calibrate-each"], 2,
         ["--calibrate-each", "name none"]),
        ("compare calibrate-each value", ["compare", str(tmp / "nema.toml"), "--calibrate-each=yes"], 2,
         ["--calibrate-each"]),
        ("design no drive", ["design", str(tmp / "nodrive.toml")], 2, ["control_rate"]),
        ("compare python study", ["compare", str(tmp / "study.toml"), "--engine", "python"], 2,
         ["MAX_STEPS_REFERENCE"]),
        ("compare big study", ["compare", str(tmp / "study.toml"), "--samples", "100000"], 2, ["MAX_STUDY_STEPS"]),
        ("robustness big study", ["robustness", str(tmp / "study.toml"), "--samples", "100000"], 2,
         ["MAX_STUDY_STEPS"]),
        ("identify missing", ["identify", str(tmp / "missing.csv")], 2, ["missing.csv"]),
        ("identify directory out", ["identify", "--out", str(tmp), str(tmp / "missing.csv")], 2, ["--out"]),
        ("identify toml as csv", ["identify", str(tmp / "drive.toml")], 2, ["drive.toml"]),
        ("identify no mode", ["identify"], 2, ["--excite"]),
        ("identify seeds", ["identify", "--accuracy", str(tmp / "drive.toml"), "--seeds", "0"], 2, ["seeds=0"]),
        ("identify seed", ["identify", "--excite", str(tmp / "drive.toml"), "--seed", "-5"], 2, ["seed=-5"]),
        ("identify duration", ["identify", "--excite", str(tmp / "drive.toml"), "--duration", "1e9"], 2,
         ["duration=1000000000.0"]),
        ("identify duration nan", ["identify", "--excite", str(tmp / "drive.toml"), "--duration", "nan"], 2,
         ["duration=nan"]),
        ("identify noise", ["identify", "--accuracy", str(tmp / "drive.toml"), "--noise", "-1"], 2, ["--noise"]),
        ("identify nr", ["identify", "--nr", "0", str(tmp / "missing.csv")], 2, ["nr=0"]),
        ("identify confidence", ["identify", "--confidence", "2", str(tmp / "missing.csv")], 2, ["confidence=2.0"]),
        ("identify coulomb speed", ["identify", "--coulomb-speed", "-1", str(tmp / "missing.csv")], 2,
         ["coulomb_speed=-1.0"]),
    ]
    nema = str(tmp / "nema.toml")
    for flag, values in CALIBRATE:
        for v in values:
            cases.append((f"calibrate {flag}={v}", ["calibrate", nema, f"{flag}={v}"], 2, [_named(flag)]))
    cases += [
        ("calibrate no drive", ["calibrate", str(tmp / "nodrive.toml")], 2, ["no drive loop"]),
        ("calibrate out dir", ["calibrate", nema, "--out", str(tmp)], 2, ["--out"]),
        ("calibrate merge dir", ["calibrate", nema, "--merge", str(tmp)], 2, ["--merge"]),
        ("calibrate missing", ["calibrate", str(tmp / "missing.toml")], 2, ["missing.toml"]),
        ("reproduce out file", ["reproduce", "--out", str(tmp / "afile")], 2, ["--out", "afile"]),
        ("plan missing", ["plan", str(tmp / "missing.toml")], 2, ["missing.toml"]),
        ("plan out file", ["plan", str(tmp / "plan_ok.toml"), "--out", str(tmp / "afile")], 2, ["--out"]),
    ]
    for i, (key, value, needle) in enumerate(PLAN_CASES):
        name = f"plan_{i}.toml"
        cases.append((f"plan {key}={value}"[:70], ["plan", str(tmp / name), "--out", str(tmp / "plots")], 2,
                      [name, needle]))
    for i, (text, needle) in enumerate(SIM_FILES):
        name = f"sim_{i}.toml"
        cases.append((f"simulate file {text!r}"[:70], ["simulate", str(tmp / name)], 2, [name, needle]))
    for flag, values in DESIGN:
        for v in values:
            cases.append((f"design {flag}={v}", ["design", f"{flag}={v}"], 2, [_named(flag)]))
    return cases


FILES = {
    "rate10.toml": "[drive]\ncontrol_rate = 10.0\n",
    "boolrate.toml": "[drive]\ncontrol_rate = true\n",
    "vbus.toml": "[drive]\ncontrol_rate = 20000.0\nv_bus = \"24\"\n",
    "long.toml": "t_end = 1e9\n",
    "costly.toml": "t_end = 100.0\n[drive]\ncontrol_rate = 1e6\nsubsteps = 10000\n",
    "pwm.toml": "t_end = 10.0\n[drive]\ncontrol_rate = 20000.0\npwm = \"switched\"\nf_pwm = 1e8\n",
    "key.toml": "[motor]\nRx = 1.0\n",
    "params.toml": "[robustness]\nparameters = \"RL\"\n",
    "samples.toml": "[robustness]\nsamples = -1\n",
    "nodrive.toml": "[plan]\ntheta2 = 0.02\n",
    "drive.toml": "[drive]\ncontrol_rate = 20000.0\n",
    "broken.toml": "t_end = = 1\n",
    "study.toml": "[drive]\ncontrol_rate = 20000.0\n[controller]\nmeasurement = \"model\"\n[robustness]\n",
    "afile": "not a directory\n",
    "nema.toml": "[motor]\npreset = \"nema17\"\n[drive]\ncontrol_rate = 20000.0\n[sensors]\nencoder_counts = 16384\n",
    "plan_ok.toml": _plan_file("t0", "0.0"),
}


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli")
    for name, text in FILES.items():
        (tmp / name).write_text(text)
    (tmp / "binary.toml").write_bytes(b"\x00\xff\xfe\x80")
    for i, (key, value, _) in enumerate(PLAN_CASES):
        (tmp / f"plan_{i}.toml").write_text(_plan_file(key, value))
    for i, (text, _) in enumerate(SIM_FILES):
        (tmp / f"sim_{i}.toml").write_text(text)
    cases = _cases(tmp)

    done = [run_cli(c[1], cwd=tmp) for c in cases]
    return {c[0]: (c, p) for c, p in zip(cases, done, strict=True)}


CASE_IDS = [c[0] for c in _cases(Path("/tmp"))]


@pytest.mark.parametrize("case_id", CASE_IDS)
def test_the_command_line_refuses_bad_input(outcomes, case_id):
    (_, argv, code, needles), proc = outcomes[case_id]
    err = proc.stderr
    assert "Traceback" not in err and "internal error" not in err, err
    assert proc.returncode == code, (argv, proc.returncode, err)
    assert all(any(a in err for a in n) if isinstance(n, tuple) else n in err for n in needles), (needles, err)
    assert proc.stdout == "" or "usage" not in proc.stdout, proc.stdout


def test_the_table_is_large():
    assert len(CASE_IDS) >= 300
