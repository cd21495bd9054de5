"""Fair baselines (flatstep.bench.fair_baselines): the checks against the d-q flat maps, the searches, the drive."""
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("ruckig")

from flatstep.bench.drive_tracking import track  # noqa: E402
from flatstep.bench.fair_baselines import (  # noqa: E402
    best_ruckig,
    best_trapezoid,
    dq_plan,
    ruckig_margins,
    trapezoid_margins,
    weakening_current,
)
from flatstep.model.flat_dq import DQFlag, dq_to_state  # noqa: E402
from flatstep.model.motor import PRESETS  # noqa: E402
from flatstep.plan.baselines import ruckig_duration, trapezoid_rows  # noqa: E402
from flatstep.plan.d_current import DCurrentPlan  # noqa: E402
from flatstep.plan.limits import MotorLimits  # noqa: E402
from flatstep.plan.segments import scurve_rows  # noqa: E402

NEMA17 = PRESETS["nema17"]
LIMITS24 = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.025, v_use=0.84, torque_angle_max=1.1)


def _flat_map_peaks(plan, d_current, n=20000):
    """Peak voltage and current norms of a plan through dq_to_state, sampled densely inside its segments."""
    t = np.linspace(plan.t0, plan.tf, n)[1:-1]
    f = plan.flag(t)
    i_d, di_d = d_current.flag(t, f.dtheta, f.ddtheta)
    x, v = dq_to_state(DQFlag(f.theta, f.dtheta, f.ddtheta, f.dddtheta, i_d, di_d), NEMA17)
    return float(np.max(np.hypot(v[0], v[1]))), float(np.max(np.hypot(x[0], x[1])))


def test_the_ruckig_check_is_the_flat_maps_on_the_ruckig_plan():
    """The Ruckig check's duration is Ruckig's, and its margins are the flat maps' peaks on that plan."""
    caps = (60.0, 30000.0, 2e7)
    duration, margins = ruckig_margins(1.0, NEMA17, LIMITS24, *caps)
    assert duration == pytest.approx(ruckig_duration(1.0, *caps), rel=1e-9)
    plan = dq_plan(*scurve_rows(0.0, 1.0, *caps), 1.0, LIMITS24)
    v_peak, i_peak = _flat_map_peaks(plan, DCurrentPlan(0.0, 0.0, 0.0, plan.tf))
    assert margins["voltage"] * 0.84 * 24.0 == pytest.approx(v_peak, rel=2e-3)
    assert margins["current"] * 1.0 == pytest.approx(i_peak, rel=2e-3)


def test_the_trapezoid_check_is_the_flat_maps_inside_its_segments():
    """The trapezoid check's margins are the flat maps' peaks inside its segments, the weakening included."""
    dc = DCurrentPlan(0.0, 0.0, 0.0, 1.0, weakening=0.004, weakening_speed=20.0)
    duration, margins = trapezoid_margins(5.0, NEMA17, LIMITS24, 140.0, 9000.0, dc)
    plan = dq_plan(*trapezoid_rows(5.0, 140.0, 9000.0), 5.0, LIMITS24)
    assert duration == pytest.approx(plan.tf, rel=1e-12)
    v_peak, i_peak = _flat_map_peaks(plan, DCurrentPlan(0.0, 0.0, 0.0, plan.tf, weakening=0.004,
                                                        weakening_speed=20.0))
    assert margins["voltage"] * 0.84 * 24.0 == pytest.approx(v_peak, rel=2e-3)
    assert margins["current"] == pytest.approx(i_peak, rel=2e-3)
    assert margins["i_d_min"] == pytest.approx(-0.004 * 120.0, rel=1e-9)


def test_the_weakening_current_minimises_the_steady_voltage():
    """The weakening current is the d current of least steady voltage at each speed (against a dense grid)."""
    for omega in (30.0, 100.0, 300.0):
        i_d = np.linspace(-2.0, 0.5, 250001)
        v = np.hypot(NEMA17.R * i_d, NEMA17.Nr * omega * NEMA17.L * i_d + NEMA17.Km * omega)
        assert weakening_current(omega, NEMA17) == pytest.approx(i_d[np.argmin(v)], abs=2e-5)


def test_best_ruckig_keeps_the_limits_and_leaves_no_slack():
    """The best Ruckig plan keeps the limits with the bus binding: caps 5 % higher break the bus."""
    b = best_ruckig(1.0, NEMA17, LIMITS24, n=10)
    assert b.margins["voltage"] <= 1.0 and b.margins["current"] <= 1.0
    assert b.margins["voltage"] > 0.97  # the bus binds
    assert b.margins["i_d_min"] == 0.0
    faster = ruckig_margins(1.0, NEMA17, LIMITS24, *(1.05 * c for c in b.caps.values()))
    assert faster[0] < b.duration and faster[1]["voltage"] > 1.0


def test_best_trapezoid_weakens_the_field_and_beats_ruckig_on_a_long_move():
    """The best trapezoid keeps the limits, weakens the field, and takes under 0.8 of Ruckig's time on 5 rad."""
    trap, ruckig = best_trapezoid(5.0, NEMA17, LIMITS24, n=12), best_ruckig(5.0, NEMA17, LIMITS24, n=10)
    assert trap.margins["voltage"] <= 1.0 and trap.margins["current"] <= 1.0
    assert trap.margins["i_d_min"] < -0.3 and trap.margins["speed_peak"] > 100.0
    assert trap.duration < 0.8 * ruckig.duration


def test_both_searches_keep_a_speed_cap():
    """A speed cap binds both searches: their plans keep under it and take longer than without it."""
    capped = replace(LIMITS24, speed_max=40.0)
    free = best_ruckig(5.0, NEMA17, LIMITS24, n=8)
    assert free.caps["v_max"] > 40.0  # the cap binds
    for b in (best_ruckig(5.0, NEMA17, capped, n=8), best_trapezoid(5.0, NEMA17, capped, n=8)):
        assert b.caps["v_max"] <= 40.0 * (1 + 1e-12)
        assert b.margins["speed_peak"] <= 40.0 * (1 + 1e-9)
        assert b.duration > free.duration


def test_the_d_q_law_tracks_the_ruckig_baseline_on_the_drive():
    """The d-q law tracks the best Ruckig plan on the drive within 1 mrad, with no fault."""
    b = best_ruckig(1.0, NEMA17, LIMITS24, n=8)
    out = track(b.plan, NEMA17, 24.0, b.d_current)
    assert out["status"] == "ok" and out["faults"] == 0
    assert out["max_error"] < 1e-3


def test_a_move_of_zero_is_refused():
    """A move of zero distance is refused by both searches."""
    with pytest.raises(ValueError, match="distance"):
        best_ruckig(0.0, NEMA17, LIMITS24)
    with pytest.raises(ValueError, match="distance"):
        best_trapezoid(0.0, NEMA17, LIMITS24)
