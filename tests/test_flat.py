"""The flat maps: proven symbolically with SymPy, then checked numerically."""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import flatstep as fs
from flatstep.model.flat import flat_voltages

# flat flag symbols: r = (rho, rho', rho''), q = (theta, ..., theta'''')
r = (sp.Symbol("r0", positive=True), *sp.symbols("r1:3", real=True))
q = sp.symbols("q0:5", real=True)
R, L, Km, J, B, Nr, tau = sp.symbols("R L K_m J B N_r tau", positive=True)


def D(expr):
    """Total time derivative along the flat flag (tau constant)."""
    return sum(sp.diff(expr, s) * ds for s, ds in zip(r[:-1] + q[:-1], r[1:] + q[1:], strict=False))


def parameterization():
    """The corrected eqs. (9)-(10) as written in docs/paper-notes.md."""
    A = J * q[2] + B * q[1] + tau
    phi = sp.acos(A / (Km * r[0])) - Nr * q[0]
    delta = Nr * q[0] + phi
    S = sp.sqrt(Km**2 * r[0] ** 2 - A**2)
    dphi = -((J * q[3] + B * q[2]) * r[0] - A * r[1]) / (r[0] * S) - Nr * q[1]
    X = L * r[1] + R * r[0] + Km * q[1] * sp.cos(delta)
    Y = L * r[0] * dphi - Km * q[1] * sp.sin(delta)
    va, vb = X * sp.sin(phi) + Y * sp.cos(phi), X * sp.cos(phi) - Y * sp.sin(phi)
    return phi, r[0] * sp.sin(phi), r[0] * sp.cos(phi), q[1], q[0], va, vb


def eq1_residuals(ia, ib, omega, theta, va, vb):
    """The residuals of eq. (1) for the given currents, speed, angle and voltages (zero along a solution)."""
    return [
        L * D(ia) - (va - R * ia + Km * omega * sp.sin(Nr * theta)),
        L * D(ib) - (vb - R * ib - Km * omega * sp.cos(Nr * theta)),
        J * D(omega) - (-Km * ia * sp.sin(Nr * theta) + Km * ib * sp.cos(Nr * theta) - B * omega - tau),
        D(theta) - omega,
    ]


def test_phi_derivative_is_the_one_used():
    """The phi derivative the map uses is the total time derivative of phi."""
    phi = parameterization()[0]
    A = J * q[2] + B * q[1] + tau
    claimed = -((J * q[3] + B * q[2]) * r[0] - A * r[1]) / (r[0] * sp.sqrt(Km**2 * r[0] ** 2 - A**2)) - Nr * q[1]
    assert sp.simplify(D(phi) - claimed) == 0


def test_parameterization_satisfies_eq1_identically():
    """The corrected parameterization satisfies eq. (1) identically."""
    phi, ia, ib, omega, theta, va, vb = parameterization()
    for res in eq1_residuals(ia, ib, omega, theta, va, vb):
        assert sp.simplify(sp.expand_trig(res)) == 0


def test_printed_eq9_matrix_does_not_satisfy_eq1():
    """The printed matrix [[cos, sin], [-sin, cos]]^-1 (eq. 9, eq. 13) is a misprint.

    At a generic point the residual of eq. (1) is nonzero, while the corrected map gives zero.
    """
    phi, ia, ib, omega, theta, va, vb = parameterization()
    c, s = sp.cos(phi), sp.sin(phi)
    X = va * s + vb * c  # recover the polar-frame voltages the paper's column vector holds
    Y = va * c - vb * s
    printed = sp.Matrix([[c, s], [-s, c]])
    M = printed.adjugate() / printed.det()  # its inverse (inv() spends 1.7 s simplifying what subs evaluates)
    va_p, vb_p = M * sp.Matrix([X, Y])
    point = {R: 8.4, L: 0.01, Km: 0.05, J: 3.6e-6, B: 1e-4, Nr: 50, tau: 0,
             r[0]: 0.4, r[1]: 1.0, r[2]: 0, q[0]: 0.01, q[1]: 2.0, q[2]: 100.0, q[3]: 1e4, q[4]: 0}
    good = eq1_residuals(ia, ib, omega, theta, va, vb)[0].subs(point)
    bad = eq1_residuals(ia, ib, omega, theta, va_p, vb_p)[0].subs(point)
    assert abs(float(good)) < 1e-12 and abs(float(bad)) > 1e-3


