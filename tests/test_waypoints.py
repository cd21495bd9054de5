"""Multi-segment moves (flatstep.plan.waypoints, flatstep.plan.segments): continuity, waypoints met, caps, errors."""
import math

import numpy as np
import pytest

from flatstep.core.traj import traj_flag
from flatstep.plan.segments import PSI_PEAKS, scurve_phases
from flatstep.plan.waypoints import FAMILIES, Caps, Waypoint, plan_waypoints

CAPS = Caps(100.0, 2000.0, 1e5)
POINTS = [0.0, 1.0, Waypoint(3.0, dwell=0.05), 2.0, 5.0, Waypoint(4.0, velocity=-5.0), 8.0]
#: Continuity order of theta each family promises at every break.
SMOOTH = {"psi": 3, "hermite": 3, "spline": 3, "scurve": 2}


def sample(plan, n=40001):
    """Times evenly spread over the plan's move, ``n`` of them."""
    return np.linspace(plan.t0, plan.tf, n)


@pytest.mark.parametrize("family", FAMILIES)
def test_every_family_is_smooth_meets_the_waypoints_and_the_caps(family):
    """Every family is smooth at its breaks, passes the waypoints in order, keeps the caps and holds the dwell."""
    points = [p if not (isinstance(p, Waypoint) and p.velocity) or family in ("hermite", "spline")
              else Waypoint(p.theta) for p in POINTS]
    if family == "spline":  # a spline chooses its own via speeds
        points = [Waypoint(p.theta, dwell=p.dwell) if isinstance(p, Waypoint) else p for p in points]
    plan = plan_waypoints(points, family=family, rho=0.6, t0=0.01, caps=CAPS)
    jumps = np.abs(plan.continuity(SMOOTH[family]))
    scale = np.array([1.0, CAPS.v_max, CAPS.a_max, CAPS.j_max])[: SMOOTH[family] + 1]
    assert np.all(jumps <= 1e-9 * scale), jumps.max(axis=0)
    t = sample(plan)
    for k, cap in ((1, CAPS.v_max), (2, CAPS.a_max), (3, CAPS.j_max)):
        peak = np.max(np.abs(plan.theta_deriv(t, k)))
        assert peak <= cap * (1 + 1e-3), (k, peak)
    # every waypoint is passed: at a break, in order; the plan rests at its ends and holds through the dwell
    theta_at_breaks = plan.theta_deriv(plan.breaks, 0)
    want = [p.theta if isinstance(p, Waypoint) else p for p in points]
    hits = [0]
    for w in want[1:]:  # each waypoint at a break after the previous one's
        hits.append(hits[-1] + 1 + int(np.flatnonzero(np.abs(theta_at_breaks[hits[-1] + 1:] - w) < 1e-9)[0]))
    assert hits[-1] == plan.n and abs(plan.theta2 - 8.0) < 1e-9 and plan.t0 == 0.01
    dwell = np.isclose(plan.durations, 0.05, rtol=0, atol=1e-12)
    assert dwell.sum() == 1 and np.all(plan.theta[dwell, :-1] == 0) and plan.theta[dwell, -1] == 3.0
    f = plan.flag(t)
    assert np.all(f.rho == 0.6) and np.all(f.drho == 0)
    np.testing.assert_array_equal(np.array(traj_flag(plan, t[::97])), np.array(plan.flag(t[::97])))


def test_caps_bind_the_psi_move_exactly():
    """The speed cap binds the psi move exactly: its duration and peak speed are the cap's."""
    plan = plan_waypoints([0.0, 10.0], caps=Caps(50.0, 1e6, 1e9))
    assert abs(plan.tf - PSI_PEAKS[0] * 10.0 / 50.0) < 1e-12
    assert abs(np.max(plan.theta_deriv(sample(plan), 1)) - 50.0) < 1e-3


