"""Baselines (flatstep.plan.baselines): Ruckig's durations, trapezoids, the best-limited search."""
import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from flatstep.model.motor import PRESETS
from flatstep.plan.baselines import _ok, _split, baseline_plan, best_baseline, ruckig_duration, trapezoid_rows
from flatstep.plan.limits import MotorLimits
from flatstep.plan.margins import plan_margins
from flatstep.plan.segments import scurve_phases

MOTOR = PRESETS["nema17"]
LIMITS = MotorLimits(v_bus=24.0, i_max=1.0)


@pytest.mark.parametrize("distance, v, a, j", [(0.05, 50.0, 2e4, 1e7), (1.0, 50.0, 2e4, 1e7), (5.0, 30.0, 5e3, 1e6),
                                               (20.0, 60.0, 3e4, 2e6), (0.3, 100.0, 1e3, 1e8)])
def test_the_scurve_table_lasts_as_long_as_ruckig(distance, v, a, j):
    pytest.importorskip("ruckig")
    h, _ = scurve_phases(distance, v, a, j)
    assert math.isclose(h.sum(), ruckig_duration(distance, v, a, j), rel_tol=1e-9)
    plan = baseline_plan("ruckig", distance, MOTOR, LIMITS, v, a, j)
    assert math.isclose(plan.tf, h.sum(), rel_tol=1e-12) and abs(plan.theta2 - distance) < 1e-9


@pytest.mark.parametrize("distance", [0.01, 1.0, 10.0])
def test_trapezoid_reaches_the_distance_in_the_textbook_time(distance):
    v, a = 40.0, 1e4
    rows, h = trapezoid_rows(distance, v, a)
    want = distance / v + v / a if distance > v * v / a else 2 * math.sqrt(distance / a)
    assert math.isclose(h.sum(), want, rel_tol=1e-12)
    end = sum(np.polyval(r, 1.0) - np.polyval(r, 0.0) for r in rows)
    assert math.isclose(end, distance, rel_tol=1e-12)


def test_split_re_expands_every_part_exactly():
    rows = np.random.default_rng(3).normal(size=(2, 11))
    parts, h = _split(rows, np.array([1.0, 2.0]), 4)
    np.testing.assert_allclose(h, [0.25] * 4 + [0.5] * 4)
    for k in range(4):
        q = Polynomial(rows[1][::-1])(Polynomial([k / 4, 0.25])).coef[::-1]
        np.testing.assert_allclose(parts[4 + k][-q.size:], q, atol=1e-14)


def test_the_best_trapezoid_is_feasible_and_its_caps_cannot_grow():
    plan, caps = best_baseline("trapezoid", 2.0, MOTOR, LIMITS)
    m = plan_margins(plan, MOTOR, LIMITS)
    assert m["voltage"] <= LIMITS.v_use and m["current"] <= 1.0
    assert abs(plan.theta2 - 2.0) < 1e-9
    bigger = baseline_plan("trapezoid", 2.0, MOTOR, LIMITS, caps["v_max"], 1.05 * caps["a_max"])
    assert not _ok(bigger, MOTOR, LIMITS)


def test_unknown_baselines_are_refused():
    with pytest.raises(ValueError, match="kind='bezier' is not one of"):
        baseline_plan("bezier", 1.0, MOTOR, LIMITS, 1.0, 1.0)
    with pytest.raises(ValueError, match="needs j_max"):
        baseline_plan("ruckig", 1.0, MOTOR, LIMITS, 1.0, 1.0)