def test_code_equals_the_proven_formula(motor):
    """The code's flat map equals the proven formula at random flags, with a load."""
    phi, ia, ib, omega, theta, va, vb = parameterization()
    f = sp.lambdify([r[0], r[1], *q[:4], R, L, Km, J, B, Nr, tau], [ia, ib, va, vb], "numpy")
    rng = np.random.default_rng(7)
    n = 50
    flag = fs.FlatFlag(rng.uniform(0.1, 1, n), rng.normal(0, 5, n), rng.normal(0, 0.1, n),
                       rng.normal(0, 3, n), rng.normal(0, 300, n), rng.normal(0, 1e5, n))
    x, v = fs.flat_to_state(flag, motor, load_torque=2e-5)
    expected = f(*flag, motor.R, motor.L, motor.Km, motor.J, motor.B, motor.Nr, 2e-5)
    np.testing.assert_allclose(np.array([x[0], x[1], v[0], v[1]]), np.array(expected), rtol=1e-12, atol=1e-13)


def test_polar_model_eq8_matches_eq1(motor):
    """The polar model of eq. (8) is eq. (1) by the chain rule, and polar and cartesian invert each other."""
    rng = np.random.default_rng(3)
    X, V = rng.normal(size=(4, 20)), rng.normal(size=(2, 20))
    rho, phi = fs.polar(X[0], X[1])
    dz = fs.polar_rhs(np.array([rho, phi, X[2], X[3]]), V, motor, 1e-5)
    dx = fs.rhs(0.0, X, V, motor, 1e-5)
    # chain rule: ia = rho sin phi, ib = rho cos phi
    np.testing.assert_allclose(dz[0] * np.sin(phi) + rho * np.cos(phi) * dz[1], dx[0], rtol=1e-11)
    np.testing.assert_allclose(dz[0] * np.cos(phi) - rho * np.sin(phi) * dz[1], dx[1], rtol=1e-11)
    np.testing.assert_allclose(dz[2:], dx[2:], rtol=1e-13)
    np.testing.assert_allclose(fs.cartesian(rho, phi), X[:2], rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize("load", [0.0, 1e-5])
def test_round_trip_flag_state_flag(motor, plan, load):
    """Flag to state and back gives the plan's flag, with and without a load."""
    t = np.linspace(0.0, 0.06, 601)
    flag = plan.flag(t)
    x, v = fs.flat_to_state(flag, motor, load)
    back = fs.state_to_flat(x, v, motor, load)
    for a, b in zip(back, flag, strict=False):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, np.max(np.abs(b))))


def test_round_trip_state_flag_state(motor):
    """State to flag and back gives the state, on the stable branch."""
    rng = np.random.default_rng(11)
    n = 200
    rho, delta = rng.uniform(0.05, 1.0, n), rng.uniform(0.05, np.pi - 0.05, n)  # the stable branch
    theta = rng.normal(0, 0.2, n)
    phi = delta - motor.Nr * theta
    x = np.array([rho * np.sin(phi), rho * np.cos(phi), rng.normal(0, 5, n), theta])
    v = rng.normal(0, 5, (2, n))
    x2, v2 = fs.flat_to_state(fs.state_to_flat(x, v, motor), motor)
    np.testing.assert_allclose(x2, x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(v2, v, rtol=1e-12, atol=1e-11)


def test_feedforward_open_loop_reproduces_the_plan(motor, plan):
    """Feeding the feedforward voltages into an accurate integration of eq. (1) follows the plan."""
    def f(t, x):
        _, v = fs.flat_to_state(plan.flag(np.array([t])), motor)
        return fs.rhs(t, x, v[:, 0], motor)
    t = np.linspace(plan.t0, plan.tf, 201)
    sol = solve_ivp(f, (plan.t0, plan.tf), plan.x0(motor.Nr), method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14)
    x_ref, _ = fs.flat_to_state(plan.flag(t), motor)
    err = np.max(np.abs(sol.y[3] - x_ref[3]))
    assert err < 1e-9, err
    np.testing.assert_allclose(sol.y[:2], x_ref[:2], atol=1e-8)


def test_flat_maps_refuse_singular_flags(motor):
    """The flat maps refuse a torque demand beyond Km rho, rho = 0 and NaN, naming each."""
    flag = fs.FlatFlag(*(np.array([v]) for v in (0.4, 0.0, 0.0, 0.0, 6000.0, 0.0)))  # J theta'' = 0.0216 > Km rho
    with pytest.raises(ValueError, match="singular"):
        fs.flat_to_state(flag, motor)
    with pytest.raises(ValueError, match="rho=0.0"):
        fs.flat_to_state(flag._replace(rho=np.array([0.0]), ddtheta=np.array([0.0])), motor)
    with pytest.raises(ValueError, match="NaN"):
        fs.flat_to_state(flag._replace(theta=np.array([np.nan]), ddtheta=np.array([np.nan])), motor)


def test_flat_voltages_at_rest_are_ohmic(motor):
    """At rest the flat voltages are R times the equilibrium currents."""
    v = flat_voltages(motor, 0.4, 0.0, 0.02, 0.0, 0.0, 0.0, np.pi / 2 - 1.0, 0.0)
    np.testing.assert_allclose(v, 8.4 * np.array(fs.equilibrium_currents(0.02, 0.4, 50)), rtol=1e-14)