def test_given_via_speed_is_met():
    """A via speed given to a Hermite move is met, at zero acceleration, with the given durations."""
    plan = plan_waypoints([0.0, Waypoint(2.0, velocity=30.0), 3.0], family="hermite", durations=[0.1, 0.05])
    assert abs(plan.theta_deriv(np.array([0.1]), 1)[0] - 30.0) < 1e-9
    assert abs(plan.theta_deriv(np.array([0.1]), 2)[0]) < 1e-6
    np.testing.assert_allclose(plan.durations, [0.1, 0.05])


@pytest.mark.parametrize("distance", [0.001, 0.5, 5.0, 50.0])
def test_scurve_phases_cover_the_distance_within_the_caps(distance):
    """The S-curve's phases cover the distance within the speed and acceleration caps, its jerk bang-bang."""
    h, j = scurve_phases(distance, 100.0, 2000.0, 1e5)
    plan = plan_waypoints([1.0, 1.0 + distance], family="scurve", caps=CAPS)
    assert abs(plan.theta2 - 1.0 - distance) < 1e-12 * max(1.0, distance)
    assert abs(plan.tf - h.sum()) < 1e-12
    t = sample(plan)
    assert np.max(np.abs(plan.theta_deriv(t, 1))) <= 100.0 * (1 + 1e-9)
    assert np.max(np.abs(plan.theta_deriv(t, 2))) <= 2000.0 * (1 + 1e-9)
    # the jerk is bang-bang: every phase at -j, 0 or +j
    assert set(np.unique(np.round(np.abs(j) / 1e5))) <= {0.0, 1.0}


def test_scurve_time_for_a_long_move_is_the_textbook_one():
    """A long S-curve move takes the textbook time D / v + v / a + a / j."""
    # the speed and acceleration caps are reached: T = D / v + v / a + a / j
    d, v, a, j = 50.0, 100.0, 2000.0, 1e5
    assert math.isclose(plan_waypoints([0.0, d], family="scurve", caps=Caps(v, a, j)).tf, d / v + v / a + a / j,
                        rel_tol=1e-12)


@pytest.mark.parametrize("args, kwargs, match", [
    ([0.0], dict(caps=CAPS), "at least 2"),
    ([0.0, 1.0], dict(family="bezier", caps=CAPS), "not a segment family"),
    ([0.0, 1.0], dict(), "neither durations nor caps"),
    ([0.0, 1.0, 2.0], dict(durations=[0.1]), "one per move"),
    ([0.0, 1.0], dict(durations=[-0.1]), "durations\\[0\\]"),
    ([0.0, 1.0], dict(family="scurve", durations=[0.1]), "follow from caps"),
    ([0.0, Waypoint(1.0, velocity=3.0), 2.0], dict(caps=CAPS), "rests at every waypoint"),
    ([Waypoint(0.0, velocity=1.0), 1.0], dict(family="hermite", caps=CAPS), "end points and dwells"),
    ([0.0, 0.0], dict(caps=CAPS), "a move needs a distance"),
    ([0.0, 1.0, 1.0, 2.0], dict(family="hermite", caps=CAPS), "same angle"),
    ([0.0, Waypoint(1.0, velocity=500.0), 2.0], dict(family="hermite", caps=CAPS), "cannot meet the caps"),
    ([0.0, 1.0], dict(rho=0.0, caps=CAPS), "rho=0.0"),
])
def test_bad_requests_are_refused(args, kwargs, match):
    """Bad waypoint requests are refused with a ValueError saying why."""
    with pytest.raises(ValueError, match=match):
        plan_waypoints(args, **kwargs)


def test_bad_waypoints_and_caps_are_refused():
    """A negative dwell, a NaN angle and a zero cap are refused, naming them."""
    with pytest.raises(ValueError, match="waypoint dwell"):
        Waypoint(1.0, dwell=-1.0)
    with pytest.raises(ValueError, match="waypoint theta"):
        Waypoint(float("nan"))
    with pytest.raises(ValueError, match="a_max"):
        Caps(1.0, 0.0, 1.0)
