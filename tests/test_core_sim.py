"""The C engine's closed loops: continuous runs against the scipy reference, sampled runs against a Python
zero-order-hold loop, and simulate()'s settings and errors for engine='c'."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flatstep as fs
from flatstep.control.smc import FlatnessSMC, SMCGains
from flatstep.model.motor import rhs

PAPER = fs.MotorParams.preset("paper")
W300 = SMCGains(W1=300.0, W2=300.0)
RUNS = {  # name: (plant, controller, load); the controller's model is always the paper's motor
    "fig1": (PAPER, FlatnessSMC(PAPER, fs.PAPER_PLAN), 0.0),
    "fig2": (PAPER, FlatnessSMC(PAPER, fs.PAPER_PLAN, W300), 1e-5),
    "fig2_model_measurement": (PAPER, FlatnessSMC(PAPER, fs.PAPER_PLAN, W300, "model"), 1e-5),
    "plant_R_plus_20pc": (PAPER.replace(R=1.2 * PAPER.R), FlatnessSMC(PAPER, fs.PAPER_PLAN, W300), 0.0),
}


LSODA = fs.Continuous(method="LSODA")  # the scipy reference at the default tolerances


def run(name, **options):
    plant, ctrl, load = RUNS[name]
    return fs.simulate(fs.Plant(plant, load=load), fs.PAPER_PLAN, ctrl, **options)


def sampled(Ts, substeps):
    return fs.DriveLoop(control_period=Ts, substeps=substeps)


@pytest.mark.parametrize("name", RUNS)
def test_continuous_c_engine_matches_scipy_reference(name):
    """Both at their defaults (rtol 1e-10, atol 1e-12): measured max |dtheta| 7.7e-10 rad (fig1),
    4.3e-10 (fig2), 1.5e-9 (model measurement), 2.5e-9 (R + 20 %)."""
    c, ref = run(name, engine="c"), run(name, engine="scipy", solver=LSODA)
    np.testing.assert_array_equal(c.t, ref.t)
    assert np.max(np.abs(c.theta - ref.theta)) < 1e-8
    assert np.max(np.abs(c.rho - ref.rho)) < 1e-7


@pytest.mark.parametrize("name", RUNS)
def test_c_result_assembly_matches_the_numpy_one(name):
    """simulate(engine='c') assembles its SimResult in one C call (core.result_columns); NumPy's assemble()
    on the same states gives the same series: references bit for bit (plan_flag is exact), the rest to
    rounding (measured: voltages 5.2e-14 V, reference voltages 1.6e-15 V, phi 2.2e-16 rad)."""
    from flatstep.engine.simulate import Run, assemble

    plant, ctrl, load = RUNS[name]
    c = run(name, engine="c")
    X = np.array([c.ia, c.ib, c.omega, c.theta])
    ref = assemble(Run(c.t, X, {}), fs.Plant(plant, load=load), fs.PAPER_PLAN, ctrl, fs.Continuous())
    for key in ("theta_ref", "omega_ref", "rho_ref", "rho", "s1"):
        np.testing.assert_array_equal(getattr(c, key), getattr(ref, key), err_msg=key)
    for key, tol in (("va", 1e-12), ("vb", 1e-12), ("phi", 1e-15), ("ia_ref", 1e-15), ("ib_ref", 1e-15),
                     ("va_ref", 1e-14), ("vb_ref", 1e-14), ("s2", 1e-9)):
        assert np.max(np.abs(getattr(c, key) - getattr(ref, key))) <= tol, key
    cs, rs = c.summary(), ref.summary()
    assert (cs.pop("status"), cs.pop("lost_at")) == (rs.pop("status"), rs.pop("lost_at"))
    assert cs == pytest.approx(rs, rel=1e-12, abs=1e-15)


def test_plan_to_state_is_plan_flag_then_flat_to_state():
    from flatstep import core

    t = np.linspace(0.0, 0.06, 301)
    x, v = core.plan_to_state(fs.PAPER_PLAN, PAPER, t, 1e-5)
    x_ref, v_ref = core.flat_to_state(core.plan_flag(fs.PAPER_PLAN, t), PAPER, 1e-5)
    np.testing.assert_array_equal(x, x_ref)
    np.testing.assert_array_equal(v, v_ref)
    with pytest.raises(ValueError, match="outside the domain of the flat maps"):
        core.plan_to_state(fs.PAPER_PLAN, PAPER, t, 1.0)  # a load torque far beyond Km rho


def test_continuous_c_engine_converges_to_the_reference_at_tighter_tolerances():
    """DOPRI5 and DOP853 both at rtol 1e-12, atol 1e-14: measured max |dtheta| 6.4e-12 rad, |dia| 1.1e-10 A."""
    c = run("fig1", engine="c", solver=fs.Continuous(rtol=1e-12, atol=1e-14))
    ref = run("fig1", engine="scipy", solver=fs.Continuous("DOP853", rtol=1e-12, atol=1e-14, max_wall_time=300.0))
    assert np.max(np.abs(c.theta - ref.theta)) < 3e-11
    assert np.max(np.abs(c.ia - ref.ia)) < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fig1", "fig2"])
def test_continuous_c_engine_converges_to_the_reference_at_tight_tolerances(name):
    """DOPRI5 and DOP853 both at rtol 1e-13, atol 1e-15: measured max |dtheta| 5.0e-13 (fig1), 1.5e-14 (fig2)."""
    c = run(name, engine="c", solver=fs.Continuous(rtol=1e-13, atol=1e-15))
    ref = run(name, engine="scipy", solver=fs.Continuous("DOP853", rtol=1e-13, atol=1e-15, max_wall_time=300.0))
    assert np.max(np.abs(c.theta - ref.theta)) < 5e-12
    assert np.max(np.abs(c.ia - ref.ia)) < 1e-10


def test_c_engine_result_is_the_reference_collect():
    """Voltages on the samples come from C smc_step; they are the reference law's to rounding."""
    r = run("fig2")
    _, ctrl, load = RUNS["fig2"]
    x = np.array([r.ia, r.ib, r.omega, r.theta])
    acc = (fs.model.motor.torque(x, PAPER) - PAPER.B * r.omega - load) / PAPER.J
    v = ctrl.voltages(r.t, x, acc)
    np.testing.assert_allclose([r.va, r.vb], v, rtol=1e-12, atol=1e-12)
    assert r.meta["engine"] == "c" and r.meta["method"] == "DOP853" and r.meta["controller_status"] == []
    assert r.meta["steps"] > 100 and r.meta["rhs_evals"] >= 12 * r.meta["steps"]


