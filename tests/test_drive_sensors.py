import math

import numpy as np
import pytest

from flatstep.loop.drive import Drive
from flatstep.loop.sensors import Sensors


def test_saturation_keeps_the_direction():
    d = Drive(v_bus=24.0)
    v = np.array([[30.0, 10.0, -48.0], [15.0, 5.0, 12.0]])
    out = d.saturate(v)
    np.testing.assert_allclose(out[:, 0], [24.0, 12.0])
    np.testing.assert_allclose(out[:, 1], [10.0, 5.0])  # inside: untouched
    np.testing.assert_allclose(out[:, 2], [-24.0, 6.0])
    assert np.all(np.abs(out) <= 24.0)


@pytest.mark.parametrize("v", [(3.0, -2.0), (20.0, 23.9), (-24.0, 0.0)])
def test_switched_pwm_has_the_commanded_average(v):
    d = Drive(pwm="switched", f_pwm=40e3)
    dur, lv = d.pwm_segments(np.array(v), np.array([0.3, -0.2]), 5e-5)
    assert dur.sum() == pytest.approx(5e-5, rel=1e-12)
    assert set(np.unique(np.abs(lv))) <= {24.0}
    np.testing.assert_allclose(dur @ lv / dur.sum(), v, atol=1e-9)


def test_dead_time_shifts_the_average_against_the_current():
    td, f = 0.5e-6, 40e3
    d = Drive(pwm="switched", f_pwm=f, dead_time=td)
    dur, lv = d.pwm_segments(np.array([5.0, 5.0]), np.array([0.3, -0.3]), 5e-5)
    avg = dur @ lv / dur.sum()
    np.testing.assert_allclose(avg, [5.0 - 2 * 24 * td * f, 5.0 + 2 * 24 * td * f], atol=1e-9)


def test_averaged_pwm_is_one_segment():
    dur, lv = Drive().pwm_segments(np.array([30.0, 0.0]), np.zeros(2), 5e-5)
    assert dur.tolist() == [5e-5] and lv.tolist() == [[24.0, 0.0]]


@pytest.mark.parametrize("kwargs, match", [
    (dict(v_bus=0.0), "v_bus=0.0"), (dict(pwm="svpwm"), "pwm='svpwm'"), (dict(dead_time=1e-5), "dead_time=1e-05"),
    (dict(f_pwm=-1.0), "f_pwm=-1.0"),
])
def test_drive_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Drive(**kwargs)


def test_encoder_quantization():
    s = Sensors(encoder_counts=16384)
    q = 2 * math.pi / 16384
    theta = np.linspace(-0.1, 0.1, 10001)
    err = s.read_angle(theta) - theta
    assert np.max(np.abs(err)) <= q / 2 + 1e-15 and np.max(np.abs(err)) > 0.49 * q
    assert len(np.unique(np.round(s.read_angle(theta) / q, 6))) == pytest.approx(0.2 / q, abs=2)
    shifted = Sensors(encoder_counts=16384, encoder_offset=0.25).read_angle(theta)
    assert np.max(np.abs(shifted - theta)) <= q / 2 + 1e-15 and not np.allclose(shifted, s.read_angle(theta))
    assert Sensors(encoder_counts=None).read_angle(0.123) == 0.123


def test_current_adc():
    s = Sensors(current_bits=12, current_range=2.0, current_offset=(0.01, 0.0), current_noise=0.002, seed=3)
    assert s.current_step == pytest.approx(4.0 / 4096)
    noise = s.noise(1000)
    assert noise.shape == (1000, 2) and np.std(noise) == pytest.approx(0.002, rel=0.1)
    np.testing.assert_array_equal(noise, Sensors(current_noise=0.002, seed=3).noise(1000))
    reading = s.read_currents(np.array([0.4, -0.1]), noise[0])
    assert np.all(np.abs(reading - (np.array([0.41, -0.1]) + noise[0])) <= s.current_step / 2 + 1e-15)
    assert s.read_currents(np.array([5.0, -5.0])).tolist() == [2.0, -2.0]  # the ADC clips at its range


@pytest.mark.parametrize("kwargs, match", [
    (dict(encoder_counts=2), "encoder_counts=2"), (dict(encoder_counts=1000.5), "encoder_counts=1000.5"),
    (dict(current_bits=0), "current_bits=0"), (dict(delay=-1), "delay=-1"), (dict(encoder_offset=0.5), "encoder_offset=0.5"),
    (dict(current_noise=-1e-3), "current_noise=-0.001"), (dict(current_offset=(0.0,)), "current_offset="),
    (dict(current_range=0.0), "current_range=0.0"),
])
def test_sensor_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Sensors(**kwargs)
