"""python-control interop: flatstep's motor, flat maps and controller inside python-control, held to flatstep."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flatstep as fs
from flatstep.model.flat import flat_to_state
from flatstep.model.motor import rhs

control = pytest.importorskip("control")
interop = pytest.importorskip("flatstep.interop")

MOTORS = ["paper", "nema17"]
#: A smooth d-q flag that is no rest-to-rest move: theta and i_d as sums of sines (value, 3 derivatives).
THETA_WAVE = ((0.03, 40.0), (0.01, 170.0))
ID_WAVE = ((0.2, 60.0, 0.1),)


def dq_flag(t):
    """The d-q flag of :data:`THETA_WAVE` and :data:`ID_WAVE` at times ``t`` (exact derivatives)."""
    theta = [sum(a * w**k * np.sin(w * t + k * np.pi / 2) for a, w in THETA_WAVE) for k in range(4)]
    i_d = [sum(a * w**k * np.sin(w * t + k * np.pi / 2) + (c if k == 0 else 0.0) for a, w, c in ID_WAVE)
           for k in range(2)]
    return interop.DQFlag(*theta, *i_d)


@pytest.mark.parametrize("name", MOTORS)
def test_dq_maps_drive_the_ab_model_along_the_flag(name):
    """The d-q reverse map's voltages, integrated through eq. (1) (scipy, not the maps), give its states."""
    motor, tau = fs.MotorParams.preset(name), 2e-3
    t = np.linspace(0.0, 0.05, 501)
    x_flag, _ = interop.dq_flag_to_state(dq_flag(t), motor, tau)

    def f(s, x):
        return rhs(s, x, interop.dq_flag_to_state(dq_flag(np.asarray(s)), motor, tau)[1], motor, tau)

    sol = solve_ivp(f, (t[0], t[-1]), x_flag[:, 0], t_eval=t, method="DOP853", rtol=1e-11, atol=1e-13)
    scale = np.abs(x_flag).max(axis=1)
    assert np.all(np.abs(sol.y - x_flag).max(axis=1) < 1e-6 * scale)


@pytest.mark.parametrize("name", MOTORS)
def test_dq_forward_inverts_reverse(name):
    """The d-q forward map inverts the reverse one, and Park's q current gives the motor's torque."""
    motor, tau = fs.MotorParams.preset(name), -1e-3
    t = np.linspace(0.0, 0.05, 101)
    flag = dq_flag(t)
    x, v = interop.dq_flag_to_state(flag, motor, tau)
    back = interop.dq_state_to_flag(x, v, motor, tau)
    for want, got in zip(flag, back, strict=False):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    d, q = interop.park(x[0], x[1], x[3], motor.Nr)
    np.testing.assert_allclose(motor.Km * q, fs.model.motor.torque(x, motor), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.array(interop.inverse_park(d, q, x[3], motor.Nr)), x[:2], atol=1e-14)


def test_dq_maps_refuse_a_nonfinite_flag(motor):
    """The d-q maps refuse a flag holding a NaN, saying so."""
    flag = dq_flag(np.linspace(0, 0.01, 5))._replace(di_d=np.array([0, 0, np.nan, 0, 0]))
    with pytest.raises(ValueError, match="NaN or infinite"):
        interop.dq_flag_to_state(flag, motor)


def rest(motor, plan, end):
    """The equilibrium state and input at the start (``end=0``) or the end of ``plan``."""
    x = plan.x0(motor.Nr) if end == 0 else plan.xf(motor.Nr)
    return x, motor.R * x[:2]


