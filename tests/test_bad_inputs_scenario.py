"""Bad scenario files in the one format: the planners' keys, waypoints, limits, old names.

Each case is a file that is valid but for one thing; the loader must refuse it with a ValueError naming the file, the
key (``file:table.key``) and what is wrong, before any planning. A sample of them also goes through the command line
(exit 2, one line, no traceback). tests/test_bad_inputs_toml.py covers every other table's values.
"""
from __future__ import annotations

import re
import time

import pytest

from flatstep.studies.scenario_file import read_scenario_file
from flatstep.validate.limits import MAX_OPTIMAL_MOVES

MOTOR = '[motor]\npreset = "nema17"\n'
DRIVE = "[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n"
LIMITS = "[limits]\ni_max = 1.0\n"
HEAD = MOTOR + DRIVE + LIMITS
FAMILY_KEYS = {"psi": "durations = [0.1]\n", "hermite": "durations = [0.1]\n", "spline": "durations = [0.1]\n",
               "scurve": "caps = {speed_max = 45.0, accel_max = 8000.0, jerk_max = 2e6}\n", "time_optimal": ""}


def _plan(planner: str, extra: str = "", waypoints: str = "[0.0, 1.0]", head: str = HEAD) -> str:
    """A valid waypoint plan of ``planner`` with ``extra`` keys (a key given in ``extra`` replaces the default)."""
    own = "".join(line + "\n" for line in FAMILY_KEYS[planner].splitlines()
                  if line.split("=")[0].strip() not in extra)
    return f'{head}[plan]\nplanner = "{planner}"\n{own}{extra}waypoints = {waypoints}\n'


#: (table, file text, what the message must contain)
CASES: list[tuple[str, str, str]] = []

# [plan] waypoints: not numbers, bad tables, too few, too many (refused before any planning)
for family in ("time_optimal", "spline"):
    for bad, shown in [('"1.0"', "'1.0'"), ("true", "True"), ("false", "False"), ("nan", "nan"), ("inf", "inf"),
                       ("[1.0]", "[1.0]"), ("1979-05-27", "1979"), ('{theta = "1.0"}', "'1.0'"),
                       ("{theta = true}", "True"), ("{velocity = 1.0}", "no theta"),
                       ("{theta = 1.0, speed = 2.0}", "speed"), ("{theta = 1.0, dwell = -1.0}", "dwell=-1.0"),
                       ('{theta = 1.0, dwell = "0.1"}', "'0.1'"), ("{theta = 1.0, dwell = nan}", "nan"),
                       ("{theta = 1.0, velocity = true}", "True"), ("1e9", "1000000000.0")]:
        CASES.append(("plan.waypoints", _plan(family, waypoints=f"[0.0, {bad}]"), f"plan.waypoints[1]|{shown}"))
    for bad, shown in [("[]", "0 waypoint(s)"), ("[0.0]", "1 waypoint(s)"), ("5.0", "5.0"), ('"0 1"', "'0 1'"),
                       ("{theta = 1.0}", "theta"),
                       ("[" + ", ".join(str(i % 2) for i in range(MAX_OPTIMAL_MOVES + 2)) + "]",
                        f"{MAX_OPTIMAL_MOVES + 1} moves"),
                       ("[" + ", ".join(str(i % 2) for i in range(100_001)) + "]", "100000 moves")]:
        CASES.append(("plan.waypoints", _plan(family, waypoints=bad), f"plan.waypoints|{shown}"))

# [plan] planner
for bad in ('"bezier"', "1", "true", '["spline"]', '"Time_Optimal"', '""'):
    CASES.append(("plan.planner", f'{HEAD}[plan]\nplanner = {bad}\nwaypoints = [0.0, 1.0]\n', "plan.planner|planner="))
CASES.append(("plan.planner", f"{HEAD}[plan]\nwaypoints = [0.0, 1.0]\n", "plan.planner|waypoints need a planner"))

# keys a planner does not take: named with the planner and the keys it takes
for planner, key, value in [
    ("time_optimal", "caps", "{speed_max = 1.0, accel_max = 1.0, jerk_max = 1.0}"),
    ("time_optimal", "durations", "[0.1]"), ("time_optimal", "rho", "0.5"), ("time_optimal", "theta1", "0.0"),
    ("time_optimal", "tf", "0.1"), ("scurve", "durations", "[0.1]"), ("scurve", "through", "true"),
    ("psi", "through", "true"), ("spline", "through", "false"), ("hermite", "rho1", "0.4"),
    ("spline", "theta2", "1.0"), ("psi", "tf", "0.2"),
]:
    CASES.append((f"plan ({planner})", _plan(planner, f"{key} = {value}\n"),
                  f"plan.{key}|the {planner} planner does not take {key}|it takes"))
for key, value in [("waypoints", "[0.0, 1.0]"), ("through", "true"), ("rho", "0.4"), ("caps", "{}"),
                   ("durations", "[0.1]")]:
    CASES.append(("plan (rest_to_rest)", f'[plan]\nplanner = "rest_to_rest"\n{key} = {value}\n',
                  f"plan.{key}|the rest_to_rest planner does not take {key}"))

