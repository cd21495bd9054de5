import math

import numpy as np
import pytest

import flatstep as fs
from flatstep.plan.rest_to_rest import MAX_ORDER, PAPER_R

T0, TF = 0.02, 0.04


def test_psi_is_the_papers_polynomial():
    tau = np.linspace(0, 1, 11)
    r1, r2, r3, r4, r5, r6 = PAPER_R
    printed = tau**5 * (r1 - r2 * tau + r3 * tau**2 - r4 * tau**3 + r5 * tau**4 - r6 * tau**5)
    np.testing.assert_allclose(fs.psi(T0 + tau * (TF - T0), T0, TF), printed, rtol=1e-12, atol=1e-15)


def test_psi_closed_form_derivative():
    # psi'(tau) = 1260 tau^4 (1 - tau)^5: the regularized incomplete beta function I_tau(5, 6)
    tau = np.linspace(0.01, 0.99, 50)
    np.testing.assert_allclose(fs.psi(T0 + tau * (TF - T0), T0, TF, 1) * (TF - T0),
                               1260 * tau**4 * (1 - tau) ** 5, rtol=0, atol=1e-11 * 2.4609375)


def test_psi_boundary_conditions():
    assert fs.psi(T0, T0, TF) == 0.0 and fs.psi(TF, T0, TF) == pytest.approx(1.0, abs=1e-13)
    # eq. (15) and the derivative orders: 4 vanish at t0, 5 at tf, the next one does not
    from flatstep.plan.rest_to_rest import _PSI_DERIVS
    assert [abs(_PSI_DERIVS[k](0.0)) < 1e-9 for k in range(1, 6)] == [True, True, True, True, False]
    assert [abs(_PSI_DERIVS[k](1.0)) < 1e-9 for k in range(1, 6)] == [True] * 5
    assert abs(_PSI_DERIVS[0].deriv(6)(1.0)) > 1.0
    assert _PSI_DERIVS[0].degree() == 10


def test_psi_is_monotone_and_held_outside():
    t = np.linspace(0.0, 0.06, 601)
    p = fs.psi(t, T0, TF)
    assert np.all(np.diff(p) >= 0) and p[0] == 0.0 and p[-1] == 1.0
    for k in range(1, MAX_ORDER + 1):
        d = fs.psi(t, T0, TF, k)
        assert np.all(d[(t <= T0) | (t >= TF)] == 0.0)


@pytest.mark.parametrize("order", range(MAX_ORDER))
def test_psi_derivatives_against_finite_differences(order):
    t = np.linspace(T0 + 1e-3, TF - 1e-3, 37)
    h = 1e-7
    fd = (fs.psi(t + h, T0, TF, order) - fs.psi(t - h, T0, TF, order)) / (2 * h)
    exact = fs.psi(t, T0, TF, order + 1)
    scale = np.max(np.abs(exact))
    np.testing.assert_allclose(fd, exact, rtol=0, atol=1e-6 * scale)


def test_psi_bad_arguments():
    with pytest.raises(ValueError, match="order=6"):
        fs.psi(0.0, T0, TF, 6)
    with pytest.raises(ValueError, match="tf=0.01 must be greater than t0=0.02"):
        fs.psi(0.0, 0.02, 0.01)


def test_flag_follows_eqs_16_and_18():
    plan = fs.RestToRest(0.1, -0.05, 0.3, 0.5, 0.0, 0.01)
    t = np.linspace(-0.002, 0.012, 29)
    f = plan.flag(t)
    np.testing.assert_allclose(f.theta, 0.1 + fs.psi(t, 0.0, 0.01) * (-0.15), rtol=1e-14)
    np.testing.assert_allclose(f.rho, 0.3 + fs.psi(t, 0.0, 0.01) * 0.2, rtol=1e-14)
    np.testing.assert_allclose(f.dddtheta, fs.psi(t, 0.0, 0.01, 3) * (-0.15), rtol=1e-14)
    np.testing.assert_allclose(f.drho, fs.psi(t, 0.0, 0.01, 1) * 0.2, rtol=1e-14)


def test_end_states_are_equilibria(motor, plan):
    for x in (plan.x0(motor.Nr), plan.xf(motor.Nr)):
        v = motor.R * x[:2]
        np.testing.assert_allclose(fs.rhs(0.0, x, v, motor), 0.0, atol=1e-12)
    np.testing.assert_allclose(plan.x0(50), [0.4, 0.0, 0.0, 0.0], atol=1e-16)
    np.testing.assert_allclose(plan.xf(50), [0.4 * math.cos(1), 0.4 * math.sin(1), 0.0, 0.02], rtol=1e-14)


def test_from_currents_recovers_the_papers_plan():
    ia2, ib2 = 0.4 * math.cos(1.0), 0.4 * math.sin(1.0)
    plan = fs.RestToRest.from_currents(0.4, 0.0, ia2, ib2, Nr=50)
    assert (plan.theta1, plan.rho1, plan.rho2) == pytest.approx((0.0, 0.4, 0.4), abs=1e-15)
    assert plan.theta2 == pytest.approx(0.02, rel=1e-14)
    # eq. (21): rho2 = ia2 sec(Nr theta2); the paper's ia2 = 0.21588 A gives 0.39956 A, "0.4 A" in the text
    assert 0.21588 / math.cos(50 * 0.02) == pytest.approx(0.39956, abs=1e-5)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rho1=0.0), "rho1=0.0"), (dict(rho2=-0.1), "rho2=-0.1"), (dict(theta2=float("nan")), "theta2=nan"),
    (dict(t0=0.04, tf=0.02), "tf=0.02 s must be greater than t0=0.04"), (dict(tf=float("inf")), "tf=inf"),
])
def test_plan_bad_inputs(kwargs, match):
    base = dict(theta1=0.0, theta2=0.02, rho1=0.4, rho2=0.4, t0=0.02, tf=0.04)
    with pytest.raises(ValueError, match=match):
        fs.RestToRest(**{**base, **kwargs})