@pytest.mark.parametrize("outputs", ["rho_theta", "theta_id"])
def test_point_to_point_with_psi_basis_is_flatsteps_plan(motor, plan, outputs):
    """python-control's point_to_point, on our FlatSystem with the paper's psi as basis, plans flatstep's move.

    On (rho, theta) its states and inputs are those of flatstep's plan through eqs. (9)-(10); on (theta, i_d)
    its theta is the plan's theta* and its ends are the plan's equilibria.
    """
    sys = interop.flatsys(motor, outputs)
    t = np.linspace(plan.t0, plan.tf, 201)
    traj = control.flatsys.point_to_point(sys, t, *rest(motor, plan, 0), *rest(motor, plan, 1),
                                          basis=interop.PsiFamily(interop.FLAG_LENGTHS[outputs], plan.t0, plan.tf))
    x, v = traj.eval(t)
    x_plan, v_plan = flat_to_state(plan.flag(t), motor)
    np.testing.assert_allclose(x[3], x_plan[3], atol=1e-10 * plan.theta2)
    np.testing.assert_allclose(x[2], x_plan[2], atol=1e-8 * np.abs(x_plan[2]).max())
    np.testing.assert_allclose(x[:, [0, -1]], np.c_[plan.x0(motor.Nr), plan.xf(motor.Nr)], atol=1e-9)
    if outputs == "rho_theta":
        np.testing.assert_allclose(x, x_plan, atol=1e-9)
        np.testing.assert_allclose(v, v_plan, atol=1e-8 * np.abs(v_plan).max())


@pytest.mark.parametrize("outputs", ["rho_theta", "theta_id"])
def test_point_to_point_feedforward_drives_our_nlsys_along_the_move(motor, plan, outputs):
    """python-control's own polynomial point_to_point moves the motor along the planned states.

    Its voltages, fed to our nlsys in input_output_response, take the motor from the plan's start equilibrium to
    its end one.
    """
    sys = interop.flatsys(motor, outputs)
    t = np.linspace(plan.t0, plan.tf, 1001)
    traj = control.flatsys.point_to_point(sys, t, *rest(motor, plan, 0), *rest(motor, plan, 1),
                                          basis=control.flatsys.PolyFamily(8, plan.tf - plan.t0))
    x, v = traj.eval(t)
    resp = control.input_output_response(interop.nlsys(motor), t - t[0], v, X0=x[:, 0],
                                         solve_ivp_kwargs=dict(method="LSODA", rtol=1e-10, atol=1e-12))
    assert resp.outputs.shape == (5, t.size)
    err = np.abs(resp.outputs[:4] - x).max(axis=1)
    assert err[3] < 1e-3 * plan.theta2, err      # inputs are interpolated linearly between 1001 samples
    assert err[2] < 1e-3 * np.abs(x[2]).max(), err
    np.testing.assert_allclose(resp.outputs[:4, -1], plan.xf(motor.Nr), atol=2e-4)


def plant_cases(motor):
    """Plants to close the loop on: a load, and the effects eq. (1) leaves out (detent, Coulomb, iron loss)."""
    return [fs.Plant(motor, load=1e-5),
            fs.Plant(motor, fs.PlantEffects(detent_torque=5e-5, coulomb_torque=1e-4, coulomb_speed=1.0,
                                               magnetizing_resistance=200.0), load=1e-5)]


@pytest.mark.parametrize("case", [0, 1])
def test_closed_loop_in_python_control_equals_flatstep_simulate(motor, plan, case):
    """The loop nlsys + controller_nlsys, closed by control.interconnect and solved by input_output_response.

    Its states are those of flatstep.simulate's continuous C engine (the paper's Fig. 2 run) to 1e-7 rad
    (5e-6 of the move) and 1e-6 A, compared every 0.1 ms (501 instants: python-control evaluates the loop's
    outputs in Python at each, two thirds of the time at the default 10 us; the largest differences, 2e-10 rad and
    8e-9 A, are the same on both grids).
    """
    plant = plant_cases(motor)[case]
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(W1=300.0, W2=300.0), measurement="ideal")
    res = fs.simulate(plant, plan, ctrl, t_end=0.05, solver=fs.Continuous(dt_out=1e-4))
    loop = control.interconnect([interop.nlsys(plant), interop.controller_nlsys(ctrl)], inplist=[],
                                outlist=["ia", "ib", "omega", "theta", "va", "vb"])
    resp = control.input_output_response(loop, res.t, 0, X0=plan.x0(motor.Nr),
                                         solve_ivp_kwargs=dict(method="LSODA", rtol=1e-9, atol=1e-12))
    y = resp.outputs
    assert np.abs(y[3] - res.theta).max() < 1e-7
    assert np.abs(y[2] - res.omega).max() < 1e-6 * np.abs(res.omega).max()
    assert np.abs(y[:2] - np.array([res.ia, res.ib])).max() < 1e-6
    assert np.abs(y[4:] - np.array([res.va, res.vb])).max() < 1e-4 * np.abs(res.va).max()
    assert res.summary()["status"] == "ok"


