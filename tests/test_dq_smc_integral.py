"""The d-q law's integral action on s2: its design rule, its anti-windup, its C twin and its registration."""
import numpy as np
import pytest

import flatstep as fs
from flatstep.core.structs import _in, _out, controller_struct, ffi, lib
from flatstep.loop.design import design_gains
from flatstep.control.dq_smc import DQIntegral
from flatstep.control.protocol import is_static
from flatstep.control.tuning import LABELS, make_controller
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.plant import PlantEffects
from flatstep.model.torque_model import TorqueModel

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
COUNT = 2 * np.pi / 16384


def test_the_design_rule_and_the_guards():
    ig = DQIntegral.designed(DESIGNED, TS, 24.0)
    assert ig.ki == pytest.approx(3e5 / 50 * 1500 / 4) and ig.control_period == TS and ig.v_hold == 24.0
    lam = DESIGNED.W2 / DESIGNED.eps2
    poles = np.sort(np.abs(np.roots([1.0, lam, ig.ki])))
    np.testing.assert_allclose(poles, [402.0, 5598.0], rtol=1e-3)  # near omega_n/4 and lambda
    assert DQIntegral.designed(DESIGNED, TS, np.inf).v_hold == 1e300
    for bad in (dict(ki=0.0), dict(ki=np.nan), dict(control_period=-1.0), dict(v_hold=np.inf)):
        with pytest.raises(ValueError, match="DQIntegral"):
            DQIntegral(**{"ki": 1.0, "control_period": TS, "v_hold": 24.0, **bad})


def test_the_python_step_integrates_inside_the_boundary_layer_only(motor, plan):
    y = np.array([0.05, 0.3, 2.0, 0.011, 30.0])
    t = 0.02
    plain = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal")
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", integral=DQIntegral(1e5, TS, 1e3))
    assert plain.initial_state() is None and ctrl.initial_state() == 0.0
    assert is_static(plain) and not is_static(ctrl)
    s2 = plain.sliding_variables(t, y[:4], y[4])[1]
    y[4] -= s2 - 20.0  # put s2 = 20 inside the boundary layer (eps2 = 50)
    s2 = float(plain.sliding_variables(t, y[:4], y[4])[1])
    assert s2 == pytest.approx(20.0)
    v0, z1 = ctrl.step(0.0, y, t)
    np.testing.assert_array_equal(v0, plain.step(None, y, t)[0])
    assert z1 == pytest.approx(TS * s2, rel=1e-12)
    v1, z2 = ctrl.step(z1, y, t)
    assert z2 == pytest.approx(2 * TS * s2, rel=1e-12)
    sn, cs = np.sin(motor.Nr * y[3]), np.cos(motor.Nr * y[3])
    dvq = (-v1[0] * sn + v1[1] * cs) - (-v0[0] * sn + v0[1] * cs)
    assert dvq == pytest.approx(-motor.L * motor.J * 1e5 * z1 / motor.Km, rel=1e-6)
    y[4] += 100.0  # s2 = 120: outside the boundary layer, held
    assert ctrl.step(z1, y, t)[1] == z1
    y[4] -= 100.0
    low = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", integral=DQIntegral(1e5, TS, np.hypot(*v0) / 2))
    assert low.step(z1, y, t)[1] == z1  # held above the bus


