"""Open-loop plans along the pull-out curve (flatstep.plan.open_loop) and their check on the drive."""
from __future__ import annotations

import numpy as np
import pytest

from flatstep.model.motor import MotorParams
from flatstep.model.pullout import pullout_torque
from flatstep.plan.open_loop import (acceleration_curve, box_shaped, natural_period, open_loop_plan, profile_plan,
                                     speed_profile, tabulated)
from flatstep.studies.open_loop import (WEAKEST, Profile, best_open_loop, best_profile, best_trapezoid, check_on_plants,
                                        measured_pullout, trapezoid_plan)

NEMA17 = MotorParams.preset("nema17")


@pytest.mark.parametrize("distance", [1.0, -5.0, 60.0])
def test_unshaped_plan_follows_the_curve_and_ends_at_rest(distance):
    """From rest to rest over the distance; the acceleration never above m T_po(omega)/J at the speed reached."""
    plan = open_loop_plan(NEMA17, 24.0, 1.0, distance, margin=0.5, shaping=False, theta1=0.3)
    assert plan.theta1 == pytest.approx(0.3) and plan.theta2 == pytest.approx(0.3 + distance, abs=1e-9)
    t = np.linspace(plan.t0, plan.tf, 20001)
    f = plan.flag(t)
    assert abs(f.dtheta[0]) < 1e-12 and abs(f.dtheta[-1]) < 1e-9 * abs(distance) / (plan.tf - plan.t0)
    allowed = acceleration_curve(NEMA17, 24.0, 1.0, np.abs(f.dtheta), margin=0.5)
    assert (np.abs(f.ddtheta) <= allowed * (1 + 1e-9) + 1e-6).all()
    assert np.sign(f.dtheta[len(t) // 2]) == np.sign(distance)


def test_shaping_keeps_the_ends_and_makes_the_acceleration_continuous():
    raw = open_loop_plan(NEMA17, 24.0, 1.0, 5.0, shaping=False)
    period = natural_period(NEMA17, 1.0, 0.4)
    shaped = box_shaped(raw, period)
    assert shaped.theta2 == pytest.approx(raw.theta2, abs=1e-9) and shaped.tf == pytest.approx(raw.tf + period)
    assert np.abs(raw.continuity(2)).max() > 1e3  # the raw acceleration jumps
    assert np.abs(shaped.continuity(2)).max() < 1e-6 * np.abs(raw.continuity(2)).max()
    t = np.linspace(0, shaped.tf, 201)
    window = np.linspace(-period, 0, 101)
    samples = raw.flag((t[:, None] + window[None, :]).ravel()).theta.reshape(t.size, window.size)
    mean = np.trapezoid(samples, window, axis=1) / period
    np.testing.assert_allclose(shaped.flag(t).theta, mean, atol=1e-5)


def test_a_tabulated_curve_is_followed_and_checked():
    curve = tabulated([0.0, 50.0, 100.0], [0.2, 0.1, 0.0])
    np.testing.assert_allclose(curve(np.array([0.0, 25.0, 100.0, 200.0])), [0.2, 0.15, 0.0, 0.0])
    plan = open_loop_plan(NEMA17, 24.0, 1.0, 10.0, margin=1.0, pullout=curve, shaping=False)
    f = plan.flag(np.linspace(0, plan.tf, 5001))
    assert (np.abs(f.ddtheta) <= curve(np.abs(f.dtheta)) / NEMA17.J * (1 + 1e-9) + 1e-6).all()
    with pytest.raises(ValueError, match="increasing speeds"):
        tabulated([0.0, 0.0], [1.0, 1.0])


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(distance=0.0), "distance"), (dict(margin=1.5), "margin"), (dict(load=0.5), "cannot start"),
    (dict(drive_kind="servo"), "drive_kind"),
])
def test_bad_input_is_refused(kwargs, match):
    args = {"motor": NEMA17, "v_bus": 24.0, "current": 1.0, "distance": 1.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        open_loop_plan(**args)


def test_sample_of_the_plants_keeps_a_plan_and_loses_one_beyond_the_drive():
    """A 1 rad plan at 0.4 of the pull-out torque is kept by the weakest, nominal and two other corners; a 5 rad
    plan that cruises at 100 rad/s on the model's curve, where the drive no longer follows it, is lost."""
    sample = [WEAKEST, {}, {"R": -0.1, "L": 0.1, "Km": 0.1, "J": -0.1, "B": -0.1},
              {"R": 0.1, "L": -0.1, "Km": -0.1, "J": -0.1, "B": 0.1}]
    kept = check_on_plants(NEMA17, open_loop_plan(NEMA17, 24.0, 1.0, 1.0, margin=0.4), 24.0, errors=sample)
    assert kept.runs == 4 and kept.safe and kept.worst_error < np.pi / (2 * 50)
    fast = open_loop_plan(NEMA17, 24.0, 1.0, 5.0, margin=0.6, w_max=100.0, drive_kind="foc_weakening")
    assert not check_on_plants(NEMA17, fast, 24.0, errors=[WEAKEST]).safe


@pytest.mark.parametrize("distance", [0.02, 1.0, 60.0])
def test_constant_profiles_give_the_trapezoid(distance):
    flat = speed_profile([0.0], [18000.0])
    plan = profile_plan(distance, 55.0, flat, flat, 1.0)
    trap = trapezoid_plan(distance, 55.0, 18000.0, 1.0)
    assert plan.tf == pytest.approx(trap.tf, rel=1e-12)
    t = np.linspace(0.0, plan.tf, 4001)
    np.testing.assert_allclose(plan.flag(t).theta, trap.flag(t).theta, atol=1e-9 * distance)


@pytest.mark.parametrize("distance", [-0.3, 4.0, 40.0])
def test_profile_plan_keeps_below_its_profiles_and_ends_at_rest(distance):
    """Accelerating, |a| <= accel(|omega|); braking, |a| <= brake(|omega|); rest to rest over the distance."""
    accel = speed_profile([0.0, 20.0, 50.0, 60.0], [40000.0, 30000.0, 8000.0, 1000.0])
    brake = speed_profile([0.0, 30.0, 60.0], [60000.0, 50000.0, 2000.0])
    plan = profile_plan(distance, 60.0, accel, brake, 0.8, theta1=0.5, t0=0.1)
    assert plan.t0 == pytest.approx(0.1) and plan.theta2 == pytest.approx(0.5 + distance, abs=1e-9)
    t = np.linspace(plan.t0, plan.tf, 40001)
    f = plan.flag(t)
    w, a = np.abs(f.dtheta), f.ddtheta * np.sign(distance)
    assert w[0] < 1e-12 and w[-1] < 1e-6 and w.max() <= 60.0 * (1 + 1e-9)
    speeding = a > 0
    assert (a[speeding] <= accel(w[speeding]) * (1 + 1e-9) + 1e-6).all()
    assert (-a[~speeding] <= brake(w[~speeding]) * (1 + 1e-9) + 1e-6).all()
    assert np.abs(plan.continuity(1)).max() < 1e-6  # the speed is continuous; the acceleration steps, bounded


@pytest.mark.parametrize(("args", "match"), [
    (([0.0, 0.0], [1.0, 1.0]), "knot speeds"), (([1.0], [1.0]), "knot speeds"), (([0.0, 5.0], [1.0, 0.0]), "> 0"),
])
def test_bad_speed_profile_is_refused(args, match):
    with pytest.raises(ValueError, match=match):
        speed_profile(*args)


def test_bad_cruise_is_refused():
    flat = speed_profile([0.0], [1000.0])
    with pytest.raises(ValueError, match="cruise"):
        profile_plan(1.0, 0.0, flat, flat, 1.0)


def test_the_search_keeps_every_candidate_safe_and_never_lengthens_the_seed():
    """A short search on a 1 rad move, seeded with a slow safe trapezoid: the result is kept by all 32 plants and no
    longer than the seed; the neighbours of a constant profile include a faster cruise along a taper."""
    seed_plan = trapezoid_plan(1.0, 30.0, 5000.0, 1.0)
    seed_check = check_on_plants(NEMA17, seed_plan, 24.0)
    assert seed_check.safe and seed_check.runs == 32
    plan, info, check = best_profile(NEMA17, 24.0, 1.0, 1.0, (seed_plan, {"v_max": 30.0, "a_max": 5000.0},
                                                               seed_check), budget=3)
    assert check.safe and check.runs == 32 and info["candidates"] <= 3
    assert plan.tf <= seed_plan.tf and plan.theta2 == pytest.approx(1.0, abs=1e-9)
    neighbours = Profile(30.0, (5000.0,) * 5, (5000.0,) * 5).moves(0.2)
    assert any(p.cruise == pytest.approx(36.0) and p.accel[-1] < 5000.0 for p in neighbours)


@pytest.mark.slow
def test_full_study_profile_against_the_best_trapezoid():
    """On the 32 plants: the profile seeded with the best trapezoid, with the same screening budget, is shorter
    (docs/curves.md, the table of benchmarks/pullout_open_loop.py)."""
    trap = best_trapezoid(NEMA17, 24.0, 1.0, 5.0)
    plan, info, check = best_profile(NEMA17, 24.0, 1.0, 5.0, trap, budget=int(trap[1]["candidates"]))
    assert check.runs == trap[2].runs == 32 and check.safe and trap[2].safe
    assert plan.tf < 0.9 * trap[0].tf


@pytest.mark.slow
def test_full_study_plan_along_the_measured_curve_keeps_every_plant():
    """On the 32 plants: the plan along the drive's measured pull-out curve, its share searched, loses no step."""
    curve = measured_pullout(NEMA17, 24.0, 1.0)
    assert curve(np.array([0.0]))[0] == pytest.approx(pullout_torque(NEMA17, "chopper", 24.0, 1.0, 0.0)[0])
    plan, info, check = best_open_loop(NEMA17, 24.0, 1.0, 1.0, pullout=curve)
    assert check.runs == 32 and check.safe and 0 < info["margin"] <= 1
    assert plan.theta2 == pytest.approx(1.0, abs=1e-9)