# [plan] t0, rho, through, durations, caps
for family in ("time_optimal", "hermite"):
    for bad, shown in [("-1", "t0=-1"), ("-0.01", "t0=-0.01"), ('"0"', "'0'"), ("true", "True"), ("nan", "nan"),
                       ("1e300", "1e+300")]:
        CASES.append(("plan.t0", _plan(family, f"t0 = {bad}\n"), f"plan.t0|{shown}"))
for bad, shown in [("0", "rho=0"), ("-1", "rho=-1"), ('"0.5"', "'0.5'"), ("true", "True"), ("nan", "nan"),
                   ("1e300", "1e+300")]:
    CASES.append(("plan.rho", _plan("spline", f"rho = {bad}\n"), f"plan.rho|{shown}"))
for bad, shown in [('"yes"', "'yes'"), ("1", "through=1"), ("[true]", "[True]")]:
    CASES.append(("plan.through", _plan("time_optimal", f"through = {bad}\n"), f"plan.through|{shown}"))
for bad, shown in [('"x"', "'x'"), ("[true]", "True"), ('["0.1"]', "'0.1'"), ("[nan]", "nan"), ("0.1", "0.1"),
                   ("[0.1, 0.1]", "a list of 1 durations"), ("[-0.1]", "-0.1"), ("[0.0]", "durations[0]=0.0"),
                   ("[]", "[]")]:
    CASES.append(("plan.durations", _plan("spline", f"durations = {bad}\n"), f"plan.durations|{shown}"))
for bad, shown in [("{v_max = 45.0, a_max = 8000.0, j_max = 2e6}", "caps.v_max is an old name: rename it "
                    "caps.speed_max"), ("{a_max = 1.0}", "caps.a_max is an old name: rename it caps.accel_max"),
                   ("{j_max = 1.0}", "rename it caps.jerk_max"), ("{speed_max = 45.0}", "must give exactly"),
                   ("{speed_max = 45.0, accel_max = 8e3, jerk_max = 2e6, snap_max = 1.0}", "snap_max"),
                   ('"fast"', "'fast'"), ("45.0", "45.0"),
                   ('{speed_max = "45", accel_max = 8e3, jerk_max = 2e6}', "plan.caps.speed_max|'45'"),
                   ("{speed_max = true, accel_max = 8e3, jerk_max = 2e6}", "plan.caps.speed_max|True"),
                   ("{speed_max = 45.0, accel_max = 0.0, jerk_max = 2e6}", "plan.caps.accel_max|accel_max=0.0"),
                   ("{speed_max = 45.0, accel_max = 8e3, jerk_max = -1.0}", "plan.caps.jerk_max|jerk_max=-1.0"),
                   ("{speed_max = nan, accel_max = 8e3, jerk_max = 2e6}", "plan.caps.speed_max|nan")]:
    CASES.append(("plan.caps", _plan("scurve", f"caps = {bad}\n"), f"plan.caps|{shown}"))

# [limits]: every key's bad values, the bus it needs, consistency
for key in ("i_max", "i_hold", "i_run", "speed_corner", "torque_angle_max", "v_use", "speed_max", "accel_max",
            "jerk_max"):
    for bad, shown in [('"1"', "'1'"), ("true", "True"), ("nan", "nan"), ("-1.0", "-1.0")]:
        limits = LIMITS if key != "i_max" else ""
        CASES.append(("limits", _plan("time_optimal", head=MOTOR + DRIVE + f"{limits or '[limits]'}\n{key} = {bad}\n"
                      .replace("\n\n", "\n")), f"limits.{key}|{shown}"))
CASES += [
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_max = 1.0\ni_hold = 2.0\n"),
     "limits.i_hold|i_hold=2.0"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_max = 1.0\nv_use = 1.5\n"),
     "limits.v_use|v_use=1.5"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_max = 1.0\ntorque_angle_max = 2.0\n"),
     "limits.torque_angle_max|torque_angle_max=2.0"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_max = 1.0\ni_hold = 0.2\ni_run = 0.3\n"),
     "limits.i_run|i_run=0.3"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_max = 1.0\ni_speed = 2.0\n"), "'i_speed'"),
    ("limits", _plan("time_optimal", head=MOTOR + "[drive]\ncontrol_rate = 20000.0\n" + LIMITS),
     "drive.v_bus|[limits] plans against the bus: give [drive] v_bus"),
    ("limits", _plan("time_optimal", head=MOTOR + LIMITS), "drive.v_bus|give [drive] v_bus"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE), "limits|time_optimal planner plans against the motor's "
     "limits"),
    ("limits", _plan("time_optimal", head=MOTOR + DRIVE + "[limits]\ni_hold = 0.3\n"), "limits.i_max|needs i_max"),
]