def test_nlsys_load_input_adds_to_the_plants_load(motor):
    """A load input of nlsys adds to the plant's load, and a load function of time is read at the time."""
    plant = fs.Plant(motor, load=1e-5)
    x, v = np.array([0.3, -0.2, 4.0, 0.01]), np.array([2.0, -1.0])
    with_input = interop.nlsys(plant, load_input=True)
    assert with_input.input_labels == ["va", "vb", "tau"]
    both = fs.Plant(motor, load=3e-5)
    np.testing.assert_allclose(with_input.dynamics(0.0, x, [*v, 2e-5]), interop.nlsys(both).dynamics(0.0, x, v))
    np.testing.assert_allclose(with_input.output(0.0, x, [*v, 2e-5])[4], both.acceleration(x))
    assert interop.nlsys(motor).output_labels == ["ia", "ib", "omega", "theta", "ddtheta"]
    varying = interop.nlsys(fs.Plant(motor, load=lambda t: 1e-5 * np.sin(40.0 * t)))   # a load function of time
    at_t = interop.nlsys(fs.Plant(motor, load=1e-5 * np.sin(40.0 * 0.03)))
    np.testing.assert_allclose(varying.dynamics(0.03, x, v), at_t.dynamics(0.03, x, v))
    assert varying.dynamics(0.03, x, v)[2] != interop.nlsys(motor).dynamics(0.03, x, v)[2]


def test_flatsys_load_from_params_and_forward_reverse(motor, plan):
    """The flat system's forward and reverse maps invert each other, with the load from its params."""
    sys = interop.flatsys(motor, "rho_theta", load_torque=1e-5)
    t = np.array([0.025, 0.03, 0.035])
    x, v = flat_to_state(plan.flag(t), motor, 1e-5)
    zflag = sys.forward(x[:, 1], v[:, 1])
    assert [len(z) for z in zflag] == [2, 4]
    np.testing.assert_allclose(zflag[1][2], plan.flag(t).ddtheta[1], rtol=1e-9)
    x_back, v_back = sys.reverse(zflag)
    np.testing.assert_allclose(x_back, x[:, 1], rtol=1e-10, atol=1e-12)
    other = sys.forward(x[:, 1], v[:, 1], {"load_torque": 2e-5})
    np.testing.assert_allclose(other[1][2] - zflag[1][2], -1e-5 / motor.J, rtol=1e-6)


def test_bad_requests_are_refused(motor, plan):
    """Bad outputs, plants, loads, controllers, psi families and torque demands are refused, naming them."""
    with pytest.raises(ValueError, match="outputs='rho_phi' is not a choice.*valid"):
        interop.flatsys(motor, "rho_phi")
    with pytest.raises(ValueError, match="not a flatstep Plant or MotorParams"):
        interop.nlsys("paper")
    with pytest.raises(ValueError, match="load_torque=nan"):
        interop.flatsys(motor, load_torque=float("nan"))
    cascade = fs.control.make_controller("cascade", motor, plan, control_period=5e-5, measurement="model")
    with pytest.raises(ValueError, match="not a static controller"):
        interop.controller_nlsys(cascade)
    with pytest.raises(ValueError, match="tf=0.01 s must be greater than t0=0.02 s"):
        interop.PsiFamily((2, 4), 0.02, 0.01)
    with pytest.raises(ValueError, match=r"flaglen=\[2, 7\]"):
        interop.PsiFamily((2, 7), 0.0, 1.0)
    with pytest.raises(ValueError, match="torque demand"):
        interop.flatsys(motor).reverse([np.array([0.01, 0.0]), np.array([0.0, 0.0, 1e6, 0.0])])
