"""Switched PWM on the C sampled loop against the Python reference.

The segments of one PWM period (``drive_pwm_period`` vs :meth:`~flatstep.loop.drive.Drive.pwm_period`, bit for
bit) and whole closed-loop runs with one RK4 step per PWM segment (C ``sampled_run`` vs ``engine="python"``), with
and without dead time.

Both compute each PWM period's breakpoints and merge them in the same order and arithmetic, so the segments are
identical; the runs then differ only where NumPy and libm round differently (docs of tests/test_core_drive.py):
measured over the runs below, max |dtheta| 3.5e-18 to 7.2e-15 rad and max |dv| 1.6e-15 to 6.9e-12 V.
"""
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep import core
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.studies.scenario_file import load_scenario

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
COUNT = 2 * np.pi / 16384
NEMA17 = Path(__file__).resolve().parents[1] / "examples" / "compare-nema17-fast.toml"
DEAD_TIMES = (0.0, 0.5e-6)

LOOPS = {  # name: (measurement, DriveLoop settings besides the drive)
    "ideal parts": ("ideal", {}),
    "14-bit, 12-bit, speed observer": ("observer", dict(sensors=Sensors(), observer=Observer(1500.0, 0))),
    "14-bit, 12-bit, noise, load observer": ("observer", dict(sensors=Sensors(current_noise=5e-3, seed=2),
                                                             observer=Observer(1500.0, 1))),
    "encoder difference, compute delay": ("model", dict(sensors=Sensors(), compute_delay=True)),
}


def c_pwm_period(drive, v, i, Tp):
    """C ``drive_pwm_period`` on a switched ``Drive``: (durations, levels) as lists."""
    p = core.ffi.new("struct drive_params *", dict(v_bus=drive.v_bus, pwm=core.lib.DRIVE_SWITCHED,
                                                     f_pwm=drive.f_pwm, dead_time=drive.dead_time))
    dur = core.ffi.new("fs_real[]", core.lib.DRIVE_PWM_SEGMENTS)
    lv = core.ffi.new("fs_real[][2]", core.lib.DRIVE_PWM_SEGMENTS)
    m = core.lib.drive_pwm_period(p, list(v), list(i), Tp, dur, lv)
    return [dur[k] for k in range(m)], [(lv[k][0], lv[k][1]) for k in range(m)]


def test_c_pwm_period_is_the_reference_bit_for_bit():
    """Random commands, currents, buses, frequencies, dead times and periods: identical segments."""
    rng = np.random.default_rng(7)
    segments = 0
    for case in range(300):
        f = rng.choice([20e3, 40e3, rng.uniform(5e3, 200e3)])
        td = 0.0 if case % 4 == 0 else rng.uniform(0, 0.25 / f) * rng.choice([1.0, 0.1])
        drive = Drive(v_bus=rng.choice([12.0, 24.0, rng.uniform(5, 60)]), pwm="switched", f_pwm=f, dead_time=td)
        v = rng.uniform(-1.3, 1.3, 2) * drive.v_bus
        if case % 5 == 0:
            v[case % 2] = rng.choice([-1.0, 0.0, 1.0]) * drive.v_bus  # at a rail, or at 50 % duty
        i = rng.normal(0, 0.5, 2) * (case % 3 != 0)  # every third case at zero current
        Tp = rng.uniform(1e-5, 3e-4) / drive.pwm_periods(TS)
        dur, lv = drive.pwm_period(v, i, Tp)
        assert c_pwm_period(drive, v, i, Tp) == (dur, lv)
        assert 1 <= len(dur) <= core.lib.DRIVE_PWM_SEGMENTS and abs(sum(dur) - Tp) < 1e-18
        segments += len(dur)
    assert segments > 1500  # both phases switch: most periods have 5 to 9 segments


def test_pwm_segments_repeat_one_period():
    """A control period of two PWM periods is one period's segments twice, on the saturated command."""
    drive = Drive(pwm="switched", f_pwm=40e3, dead_time=0.5e-6)
    dur, lv = drive.pwm_segments(np.array([5.0, -30.0]), np.array([0.3, -0.2]), TS)
    one, levels = drive.pwm_period([5.0, -30.0], [0.3, -0.2], TS / 2)
    assert drive.pwm_periods(TS) == 2 and dur.tolist() == one * 2 and lv.tolist() == [list(x) for x in levels] * 2
    assert dur.sum() == pytest.approx(TS, rel=1e-15)
    assert np.max(np.abs(lv)) == 24.0  # -30 V saturates: (5, -30) -> (4, -24), the direction kept