def test_c_step_matches_python_with_its_state(motor, plan):
    rng = np.random.default_rng(4)
    n = 300
    t = np.sort(rng.uniform(0.0, 0.04, n))
    ref = plan.flag(t)  # near the plan, |s2| on both sides of eps2 = 50
    y = np.array([rng.normal(0, 0.4, n), rng.normal(0, 0.4, n), ref.dtheta + rng.normal(0, 0.01, n),
                  ref.theta + rng.normal(0, 1e-5, n), ref.ddtheta + rng.normal(0, 30, n)])
    ctrl = fs.DQFlatnessSMC(motor, plan, DESIGNED, "ideal", integral=DQIntegral(2e6, TS, 3.0))
    bound = controller_struct(ctrl)
    v_c, z, advanced = np.empty(2), ctrl.initial_state(), 0
    for k in range(n):
        yk = np.ascontiguousarray(y[:, k])
        lib.dq_smc_step(bound.state, t[k], ffi.cast("double *", _in(yk)), ffi.cast("double *", _out(v_c)))
        v_py, z_next = ctrl.step(z, yk, t[k])
        advanced += z_next != z
        z = z_next
        assert bound.state.z == pytest.approx(z, rel=1e-12, abs=1e-15)
        if np.hypot(*v_py) < ctrl.c_v_limit:
            np.testing.assert_allclose(v_c, v_py, rtol=1e-11, atol=1e-11 * np.max(np.abs(v_py)))
    assert 20 < advanced < n - 20  # both branches of the anti-windup ran


def test_c_drive_loop_matches_the_reference(motor, plan):
    perturbed = motor.replace(R=1.1 * motor.R, L=0.9 * motor.L, Km=0.9 * motor.Km, J=1.1 * motor.J, B=0.9 * motor.B)
    plant = fs.Plant(perturbed, effects=PlantEffects(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5),
                     load=1e-5)
    ctrl = make_controller("dq_smc_i_ff", motor, plan, control_period=TS, measurement="observer",
                           smc_gains=DESIGNED, v_limit=24.0, torques=TorqueModel.of_plant(plant))
    loop = fs.DriveLoop(control_period=TS, substeps=4, drive=Drive(), sensors=Sensors(current_noise=5e-3, seed=2),
                        observer=Observer(1500.0, 2))
    c = fs.simulate(plant, plan, ctrl, loop=loop, engine="c")
    py = fs.simulate(plant, plan, ctrl, loop=loop, engine="python")
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    assert c.summary()["max_abs_theta_error_move"] < 2 * COUNT


def test_the_integral_removes_the_error_a_wrong_km_leaves():
    """NEMA 17 move, plant Km 10 % low, ideal measurement: the plain law keeps s2 = d/lambda of the back EMF it
    misses (0.54 count by docs/comparison.md's estimate); the integral removes most of it."""
    m = fs.MotorParams.preset("nema17")
    plan = fs.point_to_point(m, 0.0, 0.5, 1.0, 1.0, t0=0.01, tf=0.07)
    gains = design_gains(m, plan, load_torque=0.02).gains
    plant = fs.Plant(m.replace(Km=0.9 * m.Km), load=0.02)
    errors = {}
    for kind in ("dq_smc", "dq_smc_i"):
        ctrl = make_controller(kind, m, plan, control_period=TS, measurement="ideal", smc_gains=gains, v_limit=24.0)
        r = fs.simulate(plant, plan, ctrl, loop=fs.DriveLoop(control_period=TS, substeps=4), engine="c", t_end=0.08)
        errors[kind] = r.summary()["max_abs_theta_error_move"] / COUNT
    assert 0.4 < errors["dq_smc"] < 0.9
    assert errors["dq_smc_i"] < errors["dq_smc"] / 4


def test_registered_with_a_control_period(motor, plan):
    assert LABELS["dq_smc_i"].startswith("flatness") and LABELS["dq_smc_i_ff"].startswith("flatness")
    with pytest.raises(ValueError, match="control_rate"):
        make_controller("dq_smc_i", motor, plan, control_period=None, measurement="ideal")
    with pytest.raises(ValueError, match="needs the torques"):
        make_controller("dq_smc_i_ff", motor, plan, control_period=TS, measurement="ideal")
    ctrl = make_controller("dq_smc_i", motor, plan, control_period=TS, measurement="ideal", smc_gains=DESIGNED)
    assert ctrl.c_params()["integral"]["ki"] == pytest.approx(DESIGNED.W2 / DESIGNED.eps2 * DESIGNED.wn / 4)
