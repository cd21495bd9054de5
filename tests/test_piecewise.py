"""Segment tables (flatstep.plan.piecewise): the C evaluator against the Python one, psi as one segment, PPoly."""
import numpy as np
import pytest

from flatstep.core.traj import traj_flag, traj_theta, traj_valid
from flatstep.plan.piecewise import NCOEF, PiecewisePlan
from flatstep.plan.rest_to_rest import RestToRest


@pytest.fixture
def table():
    """Five segments of random degree-10 polynomials of uneven durations, rho linear and > 0."""
    rng = np.random.default_rng(13)
    breaks = np.concatenate([[0.01], 0.01 + np.cumsum(rng.uniform(0.002, 0.05, 5))])
    rho = np.column_stack([0.1 * rng.uniform(-1, 1, 5), np.full(5, 0.8)])
    return PiecewisePlan(breaks, rng.normal(size=(5, NCOEF)), rho)


def times(plan, n=2001):
    """Samples over and around the move, every break and NaN included."""
    span = plan.tf - plan.t0
    t = np.linspace(plan.t0 - 0.1 * span, plan.tf + 0.1 * span, n)
    return np.concatenate([t, plan.breaks, [np.nan, -np.inf, np.inf]])


def test_c_evaluator_is_the_python_one_bit_for_bit(table):
    t = times(table)
    np.testing.assert_array_equal(np.array(traj_flag(table, t)), np.array(table.flag(t)))
    for order in range(5):
        np.testing.assert_array_equal(traj_theta(table, t[:300], order), table.theta_deriv(t[:300], order))
    assert traj_valid(table)


def test_flag_keeps_the_shape_of_t(table):
    t = np.linspace(0.0, 0.2, 12).reshape(3, 4)
    flag = table.flag(t)
    assert np.shape(flag) == (6, 3, 4)
    np.testing.assert_array_equal(np.array(traj_flag(table, t)), np.array(flag))


def test_rest_to_rest_is_a_one_segment_table():
    plan = RestToRest(0.1, 2.1, 0.4, 0.7, 0.02, 0.04)
    table = PiecewisePlan.from_rest_to_rest(plan)
    t = np.linspace(0.0, 0.06, 3001)
    got, want = np.array(table.flag(t)), np.array(plan.flag(t))
    peak = np.max(np.abs(want), axis=1, keepdims=True)
    assert np.all(np.abs(got - want) <= 1e-11 * peak), np.max(np.abs(got - want) / peak, axis=1)
    assert (table.t0, table.tf, table.n) == (0.02, 0.04, 1)
    assert table.theta1 == 0.1 and abs(table.theta2 - 2.1) < 1e-12 and abs(table.rho2 - 0.7) < 1e-12
    np.testing.assert_allclose(table.x0(50), plan.x0(50), atol=1e-15)


def test_derivatives_are_the_finite_differences_of_the_one_below(table):
    h = 1e-7
    t = np.linspace(table.t0, table.tf, 400)[1:-1]
    t = t[np.min(np.abs(t[:, None] - table.breaks[None, :]), axis=1) > 10 * h]  # not across a break
    for k in range(1, 5):
        fd = (table.theta_deriv(t + h, k - 1) - table.theta_deriv(t - h, k - 1)) / (2 * h)
        exact = table.theta_deriv(t, k)
        assert np.max(np.abs(fd - exact)) < 1e-6 * np.max(np.abs(exact)), k
    f = table.flag(t)
    np.testing.assert_allclose((table.flag(t + h).rho - table.flag(t - h).rho) / (2 * h), f.drho, rtol=1e-6, atol=1e-6)


def test_ppoly_round_trip_and_derivatives(table):
    theta, rho = table.to_ppoly()
    t = np.linspace(table.t0, table.tf, 777)[1:-1]
    for k in range(4):
        want = table.theta_deriv(t, k)
        assert np.max(np.abs(theta(t, nu=k) - want)) < 1e-9 * np.max(np.abs(want)), k
    back = PiecewisePlan.from_ppoly(theta, rho)
    np.testing.assert_allclose(back.theta, table.theta, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(back.rho, table.rho, rtol=1e-12, atol=1e-12)


def test_continuity_reports_the_jumps():
    a = RestToRest(0.0, 1.0, 0.5, 0.5, 0.0, 0.1)
    one = PiecewisePlan.from_rest_to_rest(a)
    two = PiecewisePlan(np.array([0.0, 0.1, 0.2]), np.vstack([one.theta, one.theta]), np.vstack([one.rho, one.rho]))
    jumps = two.continuity(3)
    assert jumps.shape == (1, 4)
    assert abs(jumps[0, 0] - 1.0) < 1e-12  # the second copy starts again at 0: theta jumps by 1 rad
    np.testing.assert_allclose(jumps[0, 1:], 0.0, atol=1e-6)  # psi's derivatives vanish at both ends


@pytest.mark.parametrize("kwargs, match", [
    (dict(breaks=[0.0, 0.0], theta=[[1.0]], rho=[[1.0]]), "strictly increasing"),
    (dict(breaks=[0.0, np.nan], theta=[[1.0]], rho=[[1.0]]), "strictly increasing"),
    (dict(breaks=[0.0, 1e-90], theta=[[1.0]], rho=[[1.0]]), "overflows"),
    (dict(breaks=[0.0, 1.0], theta=[[1.0], [2.0]], rho=[[1.0]]), "theta has shape"),
    (dict(breaks=[0.0, 1.0], theta=np.ones((1, 12)), rho=[[1.0]]), "theta has shape"),
    (dict(breaks=[0.0, 1.0], theta=[[np.inf]], rho=[[1.0]]), "non-finite"),
    (dict(breaks=[0.0, 1.0], theta=[[1.0]], rho=[[-2.0, 1.0]]), "rho falls to"),
])
def test_invalid_tables_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PiecewisePlan(**kwargs)


def test_theta_deriv_refuses_an_order_out_of_range(table):
    with pytest.raises(ValueError, match="order=5"):
        table.theta_deriv(0.1, 5)


def test_concatenate_joins_consecutive_tables_and_refuses_a_gap():
    a = PiecewisePlan.from_rest_to_rest(RestToRest(0.0, 1.0, 0.5, 0.5, 0.0, 0.1))
    hold = PiecewisePlan.hold(1.0, 0.5, 0.1, 0.3)
    b = PiecewisePlan.from_rest_to_rest(RestToRest(1.0, -2.0, 0.5, 0.7, 0.3, 0.5))
    joined = PiecewisePlan.concatenate([a, hold, b])
    np.testing.assert_array_equal(joined.breaks, [0.0, 0.1, 0.3, 0.5])
    t = np.linspace(-0.1, 0.6, 701)
    want = np.where(t < 0.1, a.theta_deriv(t, 0), np.where(t < 0.3, 1.0, b.theta_deriv(t, 0)))
    np.testing.assert_allclose(joined.theta_deriv(t, 0), want, atol=1e-12)
    assert joined.rho2 == pytest.approx(0.7)
    assert np.all(np.abs(joined.continuity(3)) < 1e-6 * np.array([1, 1e2, 1e4, 1e6]))  # psi rests: C3 joins
    with pytest.raises(ValueError, match="must meet"):
        PiecewisePlan.concatenate([a, b])
    with pytest.raises(ValueError, match="at least one"):
        PiecewisePlan.concatenate([])
