"""Exports a machine runs: step timestamps within a microstep of the plan, setpoint streams the C core replays."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep._flatstep_core import ffi, lib
from flatstep.plan.export import SETPOINT_COLUMNS, setpoint_stream, step_times
from flatstep.studies.scenario_file import read_scenario_file

ROOT = Path(__file__).resolve().parent.parent
VIA = ROOT / "examples" / "plans" / "hermite-via.toml"


@pytest.fixture(scope="module")
def via():
    """The hermite via-point plan: forward to 6 rad, then back to 2 rad (a reversal)."""
    sf = read_scenario_file(VIA)
    return sf.scenario.plan, sf.scenario.motor


def _dense(plan, n=400_001):
    return np.linspace(plan.t0 - 1e-3, plan.tf + 1e-3, n)


@pytest.mark.parametrize("microsteps", [1, 16, 256])
def test_steps_keep_the_commanded_position_within_half_a_microstep(via, microsteps):
    plan, motor = via
    train = step_times(plan, motor, microsteps)
    t = _dense(plan)
    error = np.abs(plan.flag(t).theta - train.commanded(t))
    assert error.max() <= train.position_bound + 1e-12
    assert train.position_bound < 0.5 * train.increment * (1 + 1e-6)
    # net steps: the end angle to the nearest microstep; both directions occur (the plan reverses)
    net = int(train.direction.astype(int).sum())
    assert net == int(np.floor((plan.theta2 - plan.theta1) / train.increment + 0.5))
    assert set(np.unique(train.direction)) == {-1, 1}
    assert np.all(np.diff(train.t) >= 0)


def test_each_step_is_at_its_crossing(via):
    plan, motor = via
    train = step_times(plan, motor, 16)
    theta = plan.flag(train.t).theta
    before = train.positions - train.direction * train.increment
    midway = 0.5 * (before + train.positions)  # the level crossed
    assert np.abs(theta - midway).max() < 1e-9


def test_a_timer_rounds_timestamps_within_the_stated_bound(via):
    plan, motor = via
    train = step_times(plan, motor, 16, timer_rate=1e5)
    ticks = train.t * 1e5
    assert np.allclose(ticks, np.round(ticks), atol=1e-6)
    t = _dense(plan)
    error = np.abs(plan.flag(t).theta - train.commanded(t))
    assert error.max() <= train.position_bound + 1e-12
    assert train.position_bound > 0.5 * train.increment  # the timer's share is stated


def test_steps_on_a_time_optimal_move():
    sf = read_scenario_file(ROOT / "examples" / "plans" / "nema17-168-ten-revolutions.toml")
    plan, motor = sf.scenario.plan, sf.scenario.motor
    train = step_times(plan, motor, 16)
    assert train.t.size == round((plan.theta2 - plan.theta1) / train.increment)
    assert np.all(train.direction == 1)
    t = _dense(plan)
    assert np.abs(plan.flag(t).theta - train.commanded(t)).max() <= train.position_bound + 1e-12


def test_setpoints_follow_the_flat_maps(via):
    plan, motor = via
    stream = setpoint_stream(plan, motor, 20_000.0, load_torque=0.01)
    t = stream.t
    flag = plan.flag(t)
    x, _ = fs.flat_to_state(flag, motor, 0.01)
    theta, omega, alpha, torque, i_d, i_q = stream.rows.T
    assert np.array_equal(theta, flag.theta) and np.array_equal(omega, flag.dtheta)
    assert np.allclose(torque, motor.J * flag.ddtheta + motor.B * flag.dtheta + 0.01, rtol=0, atol=1e-15)
    assert np.allclose(i_q, torque / motor.Km, rtol=1e-9, atol=1e-12)
    assert np.allclose(np.hypot(i_d, i_q), flag.rho, rtol=1e-9)
    assert stream.t[-1] <= plan.tf and stream.t[-1] > plan.tf - 1 / 20_000.0


def _replay(stream, times, mode):
    rows = np.ascontiguousarray(stream.rows.astype(np.float32))
    s = ffi.new("struct setpoint_stream *", dict(rows=ffi.from_buffer("float[]", rows), n=rows.shape[0],
                                                  t0=stream.t0, rate=stream.rate))
    out = ffi.new("fs_real[]", lib.SETPOINT_LEN)
    values = np.empty((len(times), lib.SETPOINT_LEN))
    for k, t in enumerate(times):  # a test driver, not a hot path
        assert lib.setpoint_at(s, float(t), mode, out) == lib.SETPOINT_OK
        values[k] = list(out)
    return values


def test_the_c_core_replays_the_stream_to_float_precision(via):
    plan, motor = via
    stream = setpoint_stream(plan, motor, 5_000.0)
    got = _replay(stream, stream.t, lib.SETPOINT_HOLD)
    assert np.array_equal(got, stream.rows.astype(np.float32).astype(np.float64))
    scale = np.abs(stream.rows).max(axis=0)
    assert np.all(np.abs(got - stream.rows) <= 2.0**-24 * scale + 1e-30)
    # linear between rows: halfway is the mean of the two rows
    mid = stream.t[:-1] + 0.5 / stream.rate
    lin = _replay(stream, mid[::25], lib.SETPOINT_LINEAR)
    f32 = stream.rows.astype(np.float32).astype(np.float64)
    assert np.allclose(lin, 0.5 * (f32[:-1] + f32[1:])[::25], rtol=1e-12, atol=1e-12)
    # outside the stream: held at its ends
    ends = _replay(stream, [stream.t0 - 1.0, stream.t[-1] + 1.0], lib.SETPOINT_HOLD)
    assert np.array_equal(ends, f32[[0, -1]])


def test_replay_refuses_bad_arguments():
    rows = np.zeros((2, lib.SETPOINT_LEN), dtype=np.float32)
    out = ffi.new("fs_real[]", lib.SETPOINT_LEN)
    good = dict(rows=ffi.from_buffer("float[]", rows), n=2, t0=0.0, rate=1000.0)
    for change in (dict(n=0), dict(rate=0.0), dict(rate=float("nan")), dict(t0=float("inf")),
                   dict(rows=ffi.NULL)):
        s = ffi.new("struct setpoint_stream *", {**good, **change})
        assert lib.setpoint_at(s, 0.0, lib.SETPOINT_HOLD, out) == lib.SETPOINT_EARGS
    s = ffi.new("struct setpoint_stream *", good)
    assert lib.setpoint_at(s, float("nan"), lib.SETPOINT_HOLD, out) == lib.SETPOINT_EARGS
    assert lib.setpoint_at(s, 0.0, 7, out) == lib.SETPOINT_EARGS
    assert lib.setpoint_at(ffi.NULL, 0.0, lib.SETPOINT_HOLD, out) == lib.SETPOINT_EARGS


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
def test_the_c_header_compiles_and_replays(via, tmp_path):
    plan, motor = via
    stream = setpoint_stream(plan, motor, 2_000.0)
    (tmp_path / "move.h").write_text(stream.c_table("move"))
    (tmp_path / "main.c").write_text(
        '#include <stdio.h>\n#include "setpoints.h"\n#include "move.h"\n'
        "int main(void) {\n"
        "  struct setpoint_stream s = {&move[0][0], MOVE_ROWS, MOVE_T0, MOVE_RATE};\n"
        "  fs_real out[SETPOINT_LEN];\n"
        "  for (unsigned k = 0; k < MOVE_ROWS; k++) {\n"
        "    if (setpoint_at(&s, MOVE_T0 + k / MOVE_RATE, SETPOINT_HOLD, out) != SETPOINT_OK) return 1;\n"
        '    for (int j = 0; j < SETPOINT_LEN; j++) printf("%.17g%c", (double)out[j], j + 1 < SETPOINT_LEN ? \',\' : \'\\n\');\n'
        "  }\n  return 0;\n}\n")
    exe = tmp_path / "replay"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", "-I", str(ROOT / "csrc"), "-I", str(tmp_path),
                    str(tmp_path / "main.c"), str(ROOT / "csrc" / "setpoints.c"), "-lm", "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    got = np.loadtxt(out.splitlines(), delimiter=",")
    assert got.shape == stream.rows.shape
    assert np.array_equal(got, stream.rows.astype(np.float32).astype(np.float64))


@pytest.mark.parametrize("kwargs, match", [
    (dict(microsteps=0), "microsteps"), (dict(microsteps=4096), "microsteps"), (dict(microsteps=2.5), "microsteps"),
    (dict(timer_rate=-1.0), "timer_rate"), (dict(timer_rate=float("nan")), "timer_rate"),
])
def test_step_times_refuses_bad_arguments(via, kwargs, match):
    plan, motor = via
    with pytest.raises(ValueError, match=match):
        step_times(plan, motor, **kwargs)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rate=0.0), "rate"), (dict(rate="fast"), "rate"), (dict(rate=1e3, t_end=0.0), "t_end"),
    (dict(rate=1e3, load_torque=float("nan")), "load_torque"),
])
def test_setpoint_stream_refuses_bad_arguments(via, kwargs, match):
    plan, motor = via
    with pytest.raises(ValueError, match=match):
        setpoint_stream(plan, motor, **kwargs)


def test_c_table_refuses_a_name_that_is_not_a_c_identifier(via):
    plan, motor = via
    with pytest.raises(ValueError, match="C identifier"):
        setpoint_stream(plan, motor, 1e3).c_table("1move")


def test_export_command(cli, tmp_path):
    # --no-verify: the file's plan as it is (the check on the drive has its own tests)
    run = cli(["export", str(VIA), "--no-verify", "--steps", "--microsteps", "8", "--out", "steps.csv"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    data = np.loadtxt(tmp_path / "steps.csv", delimiter=",", skiprows=1)
    assert (tmp_path / "steps.csv").read_text().startswith("t,direction,position")
    assert set(np.unique(data[:, 1])) == {-1.0, 1.0}
    run = cli(["export", str(VIA), "--no-verify", "--setpoints", "--out", "sp.csv"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    header = (tmp_path / "sp.csv").read_text().splitlines()[0]
    assert header == "t," + ",".join(SETPOINT_COLUMNS)
    run = cli(["export", str(VIA), "--no-verify", "--setpoints", "--rate", "1000", "--out", "sp.h", "--name", "via"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "static const float via[VIA_ROWS][6]" in (tmp_path / "sp.h").read_text()
    # written again over its own file: allowed; over a file flatstep did not write: refused
    assert cli(["export", str(VIA), "--no-verify", "--setpoints", "--out", "sp.h"], cwd=tmp_path).returncode == 0
    (tmp_path / "notes.csv").write_text("my notes\n")
    run = cli(["export", str(VIA), "--no-verify", "--steps", "--out", "notes.csv"], cwd=tmp_path)
    assert run.returncode == 2 and "notes.csv" in run.stderr
    run = cli(["export", str(VIA), "--no-verify", "--steps", "--out", "steps.h"], cwd=tmp_path)
    assert run.returncode == 2 and "C header" in run.stderr
    run = cli(["export", str(VIA), "--no-verify", "--steps", "--microsteps", "0", "--out", "s.csv"], cwd=tmp_path)
    assert run.returncode == 2 and "microsteps" in run.stderr


def test_the_via_example_is_kept_on_its_own_drive(cli, tmp_path):
    """The README exports hermite-via.toml without --no-verify: flatstep plan keeps it on its drive and controller."""
    run = cli(["plan", str(VIA)], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "verified on the drive" in run.stdout and "every run ok" in run.stdout
    run = cli(["export", str(VIA), "--steps", "--out", "steps.csv"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