# old names: told what to write instead
for table, head in (("drive", "[drive]\ncontrol_rate = 20000.0\n"), ("limits", DRIVE + "[limits]\ni_max = 1.0\n"),
                    ("controller", "[controller]\n")):
    for old in ("v_limit", "v_max", "v_hold", "c_v_limit"):
        CASES.append(("old names", f"{MOTOR}{head}{old} = 24.0\n", f"{table}.{old}|{old} is an old name|[drive] v_bus"))
CASES += [
    ("old names", f"v_max = 24.0\n{HEAD}", ":v_max|[drive] v_bus"),
    ("old names", f'{MOTOR}[limits]\nv_bus = 24.0\ni_max = 1.0\n[plan]\nplanner = "time_optimal"\n'
     "waypoints = [0.0, 1.0]\n", "limits.v_bus|v_bus is an old name|moved to [drive] v_bus"),
    ("old names", _plan("time_optimal") + "[simulate]\ncontrol_rate = 20000\n", "simulate|[drive] control_rate"),
    ("old names", _plan("time_optimal") + "[simulate]\nt_after = 0.02\n", "simulate|t_end"),
    ("old names", '[limits]\nv_bus = 24.0\ni_max = 1.0\n[plan]\nwaypoints = [0.0, 1.0]\n', "limits.v_bus"),
    ("old names", '[motor]\npreset = "nema17"\n[plan]\nwaypoints = [0.0, 1.0]\n', "plan.planner|time_optimal"),
    ("old names", '[plan]\nplanner = "spline"\ndurations = [0.1]\nwaypoints = [0.0, 1.0]\n',
     ":motor|give [motor]|nema17"),
]

# the tables around a waypoint plan (every controller type follows one): an unknown type, the design's load
for kind in ("pid", "cascade+integral", "dq_smc+km_estimate"):
    CASES.append(("controller", _plan("time_optimal") + f'[controller]\ntype = "{kind}"\n',
                  f"controller.type|{kind!r}"))
CASES += [
    ("plant", "[plant]\ndetent_torque = 1000.0\n[load]\ntorque = 5.0\n[drive]\ncontrol_rate = 20000.0\n"
     "[controller]\ndesign = true\n", "plant.detent_torque|1000.0|load.torque + plant.detent_torque"),
    ("plant", "[plant]\ncoulomb_torque = 999.0\ndetent_torque = 2.0\n[drive]\ncontrol_rate = 20000.0\n"
     "[controller]\ndesign = true\n", "plant.coulomb_torque|999.0"),
    ("load", "[plant]\ndetent_torque = 1.0\n[load]\ntorque = -999.5\n[drive]\ncontrol_rate = 20000.0\n"
     "[controller]\ndesign = true\n", "load.torque|-999.5"),
    ("drive", _plan("time_optimal", head=MOTOR + "[drive]\nv_bus = 24.0\n" + LIMITS), "control_rate is needed"),
    ("", "t_end = 0.01\n" + _plan("time_optimal"), ":t_end|t_end=0.01"),
]


def _id(case: tuple[str, str, str]) -> str:
    table, _, needle = case
    return f"{table}:{needle}"[:60]


def test_the_table_is_large_and_counted_by_table():
    by_table: dict[str, int] = {}
    for table, _, _ in CASES:
        key = table.split(" (")[0]
        by_table[key] = by_table.get(key, 0) + 1
    assert len(CASES) >= 150, by_table
    assert by_table["plan.waypoints"] >= 40 and by_table["limits"] >= 40 and by_table["old names"] >= 15, by_table


@pytest.mark.parametrize("table, text, needle", CASES, ids=[_id(c) for c in CASES])
def test_a_bad_file_is_refused_naming_the_key(tmp_path, table, text, needle):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    start = time.perf_counter()
    with pytest.raises(ValueError) as err:
        read_scenario_file(path)
    message = str(err.value)
    assert time.perf_counter() - start < 10.0, "refused before any work (planning 1e5 waypoints takes minutes)"
    assert message.startswith(str(path)), message
    for part in needle.split("|"):
        assert part in message, (part, message)


SAMPLE = CASES[::9]


@pytest.mark.parametrize("table, text, needle", SAMPLE, ids=[_id(c) for c in SAMPLE])
def test_the_command_line_refuses_with_exit_2(cli, tmp_path, table, text, needle):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    for argv in (["plan", path, "--out", tmp_path / "o"], ["simulate", path]):
        run = cli(argv, cwd=tmp_path)
        assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
        assert re.match(r"flatstep: (error|refused): ", run.stderr) and run.stderr.count("\n") == 1, run.stderr
        assert needle.split("|")[0] in run.stderr, run.stderr


@pytest.mark.parametrize("planner", list(FAMILY_KEYS))
def test_the_base_files_are_valid(tmp_path, planner):
    """Each case fails for its one fault: the file it starts from plans."""
    path = tmp_path / "ok.toml"
    path.write_text(_plan(planner))
    sf = read_scenario_file(path)
    assert sf.planner == planner and sf.plan.theta2 == pytest.approx(1.0) and sf.limits is not None
