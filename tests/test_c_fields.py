"""Each part gives the fields of its own C struct; the binding fills the structs from them and knows no field name."""
import math

import numpy as np
import pytest

from flatstep._flatstep_core import ffi, lib
from flatstep.core.runs import _loop_fields
from flatstep.core.structs import _plant_fields
from flatstep.loop.drive import PWM_MODES, Drive
from flatstep.loop.observers import MAX_ORDER, Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.motor import MotorParams, full_step
from flatstep.model.plant import PlantEffects

MOTOR = MotorParams.preset("nema17")


def test_the_motors_fields_fill_struct_motor_params():
    m = ffi.new("struct motor_params *", MOTOR.c_params())
    assert (m.R, m.L, m.Km, m.J, m.B, m.Nr) == (MOTOR.R, MOTOR.L, MOTOR.Km, MOTOR.J, MOTOR.B, MOTOR.Nr)
    assert lib.motor_params_valid(m)


def test_full_step_lives_with_the_motor():
    assert full_step(50) == pytest.approx(2 * math.pi / 200)  # 1.8 deg on a 200-step motor
    assert full_step(MOTOR.Nr) == math.pi / (2 * MOTOR.Nr)


@pytest.mark.parametrize("effects", [PlantEffects(detent_torque=0.01, coulomb_torque=0.002, coulomb_speed=0.5,
                                                  magnetizing_resistance=40.0, detent_harmonic=2),
                                     PlantEffects(detent_torque=0.01)])
def test_the_effects_fields_fill_struct_plant_effects(effects):
    e = ffi.new("struct plant_effects *", effects.c_effects())
    assert (e.detent_torque, e.detent_harmonic, e.coulomb_torque, e.coulomb_speed) == (
        effects.detent_torque, effects.detent_harmonic, effects.coulomb_torque, effects.coulomb_speed)
    assert e.magnetizing_resistance == (effects.magnetizing_resistance or 0.0)  # 0: no iron loss


def test_a_plant_without_effects_has_zero_effects():
    p = ffi.new("struct plant *", _plant_fields(MOTOR, 1e-3, None))
    assert p.load == 1e-3 and p.motor.Km == MOTOR.Km and not lib.plant_has_effects(p)
    q = ffi.new("struct plant *", _plant_fields(MOTOR, 0.0, PlantEffects(coulomb_torque=0.01)))
    assert lib.plant_has_effects(q) and lib.plant_valid(q)


@pytest.mark.parametrize("mode", PWM_MODES)
def test_the_drives_pwm_mode_is_the_c_enum(mode):
    drive = Drive(v_bus=36.0, pwm=mode, f_pwm=20e3, dead_time=1e-6)
    d = ffi.new("struct drive_params *", drive.c_params(compute_delay=True))
    assert d.pwm == getattr(lib, f"DRIVE_{mode.upper()}")
    assert (d.v_bus, d.f_pwm, d.dead_time, d.compute_delay) == (36.0, 20e3, 1e-6, True)
    state = ffi.new("struct drive *")
    assert lib.drive_init(state, d, [0.0, 0.0]) == 0


def test_no_drive_is_an_unlimited_averaged_bridge():
    d = ffi.new("struct drive_params *", Drive.c_ideal_params(compute_delay=False))
    assert math.isinf(d.v_bus) and d.pwm == lib.DRIVE_AVERAGED and not d.compute_delay
    assert lib.drive_init(ffi.new("struct drive *"), d, [0.0, 0.0]) == 0


def test_the_sensors_fields_fill_struct_sensors_params():
    sensors = Sensors(encoder_counts=4000, encoder_offset=0.25, current_bits=10, current_range=3.0,
                      current_offset=(0.01, -0.02), delay=2)
    s = ffi.new("struct sensors_params *", sensors.c_params())
    assert (s.angle_step, s.encoder_offset, s.current_step, s.current_range, s.delay) == (
        2 * math.pi / 4000, 0.25, 6.0 / 1024, 3.0, 2)
    assert list(s.current_offset) == [0.01, -0.02] and lib.sensors_params_valid(s)
    exact = ffi.new("struct sensors_params *", Sensors(encoder_counts=None, current_bits=None).c_params())
    assert exact.angle_step == 0.0 and exact.current_step == 0.0


@pytest.mark.parametrize("load_states", [0, 1, 2])
def test_the_observers_fields_are_its_matrices(load_states):
    obs, Ts = Observer(bandwidth=800.0, load_states=load_states), 5e-5
    o = ffi.new("struct observer_params *", obs.c_params(MOTOR, Ts))
    Ad, Bd, Lc = obs.matrices(MOTOR, Ts)
    n = obs.order
    assert o.order == n and lib.OBSERVER_MAX_ORDER == MAX_ORDER
    np.testing.assert_array_equal([[o.Ad[i][j] for j in range(n)] for i in range(n)], Ad)
    np.testing.assert_array_equal([o.Bd[i] for i in range(n)], Bd)
    np.testing.assert_array_equal([o.Lc[i] for i in range(n)], Lc)
    assert lib.observer_init(ffi.new("struct observer *"), o) == 0


def test_the_loop_is_the_parts_fields():
    drive, sensors, obs = Drive(v_bus=24.0, pwm="switched"), Sensors(encoder_counts=4000), Observer()
    p = ffi.new("struct sampled_params *", _loop_fields(MOTOR, 5e-5, 2, drive, sensors, obs, True))
    assert p.sensed and p.observed and p.model.Nr == MOTOR.Nr and p.drive.pwm == lib.DRIVE_SWITCHED
    assert p.drive.compute_delay and p.sensors.angle_step == 2 * math.pi / 4000 and p.observer.order == obs.order
    ideal = ffi.new("struct sampled_params *", _loop_fields(MOTOR, 5e-5, 2, None, None, None, False))
    assert not ideal.sensed and not ideal.observed and math.isinf(ideal.drive.v_bus) and ideal.observer.order == 0
    assert lib.sampled_init(ffi.new("struct sampled *"), p) == 0
    assert lib.sampled_init(ffi.new("struct sampled *"), ideal) == 0