@pytest.mark.parametrize("method, lo, hi", [("DOP853", 12, 12), ("DOPRI5", 6, 6), ("DOP853-dense7", 12, 15)])
def test_every_c_integrator_tracks_fig1_and_matches_the_default(method, lo, hi):
    """continuous_run's three integrators: Fig. 1 starts on the plan, so theta*(t) is the exact angle; at rtol
    1e-10 each stays within 1e-9 rad of it, and the currents agree with the default's to 1e-7 A. Evaluations
    per accepted step: 12 (DOP853), 6 (DOPRI5), up to 3 more where a step holds an output time (dense7)."""
    from flatstep import core

    plant, ctrl, load = RUNS["fig1"]
    p = fs.PAPER_PLAN
    t = np.linspace(0.0, 0.06, 601)
    X, st = core.run_continuous(ctrl, plant, load, p.x0(plant.Nr), t, rtol=1e-10, atol=1e-12, method=method)
    X0, _ = core.run_continuous(ctrl, plant, load, p.x0(plant.Nr), t, rtol=1e-10, atol=1e-12)
    assert np.abs(X[3] - p.flag(t).theta).max() < 1e-9
    assert np.abs(X[:2] - X0[:2]).max() < 1e-7
    assert lo * st["steps"] <= st["rhs_evals"] <= hi * st["steps"] + (lo + 1) * st["rejected"] + 6
    with pytest.raises(ValueError, match="not a C integrator"):
        core.run_continuous(ctrl, plant, load, p.x0(plant.Nr), t, rtol=1e-10, atol=1e-12, method="RK45")


def zoh_reference(plant, ctrl, load, Ts, n):
    """A Python sampled loop: the reference law at t = k Ts, voltage held, plant by DOP853 at rtol 1e-12."""
    x, xs = fs.PAPER_PLAN.x0(plant.Nr), []
    for k in range(n + 1):
        xs.append(x)
        if k == n:
            break
        acc = (fs.model.motor.torque(x, plant) - plant.B * x[2] - load) / plant.J
        v = ctrl.voltages(k * Ts, x, acc if ctrl.measurement == "ideal" else None)
        sol = solve_ivp(lambda t, y: rhs(t, y, v, plant, load), (k * Ts, (k + 1) * Ts), x, method="DOP853",
                        rtol=1e-12, atol=1e-14)
        x = sol.y[:, -1]
    return np.array(xs).T


