"""The d-q flat maps (theta, i_d): proven symbolically with SymPy, then checked numerically."""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import flatstep as fs
from flatstep.model.flat_dq import DQFlag, dq_to_state, inverse_park, park, state_to_dq
from flatstep.model.plant import Plant, PlantEffects, plant_rhs
from flatstep.model.torque_model import TorqueModel

# flat flag symbols: q = (theta, ..., theta''''), d = (i_d, i_d', i_d''); the load tau(t) as l = (tau, tau', tau'')
q = sp.symbols("q0:5", real=True)
d = sp.symbols("d0:3", real=True)
lo = sp.symbols("l0:3", real=True)
R, L, Km, J, B, Nr, Td, Tc, ws, h = sp.symbols("R L K_m J B N_r T_d T_c omega_s h", positive=True)
ph = sp.Symbol("varphi", real=True)
CHAINS = (q, d, lo)


def D(expr):
    """Total time derivative along the flag and the load."""
    return sum(sp.diff(expr, c[k]) * c[k + 1] for c in CHAINS for k in range(len(c) - 1))


def torque(theta, omega, effects):
    """E of flatstep.model.torque_model: load, detent with phase, smooth Coulomb (or the load alone)."""
    return lo[0] + (Td * sp.sin(h * Nr * theta + ph) + Tc * sp.tanh(omega / ws) if effects else 0)


def parameterization(effects):
    """The map of flatstep.model.flat_dq as written in its docstring, with the torque rate from torque_rate()."""
    E = torque(q[0], q[1], effects)
    dE = lo[1] + (Td * h * Nr * sp.cos(h * Nr * q[0] + ph) * q[1]
                  + Tc / ws * (1 - sp.tanh(q[1] / ws) ** 2) * q[2] if effects else 0)
    iq = (J * q[2] + B * q[1] + E) / Km
    diq = (J * q[3] + B * q[2] + dE) / Km
    vd = L * d[1] + R * d[0] - L * Nr * q[1] * iq
    vq = L * diq + R * iq + L * Nr * q[1] * d[0] + Km * q[1]
    c, s = sp.cos(Nr * q[0]), sp.sin(Nr * q[0])
    return d[0] * c - iq * s, d[0] * s + iq * c, q[1], q[0], vd * c - vq * s, vd * s + vq * c, dE, E


def eq1_residuals(ia, ib, omega, theta, va, vb, effects):
    """Eq. (1) with the modelled torques E on the shaft."""
    return [
        L * D(ia) - (va - R * ia + Km * omega * sp.sin(Nr * theta)),
        L * D(ib) - (vb - R * ib - Km * omega * sp.cos(Nr * theta)),
        J * D(omega) - (-Km * ia * sp.sin(Nr * theta) + Km * ib * sp.cos(Nr * theta) - B * omega
                        - torque(theta, omega, effects)),
        D(theta) - omega,
    ]


def vanishes(expr):
    """Whether ``expr`` is identically zero.

    Trig functions of sums expanded, sin^2(Nr q0) written 1 - cos^2(Nr q0), then expanded: exact, and a hundred
    times faster than ``sp.simplify`` on the torque equation.
    """
    s, c = sp.sin(Nr * q[0]), sp.cos(Nr * q[0])
    return sp.expand(sp.expand(sp.expand_trig(expr)).subs(s**2, 1 - c**2)) == 0


@pytest.mark.parametrize("effects", [False, True], ids=["eq1", "eq1+detent+coulomb+load(t)"])
def test_parameterization_satisfies_eq1_identically(effects):
    """The d-q map satisfies eq. (1) identically, with and without the torques; a wrong voltage does not."""
    ia, ib, omega, theta, va, vb, dE, E = parameterization(effects)
    assert vanishes(D(E) - dE)  # the torque rate used is the derivative of the torque
    for res in eq1_residuals(ia, ib, omega, theta, va, vb, effects):
        assert vanishes(res)
    assert not vanishes(eq1_residuals(ia, ib, omega, theta, va + L * Nr * q[1], vb, effects)[0])  # it can fail


def test_code_equals_the_proven_formula(motor):
    """The code's d-q map equals the proven formula at random flags, with detent, Coulomb and a changing load."""
    ia, ib, _, _, va, vb, _, _ = parameterization(True)
    f = sp.lambdify([*q[:4], *d[:2], lo[0], lo[1], R, L, Km, J, B, Nr, Td, Tc, ws, h, ph], [ia, ib, va, vb], "numpy")
    rng = np.random.default_rng(7)
    n = 50
    flag = DQFlag(rng.normal(0, 0.1, n), rng.normal(0, 3, n), rng.normal(0, 300, n), rng.normal(0, 1e5, n),
                  rng.normal(0, 0.3, n), rng.normal(0, 20, n))
    tm = TorqueModel(detent_torque=1e-3, detent_harmonic=4, detent_phase=0.3, coulomb_torque=2e-4,
                     coulomb_speed=0.5, load=1e-5, load_step=3e-5, load_t0=0.01, load_tf=0.03)
    t = rng.uniform(0.0, 0.04, n)
    x, v = dq_to_state(flag, motor, tm, t)
    tau, dtau = tm.load_torque(t)
    assert np.ptp(tau) > 1e-5 and np.max(np.abs(dtau)) > 1e-3  # the load does change along these times
    expected = f(*flag, tau, dtau, motor.R, motor.L, motor.Km, motor.J, motor.B, motor.Nr, 1e-3, 2e-4, 0.5, 4, 0.3)
    np.testing.assert_allclose(np.array([x[0], x[1], v[0], v[1]]), np.array(expected), rtol=1e-11, atol=1e-12)


