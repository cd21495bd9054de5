"""The d-q law's online Km estimate: off is today's law, its guards, its C twin, its convergence, its registration."""
from dataclasses import replace

import numpy as np
import pytest

import flatstep as fs
from flatstep.core.structs import _in, _out, controller_struct, ffi, lib
from flatstep.loop.design import design_gains
from flatstep.control.dq_smc import DQIntegral, DQKmAdaptation
from flatstep.control.protocol import is_static
from flatstep.control.tuning import LABELS, make_controller

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
ADAPT = DQKmAdaptation(rate=1500.0, phi0=50.0, range=0.3, control_period=TS, v_hold=3.0)


def test_off_is_todays_law(near_plan, motor, plan):
    t, y = near_plan(plan, 50, 1)
    today = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", integral=DQIntegral(1e5, TS, 1e3))
    adapted = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", integral=DQIntegral(1e5, TS, 1e3), adaptation=ADAPT)
    assert today.adaptation is None and today.initial_state() == 0.0 and "adapt" in today.c_params()
    assert today.c_params()["adapt"] == {} and adapted.initial_state() == (0.0, motor.Km)
    bound = controller_struct(today)
    assert bound.state.km == motor.Km and bound.state.p.adapt.rate == 0
    v_c = np.empty(2)
    for k in range(t.size):  # the estimate at its start, motor.Km: the same voltages, bit for bit
        yk = np.ascontiguousarray(y[:, k])
        v_today = today.step(0.0, yk, t[k])[0]
        np.testing.assert_array_equal(adapted.step((0.0, motor.Km), yk, t[k])[0], v_today)
        lib.dq_smc_step(bound.state, t[k], ffi.cast("double *", _in(yk)), ffi.cast("double *", _out(v_c)))
        lib.dq_smc_reset(bound.state)
        np.testing.assert_allclose(v_c, v_today, rtol=1e-12, atol=1e-12 * np.max(np.abs(v_today)))
    assert not is_static(fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", adaptation=ADAPT))


@pytest.mark.parametrize("bad, match", [(dict(rate=0.0), "rate"), (dict(phi0=np.nan), "phi0"),
                                        (dict(range=1.0), r"range=1.0 must be in \(0, 1\)"),
                                        (dict(range=-0.1), "range"), (dict(control_period=np.inf), "control_period"),
                                        (dict(v_hold=0.0), "v_hold")])
def test_the_guards(bad, match, motor, plan):
    with pytest.raises(ValueError, match=match):
        replace(ADAPT, **bad)
    with pytest.raises(ValueError, match="is not a DQKmAdaptation"):
        fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", adaptation=0.9)  # type: ignore[arg-type]


def test_c_rejects_what_python_refuses(motor, plan):
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", adaptation=ADAPT)
    params = ctrl.c_params()
    state = ffi.new("struct dq_smc *")
    for field, value in (("range", 1.5), ("phi0", 0.0), ("rate", -1.0), ("Ts", np.nan)):
        bad = {**params, "adapt": {**params["adapt"], field: value}}
        assert lib.dq_smc_init(state, ffi.new("struct dq_smc_params *", bad)) == lib.DQ_SMC_EADAPT
    assert lib.dq_smc_init(state, ffi.new("struct dq_smc_params *", params)) == lib.DQ_SMC_PARAMS_OK


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_c_step_matches_python_with_its_state(near_plan, motor, plan, measurement):
    t, y = near_plan(plan, 400, 4)
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, measurement, integral=DQIntegral(2e6, TS, 3.0),
                            adaptation=replace(ADAPT, rate=3e4))
    bound = controller_struct(ctrl)
    v_c, state, moved = np.empty(2), ctrl.initial_state(), 0
    for k in range(t.size):
        yk = np.ascontiguousarray(y[:, k])
        lib.dq_smc_step(bound.state, t[k], ffi.cast("double *", _in(yk)), ffi.cast("double *", _out(v_c)))
        v_py, nxt = ctrl.step(state, yk, t[k])
        moved += nxt[1] != state[1]
        state = nxt
        assert bound.state.z == pytest.approx(state[0], rel=1e-12, abs=1e-15)
        assert bound.state.km == pytest.approx(state[1], rel=1e-12)
        if np.hypot(*v_py) < ctrl.c_v_limit:
            np.testing.assert_allclose(v_c, v_py, rtol=1e-11, atol=1e-11 * np.max(np.abs(v_py)))
    if measurement == "ideal":  # (the model's theta'' from random currents puts s2 outside the layer: held)
        assert 20 < moved < t.size - 20  # the estimate both advanced and held
        assert 0.7 * motor.Km <= state[1] <= 1.3 * motor.Km and state[1] != motor.Km


def test_the_estimate_converges_toward_the_plants_km():
    """NEMA 17 move, plant Km 10 % low, ideal measurement, the law without the integral: Km^ goes from the nominal
    Km to within 1 % of the plant's and stays there to the end; held at rest before the move."""
    m = fs.MotorParams.preset("nema17")
    plan = fs.point_to_point(m, 0.0, 0.5, 1.0, 1.0, t0=0.01, tf=0.07)
    gains = design_gains(m, plan, load_torque=0.02).gains
    plant = fs.Plant(m.replace(Km=0.9 * m.Km), load=0.02)
    ctrl = fs.DQFlatnessSMC(m, plan, gains, "ideal", torques=fs.TorqueModel.of_plant(plant),
                            adaptation=DQKmAdaptation.designed(m, plan, gains, TS, 24.0))
    trace, step = [], ctrl.step

    def recorded(state, y, t):
        v, nxt = step(state, y, t)
        trace.append((t, nxt[1]))
        return v, nxt

    ctrl.step = recorded  # type: ignore[method-assign]
    fs.simulate(plant, plan, ctrl, loop=fs.DriveLoop(control_period=TS, substeps=4), engine="python", t_end=0.08)
    t, km = np.array(trace).T
    assert np.all(km[t < plan.t0] == m.Km)
    late = km[t >= 0.04] / (0.9 * m.Km)
    assert np.all(np.abs(late - 1) < 0.01), late.min()


def test_registered_with_a_control_period(motor, plan):
    assert LABELS["dq_smc_i_ff_km"].startswith("flatness")
    torques = fs.TorqueModel(detent_torque=1e-3)
    with pytest.raises(ValueError, match="control_rate"):
        make_controller("dq_smc_i_ff_km", motor, plan, control_period=None, measurement="ideal", torques=torques)
    ctrl = make_controller("dq_smc_i_ff_km", motor, plan, control_period=TS, measurement="ideal", smc_gains=DESIGNED,
                           v_limit=24.0, torques=torques)
    assert ctrl.adaptation is not None and ctrl.integral is not None
    assert ctrl.adaptation.rate == DESIGNED.wn and ctrl.adaptation.range == 0.3 and ctrl.adaptation.v_hold == 24.0
    speed = np.max(np.abs(plan.flag(np.linspace(plan.t0, plan.tf, 401)).dtheta))
    assert ctrl.adaptation.phi0 == pytest.approx(0.1 * motor.Km * speed / motor.L)
    assert make_controller("dq_smc_i_ff", motor, plan, control_period=TS, measurement="ideal", smc_gains=DESIGNED,
                           torques=torques).adaptation is None
