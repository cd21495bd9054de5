"""The sliding-mode law tracking a segment table: C against the Python reference, and a table against psi."""
import numpy as np
import pytest

from flatstep import core
from flatstep.core.structs import smc_struct
from flatstep._flatstep_core import ffi, lib
from flatstep.control.smc import FlatnessSMC, SMCGains
from flatstep.engine.simulate import simulate
from flatstep.loop.reference import DriveLoop
from flatstep.model.motor import PRESETS
from flatstep.plan.piecewise import PiecewisePlan
from flatstep.plan.rest_to_rest import RestToRest
from flatstep.plan.waypoints import Caps, Waypoint, plan_waypoints

MOTOR = PRESETS["paper"]


@pytest.fixture(scope="module")
def sequence():
    """A four-waypoint Hermite move with a dwell, slow enough for the paper's gains."""
    return plan_waypoints([0.0, 0.02, Waypoint(0.05, dwell=0.01), -0.01], family="hermite", rho=0.4, t0=0.01,
                          caps=Caps(3.0, 300.0, 3e4))


@pytest.mark.parametrize("measurement", ["ideal", "model"])
def test_c_law_on_a_table_is_the_python_law(sequence, measurement):
    ctrl = FlatnessSMC(MOTOR, sequence, SMCGains(hold_damping=0.7), measurement)
    rng = np.random.default_rng(7)
    t = np.sort(rng.uniform(0.0, sequence.tf + 0.02, 500))
    ref = sequence.flag(t)
    x = np.array([0.4 * np.sin(50 * ref.theta), 0.4 * np.cos(50 * ref.theta), ref.dtheta, ref.theta])
    x += rng.normal(scale=[[0.01], [0.01], [0.5], [1e-3]], size=x.shape)
    acc = ref.ddtheta + rng.normal(scale=10.0, size=t.size)
    v_c, status = core.smc_voltages(ctrl, t, x, acc if measurement == "ideal" else None)
    v_py = ctrl.voltages(t, x, acc if measurement == "ideal" else None)
    assert not status.any()
    np.testing.assert_allclose(v_c, v_py, rtol=1e-11, atol=1e-11 * np.max(np.abs(v_py)))
    assert np.any(t > sequence.tf) and np.any(t < sequence.breaks[2])  # the hold and the moves are both sampled


def test_the_c_reference_is_the_table(sequence):
    s = smc_struct(FlatnessSMC(MOTOR, sequence))
    assert s.plan.traj != ffi.NULL and s.p.plan.traj == s.plan.traj
    flag = ffi.new("double[6]")
    for t in np.linspace(0.0, sequence.tf + 0.01, 97):
        lib.plan_flag(ffi.addressof(s, "plan"), t, flag)
        np.testing.assert_array_equal(list(flag), np.array(sequence.flag(t)))


def test_smc_init_refuses_a_broken_table():
    params = FlatnessSMC(MOTOR, PiecewisePlan.from_rest_to_rest(RestToRest(0.0, 0.02, 0.4, 0.4))).c_params()
    table = params["plan"]["traj"]
    broken = ffi.new("struct traj *", dict(n=0, breaks=table.breaks, theta=table.theta, rho=table.rho))
    s = ffi.new("struct smc *")
    bad = {**params, "plan": {**params["plan"], "traj": broken}}
    assert lib.smc_init(s, ffi.new("struct smc_params *", bad)) == lib.SMC_EPLAN
    assert lib.smc_init(s, ffi.new("struct smc_params *", params)) == lib.SMC_PARAMS_OK


def test_a_one_segment_table_runs_as_the_paper_move():
    plan = RestToRest(0.0, 0.05, 0.4, 0.5, 0.01, 0.04)
    table = PiecewisePlan.from_rest_to_rest(plan)
    a = simulate(MOTOR, plan, FlatnessSMC(MOTOR, plan), t_end=0.06)
    b = simulate(MOTOR, table, FlatnessSMC(MOTOR, table), t_end=0.06)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_allclose(b.theta, a.theta, atol=1e-9)
    np.testing.assert_allclose(b.rho, a.rho, atol=1e-9)
    assert b.meta["plan"]["tf"] == 0.04 and abs(b.meta["plan"]["theta2"] - 0.05) < 1e-12


def test_a_waypoint_sequence_runs_on_every_engine(sequence):
    ctrl = FlatnessSMC(MOTOR, sequence)
    t_end = sequence.tf + 0.02
    c = simulate(MOTOR, sequence, ctrl, engine="c", t_end=t_end)
    sp = simulate(MOTOR, sequence, ctrl, engine="scipy", t_end=t_end)
    for r in (c, sp):  # the continuous law tracks the whole sequence, the dwell included
        assert np.max(np.abs(r.theta - r.theta_ref)) < 1e-6
        assert abs(r.theta[-1] - sequence.theta2) < 1e-6
    dwell = (c.t > sequence.breaks[2] + 1e-4) & (c.t < sequence.breaks[3] - 1e-4)
    assert dwell.sum() > 5 and np.max(np.abs(c.theta[dwell] - 0.05)) < 1e-6
    loop = DriveLoop(control_period=2e-5, substeps=2)
    s_c = simulate(MOTOR, sequence, ctrl, engine="c", loop=loop, t_end=t_end)
    s_py = simulate(MOTOR, sequence, ctrl, engine="python", loop=loop, t_end=t_end)
    np.testing.assert_allclose(s_c.theta, s_py.theta, atol=1e-10)
    np.testing.assert_allclose(s_c.va, s_py.va, rtol=1e-8, atol=1e-8)