def test_park_is_a_rotation_and_its_inverse():
    """Park's transform keeps the current's magnitude, and inverse_park undoes it."""
    rng = np.random.default_rng(1)
    a, b, p = rng.normal(size=(3, 30))
    dd, qq = park(a, b, p)
    np.testing.assert_allclose(np.hypot(dd, qq), np.hypot(a, b), rtol=1e-14)
    np.testing.assert_allclose(inverse_park(dd, qq, p), [a, b], rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("tm", [TorqueModel(), TorqueModel(detent_torque=1e-3, detent_phase=-0.4, coulomb_torque=2e-4,
                                                           coulomb_speed=0.5, load=1e-5)], ids=["plain", "effects"])
def test_round_trip_flag_state_flag(motor, plan, tm):
    """Flag to state and back gives the flag, with and without the torque model's effects."""
    t = np.linspace(0.0, 0.06, 601)
    ref = plan.flag(t)
    flag = DQFlag(ref.theta, ref.dtheta, ref.ddtheta, ref.dddtheta, 0.1 * np.sin(200 * t), 20 * np.cos(200 * t))
    x, v = dq_to_state(flag, motor, tm, t)
    back = state_to_dq(x, v, motor, tm, t)
    for a, b in zip(back, flag, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10 * max(1.0, np.max(np.abs(b))))


def test_round_trip_state_flag_state(motor):
    """State to flag and back gives the state."""
    rng = np.random.default_rng(11)
    x = rng.normal(0, [0.5, 0.5, 5, 0.2], (200, 4)).T
    v = rng.normal(0, 5, (2, 200))
    x2, v2 = dq_to_state(state_to_dq(x, v, motor), motor)
    np.testing.assert_allclose(x2, x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(v2, v, rtol=1e-12, atol=1e-11)


def test_with_i_d_equal_to_rho_at_rest_it_is_the_polar_map(motor, plan):
    """At rest with no demand the d axis carries the whole current: the (rho, theta) map's rest state."""
    flag = plan.flag(np.array([0.0, 0.06]))
    x_polar, v_polar = fs.flat_to_state(flag, motor)
    zero = np.zeros(2)
    x, v = dq_to_state(DQFlag(flag.theta, zero, zero, zero, flag.rho, zero), motor)
    np.testing.assert_allclose(x, x_polar, atol=1e-15)
    np.testing.assert_allclose(v, v_polar, atol=1e-13)


def test_no_singularity_where_the_polar_map_has_one(motor):
    """A torque demand above Km rho is out of reach of (rho, theta) at rho = 0.4 A, never of (theta, i_d)."""
    flag = DQFlag(*(np.array([v]) for v in (0.0, 0.0, 6000.0, 0.0, 0.0, 0.0)))
    x, v = dq_to_state(flag, motor)
    assert np.isclose(x[1, 0], motor.J * 6000.0 / motor.Km) and np.all(np.isfinite(v))
    with pytest.raises(ValueError, match="NaN"):
        dq_to_state(flag._replace(i_d=np.array([np.nan])), motor)


@pytest.mark.parametrize("with_effects", [False, True])
def test_feedforward_open_loop_reproduces_the_plan(motor, plan, with_effects):
    """The feedforward voltages of the map, fed into eq. (1) with the plant's effects, follow the plan.

    The torque model knows the effects exactly; without it the effects throw the rotor off the plan.
    """
    effects = PlantEffects(detent_torque=1e-3, coulomb_torque=2e-4, coulomb_speed=0.5) if with_effects else None
    plant = Plant(motor, effects=effects, load=1e-5)
    known = TorqueModel.of_plant(plant)

    def flag_at(t):
        f = plan.flag(np.array([t]))
        return DQFlag(f.theta, f.dtheta, f.ddtheta, f.dddtheta, np.zeros(1), np.zeros(1))

    def run(tm):
        def f(t, x):
            _, v = dq_to_state(flag_at(t), motor, tm, t)
            return plant_rhs(x, v[:, 0], motor, 1e-5, effects)
        x0 = dq_to_state(flag_at(plan.t0), motor, tm, plan.t0)[0][:, 0]
        return solve_ivp(f, (plan.t0, plan.tf), x0, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14)
    t = np.linspace(plan.t0, plan.tf, 201)
    theta_ref = plan.flag(t).theta
    assert np.max(np.abs(run(known).y[3] - theta_ref)) < 1e-9
    if with_effects:
        assert np.max(np.abs(run(TorqueModel(load=1e-5)).y[3] - theta_ref)) > 1e-5