@pytest.mark.parametrize("name, Ts, t_end", [("fig1", 5e-5, 0.06), ("fig2_model_measurement", 2e-5, 0.04)])
def test_sampled_c_engine_matches_a_python_zoh_loop(name, Ts, t_end):
    """10 RK4 substeps per period: measured max |dtheta| 6.3e-13 rad (fig1). (Fig. 2's loop at Ts = 50 us
    amplifies rounding-level differences to 1e-6 A in a few periods, so it is compared at 20 us.)"""
    plant, ctrl, load = RUNS[name]
    n = int(round(t_end / Ts))
    r = run(name, loop=sampled(Ts, 10), t_end=t_end)
    assert r.t.size == n + 1 and r.t[-1] == pytest.approx(t_end) and np.all(np.diff(r.t) == pytest.approx(Ts))
    X = zoh_reference(plant, ctrl, load, Ts, n)
    assert np.max(np.abs(r.theta - X[3])) < 1e-10
    assert np.max(np.abs(r.ia - X[0])) < 1e-9
    assert r.meta["method"] == "RK4" and r.meta["control_period"] == Ts and r.meta["substeps"] == 10


def test_sampled_loop_approaches_the_continuous_one_as_the_period_shrinks():
    """The paper's law is a continuous-time design: under a ZOH its angle error grows quickly with Ts
    (measured 2.5e-2, 8.4e-3, 2.6e-4 rad at Ts = 40, 10, 1 us)."""
    cont = run("fig1")
    errors = []
    for Ts in (4e-5, 1e-5, 1e-6):
        r = run("fig1", loop=sampled(Ts, 4))
        errors.append(np.max(np.abs(np.interp(cont.t, r.t, r.theta) - cont.theta)))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-3


def test_sampled_voltages_are_the_applied_ones():
    r = run("fig1", loop=sampled(1e-4, 5))
    _, ctrl, _ = RUNS["fig1"]
    x = np.array([r.ia, r.ib, r.omega, r.theta])
    acc = (fs.model.motor.torque(x, PAPER) - PAPER.B * r.omega) / PAPER.J
    np.testing.assert_allclose([r.va, r.vb], ctrl.voltages(r.t, x, acc), rtol=1e-12, atol=1e-12)


def test_sampled_loop_reports_controller_faults_instead_of_nan():
    """From zero currents the law is undefined: the C controller applies 0 V and says why."""
    r = fs.simulate(PAPER, fs.PAPER_PLAN, x0=[0.0, 0.0, 0.0, 0.0], loop=sampled(1e-4, 10))
    assert r.meta["controller_status"] == ["rho"]
    assert np.all(r.va == 0.0) and np.all(r.ia == 0.0)


def test_continuous_loop_stops_outside_the_laws_domain():
    with pytest.raises(RuntimeError, match="controller faulted"):
        fs.simulate(PAPER, fs.PAPER_PLAN, x0=[0.0, 0.0, 0.0, 0.0])


def test_c_engine_is_the_default():
    r = fs.simulate(PAPER, fs.PAPER_PLAN, t_end=0.04, solver=fs.Continuous(dt_out=1e-3))
    assert r.meta["engine"] == "c" and r.t.size == 41
    r = fs.simulate(PAPER, fs.PAPER_PLAN, t_end=0.04, loop=sampled(1e-3, 4))
    assert r.meta["engine"] == "c" and r.t.size == 41


@pytest.mark.parametrize("kwargs, match", [
    (dict(engine="scipy", loop=sampled(1e-4, 4)), r"engine='scipy' does not run sampled control; valid: \['c', "),
    (dict(solver=fs.Continuous(method="RK45")), "method='RK45' is not a C integrator"),
    (dict(plant=fs.Plant(PAPER, load=lambda t: 0.0 * t)), "engine='c' takes a constant load torque"),
    (dict(plant=fs.Plant(PAPER, load=lambda t: 0.0 * t), loop=sampled(1e-4, 4)),
     "engine='c' takes a constant load torque"),
])
def test_bad_c_engine_options(kwargs, match):
    plant = kwargs.pop("plant", PAPER)
    with pytest.raises(ValueError, match=match):
        fs.simulate(plant, fs.PAPER_PLAN, **kwargs)
