"""The d-q law's angle advance: off is today's law, the voltage turned by Nr omega t_a, its guards, its C twin, its
registration, and what it buys on a field-weakening plan at the speed cap.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import tomllib

import flatstep as fs
from flatstep.control.build import BuildContext
from flatstep.control.dq_smc import DQIntegral, advance_of
from flatstep.control.spec import ControllerSpec
from flatstep.core.structs import _in, _out, controller_struct, ffi, lib
from flatstep.engine.simulate import simulate
from flatstep.loop.design import design_gains
from flatstep.loop.sensors import Sensors
from flatstep.model.datasheet import motor_from_table
from flatstep.model.flat_dq import park
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_dq import time_optimal_dq
from flatstep.studies.verify import drive_loop

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)


def test_the_advance_turns_the_voltage_by_the_angle_the_rotor_turns(near_plan, motor, plan):
    t, y = near_plan(plan, 200, 1)
    plain = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal")
    ahead = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", advance=advance_of(TS))
    assert plain.advance == 0.0 and ahead.advance == TS / 2 and advance_of(TS, compute_delay=True) == 1.5 * TS
    v0, v1 = plain.voltages(t, y[:4], y[4]), ahead.voltages(t, y[:4], y[4])
    # the same d-q voltage: at the measured angle without, at the angle Nr omega Ts/2 ahead with the advance
    np.testing.assert_allclose(np.array(park(*v1, motor.Nr * (y[3] + y[2] * TS / 2))),
                               np.array(park(*v0, motor.Nr * y[3])), rtol=1e-9, atol=1e-9)
    assert np.max(np.abs(v1 - v0)) > 1e-3  # and it moved


@pytest.mark.parametrize("bad", [-1e-6, np.nan, np.inf, "0.1", True])
def test_the_guards(bad, motor, plan):
    with pytest.raises(ValueError, match="advance="):
        fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", advance=bad)


def test_c_rejects_what_python_refuses(motor, plan):
    params = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", advance=TS / 2).c_params()
    state = ffi.new("struct dq_smc *")
    for value in (-1e-9, np.nan, np.inf):
        bad = {**params, "advance": value}
        assert lib.dq_smc_init(state, ffi.new("struct dq_smc_params *", bad)) == lib.DQ_SMC_EADVANCE
    assert lib.dq_smc_init(state, ffi.new("struct dq_smc_params *", params)) == lib.DQ_SMC_PARAMS_OK


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_c_step_matches_python(near_plan, motor, plan, measurement):
    t, y = near_plan(plan, 300, 4)
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, measurement, integral=DQIntegral(2e6, TS, 3.0),
                            advance=0.7 * TS)
    bound = controller_struct(ctrl)
    v_c, state = np.empty(2), ctrl.initial_state()
    for k in range(t.size):
        yk = np.ascontiguousarray(y[:, k])
        lib.dq_smc_step(bound.state, t[k], ffi.cast("double *", _in(yk)), ffi.cast("double *", _out(v_c)))
        v_py, state = ctrl.step(state, yk, t[k])
        assert bound.state.z == pytest.approx(state, rel=1e-12, abs=1e-15)
        if np.hypot(*v_py) < ctrl.c_v_limit:
            np.testing.assert_allclose(v_c, v_py, rtol=1e-11, atol=1e-11 * np.max(np.abs(v_py)))


def test_the_spec_option_builds_half_a_period_and_needs_one(motor, plan):
    spec = ControllerSpec("dq_smc", advance=True)
    assert spec.needs() == {"control_period"} and spec.name() == "dq_smc+advance"
    assert ControllerSpec.parse("dq_smc+advance") == spec
    ctx = BuildContext(motor, plan, "ideal", control_period=TS)
    assert spec.build(ctx).advance == TS / 2
    assert ControllerSpec("dq_smc").build(ctx).advance == 0.0
    assert spec.build(BuildContext(motor, plan, "ideal", control_period=TS, compute_delay=True)).advance == 1.5 * TS
    with pytest.raises(ValueError, match="control_period"):
        spec.build(BuildContext(motor, plan, "ideal"))


def test_the_advance_tracks_the_sanyo_at_its_speed_cap():
    """Sanyo 103H5208 at 24 V, 1 rad field-weakening plan at the 88 rad/s cap (0.22 electrical rad per period), 20 kHz
    drive, 4000-count encoder: 2.27 mrad without the advance (benchmarks/field_weakening_optimum.py), within 1 mrad
    with it.
    """
    path = Path(__file__).resolve().parent.parent / "examples" / "motors" / "sanyo-103h5208-5240.toml"
    model = motor_from_table(tomllib.loads(path.read_text())["motor"], str(path))
    m, i_max = model.params, model.rated_rho
    fw = time_optimal_dq(1.0, m, MotorLimits(v_bus=24.0, i_max=i_max, i_hold=0.01 * i_max, v_use=0.84),
                         control_rate=20000.0, voltage="vector")
    loop = drive_loop(24.0, 20000.0, sensors=Sensors(encoder_counts=4000))
    d = design_gains(m, fw.plan, control_period=TS, v_bus=24.0, encoder_counts=4000, current_step=4 / 4096)
    loop = replace(loop, observer=d.observer)
    errors = []
    for advance in (0.0, advance_of(TS)):
        ctrl = fs.DQFlatnessSMC(m, fw.plan, d.gains, "observer", d_current=fw.d_current, advance=advance)
        r = simulate(m, fw.plan, ctrl, loop=loop, t_end=fw.plan.tf + 0.01, x0=[0.0, 0.0, 0.0, fw.plan.theta1])
        during = (r.t >= fw.plan.t0) & (r.t <= fw.plan.tf)
        assert r.status == "ok"
        errors.append(float(np.max(np.abs(r.theta_error[during]))))
    assert errors[0] > 1.5e-3 and errors[1] < 1e-3, errors