def paper_run(motor, plan, measurement, options, drive, engine):
    """A drive run on the paper's motor and move: 60 ms at 20 kHz, perturbed plant, 1e-5 N m."""
    perturbed = motor.replace(R=1.1 * motor.R, L=0.9 * motor.L, Km=0.9 * motor.Km, J=1.1 * motor.J, B=0.9 * motor.B)
    plant = fs.Plant(perturbed, load=1e-5)
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, measurement)
    return fs.simulate(plant, plan, ctrl, loop=fs.DriveLoop(TS, 4, drive=drive, **options), engine=engine)


def assert_parity(c, py):
    """C within 1e-9 rad and A, 1e-8 V of the reference at every control instant."""
    assert c.meta["engine"] == "c" and py.meta["engine"] == "python"
    np.testing.assert_array_equal(c.t, py.t)
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-9)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-8)
    assert c.meta["controller_faults"] == py.meta["controller_faults"]


@pytest.mark.parametrize("dead_time", DEAD_TIMES)
@pytest.mark.parametrize("name", LOOPS)
def test_c_switched_pwm_matches_the_reference(motor, plan, name, dead_time):
    """The paper's motor with the designed gains, every measurement mode, with and without dead time."""
    measurement, options = LOOPS[name]
    drive = Drive(v_bus=24.0, pwm="switched", f_pwm=40e3, dead_time=dead_time)
    c, py = (paper_run(motor, plan, measurement, options, drive, engine) for engine in ("c", "python"))
    averaged = paper_run(motor, plan, measurement, options, Drive(v_bus=24.0), "c")
    assert_parity(c, py)
    print(f"\n{name}, dead time {dead_time:g} s: max |dtheta| {np.max(np.abs(c.theta - py.theta)):.2g} rad, "
          f"max |dv| {np.max(np.abs([c.va - py.va, c.vb - py.vb])):.2g} V, "
          f"PWM vs averaged {np.max(np.abs(c.theta - averaged.theta)) / COUNT:.3g} counts")
    assert c.meta["drive"] == drive.as_dict()
    assert np.max(np.abs([c.va, c.vb])) <= 24.0  # the recorded voltages are the averaged commands
    chopped = np.max(np.abs(c.theta - averaged.theta))
    assert chopped > 1e-12  # the C plant saw the PWM segments, not the averaged voltage
    if dead_time == 0 and measurement == "ideal":
        # centre-aligned PWM sampled at period boundaries tracks like the averaged bridge
        assert c.summary()["max_abs_theta_error_move"] < 2 * averaged.summary()["max_abs_theta_error_move"] + COUNT
    if dead_time > 0 and measurement == "ideal":
        assert chopped > COUNT  # 0.96 V against each current: the uncompensated dead time moves the rotor


@pytest.mark.parametrize("dead_time", DEAD_TIMES)
def test_c_switched_pwm_on_the_nema17_scenario(dead_time):
    """The NEMA 17 compare scenario (load, detent, Coulomb friction, sensors, load observer) under PWM.

    With dead time, also the speed-up on this 60 ms switched run: its Python reference run, timed, against the best
    of 3 C runs (one reference run serves both checks).
    """
    scenario, _ = load_scenario(NEMA17)
    drive = Drive(v_bus=24, pwm="switched", f_pwm=40e3, dead_time=dead_time)
    switched = replace(scenario, loop=replace(scenario.loop, drive=drive))
    assert switched.loop.sensors is not None and switched.loop.observer is not None
    c = switched.run(engine="c")
    t0 = time.perf_counter()
    py = switched.run(engine="python")
    t_py = time.perf_counter() - t0
    assert_parity(c, py)
    print(f"\nNEMA 17, dead time {dead_time:g} s: max |dtheta| {np.max(np.abs(c.theta - py.theta)):.2g} rad, "
          f"max |dv| {np.max(np.abs([c.va - py.va, c.vb - py.vb])):.2g} V, "
          f"move error {c.summary()['max_abs_theta_error_move'] / COUNT:.2f} counts")
    assert c.summary()["max_abs_theta_error_move"] < 20 * COUNT  # 0.5 rad in 60 ms against 0.039 N m (9-10 counts)
    if dead_time == 0:
        return
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        switched.run(engine="c")
        times.append(time.perf_counter() - t0)
    ratio = t_py / min(times)
    print(f"switched PWM, NEMA 17 scenario, 2000 periods: C {1e3 * min(times):.1f} ms, "
          f"Python reference {1e3 * t_py:.0f} ms, speed-up {ratio:.0f}x")
    assert ratio > 20
