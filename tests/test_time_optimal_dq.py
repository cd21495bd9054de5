"""The field-weakening planner in the d-q flat outputs: C and reference parity, the shot, feasibility, the d current."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flatstep.control.dq_smc import DQFlatnessSMC
from flatstep.engine.simulate import simulate
from flatstep.loop.design import design_gains
from flatstep.model.motor import MotorParams
from flatstep.plan.d_current import DCurrentPlan, hermite_cubic
from flatstep.plan.limits import MotorLimits
from flatstep.plan.time_optimal_dq import plan_dq_move, speed_cap, time_optimal_dq
from flatstep.plan.time_optimal_dq_c import plan_raw
from flatstep.plan.time_optimal_dq_envelope import best_currents, dq_envelope
from flatstep.plan.time_optimal_dq_phases import _brake, _speed_up
from flatstep.plan.time_optimal_dq_policy import D_SLEW, X_END, _Model
from flatstep.plan.time_optimal_dq_profile import dq_fit
from flatstep.plan.time_optimal_dq_ramp import ramp_ends, ramp_voltage
from flatstep.plan.time_optimal_dq_shoot import RAMP_LOW, _land, estimate, shoot
from flatstep.studies.verify import drive_loop

NEMA17 = MotorParams.preset("nema17")


def limits(v_bus: float = 24.0, **kw: float) -> MotorLimits:
    """The tests' limits: a ``v_bus`` bus of which 84 % is used, 1 A, and the keywords ``kw``."""
    return MotorLimits(v_bus=v_bus, i_max=1.0, v_use=0.84, **kw)


@pytest.mark.parametrize("v_bus,distance", [(24.0, 0.1), (24.0, 0.3), (24.0, 5.0), (12.0, 0.1), (12.0, 1.0),
                                             (12.0, 20.0)])
def test_c_and_reference_plan_the_same_move(v_bus: float, distance: float) -> None:
    """The C planner and the Python reference plan the same move: duration, shape and tables."""
    py = plan_dq_move(distance, NEMA17, limits(v_bus), engine="python")
    c = plan_dq_move(distance, NEMA17, limits(v_bus), engine="c")
    assert c.tf == pytest.approx(py.tf, rel=1e-9)
    assert c.kappa == pytest.approx(py.kappa, rel=1e-9)
    assert c.width == pytest.approx(py.width, rel=1e-12)
    np.testing.assert_allclose(c.table.breaks, py.table.breaks, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(c.table.i_d, py.table.i_d, atol=1e-8)
    np.testing.assert_allclose(c.table.theta, py.table.theta, rtol=1e-6, atol=1e-8)


def test_shot_lands_on_the_distance_at_rest_and_the_table_follows_it() -> None:
    """The shot lands on the distance at rest, the table follows its samples, and the voltage meets the bus."""
    lim = limits(24.0)
    v = 0.98 * lim.v_use * lim.v_bus
    shot = shoot(0.3, NEMA17, v, 0.995, 0.995 * speed_cap(NEMA17, lim, 20000.0))
    assert shot is not None and shot.end.angle == pytest.approx(0.3, rel=1e-9)
    table = dq_fit(shot, 0.3, NEMA17, v, 0.995)
    plan = time_optimal_dq(0.3, NEMA17, lim).plan
    f = plan.flag(np.array([plan.t0, plan.tf]))
    assert f.theta.tolist() == pytest.approx([0.0, 0.3], abs=1e-12)
    assert f.dtheta.tolist() == pytest.approx([0.0, 0.0], abs=1e-9)
    assert f.ddtheta.tolist() == pytest.approx([0.0, 0.0], abs=1e-6)
    # the knots are the shot's samples: theta and the speed of the model, integrated
    k = np.searchsorted(np.arange(shot.n_acc) * shot.h, table.breaks[1:5])
    np.testing.assert_allclose(table.theta[1:5, -1], shot.accel.theta[k], rtol=1e-12)
    # the currents change at the bus's full rate: the planned voltage meets the bus, where the old planner kept a
    # share for the inductance
    fw = time_optimal_dq(0.3, NEMA17, lim)
    v_mag, _, _ = _voltages(fw.plan, fw.d_current, NEMA17)
    assert np.max(v_mag) >= 0.95 * lim.v_use * lim.v_bus


def _nema17_12v_shot() -> tuple:
    """The NEMA 17 preset at 12 V (R i_max 41 % of the bus): the shot's bus, its speed cap and its 0.3 rad shot."""
    lim = limits(12.0)
    v = 0.98 * lim.v_use * lim.v_bus
    cap = 0.995 * speed_cap(NEMA17, lim, 20000.0)
    shot = shoot(0.3, NEMA17, v, 0.995, cap)
    assert shot is not None
    return v, cap, shot


def test_terminal_ramp_rate_falls_where_the_ramp_would_leave_the_bus() -> None:
    """The terminal ramp's rate falls where the full rate would leave the bus, and a second shot keeps it."""
    v, cap, shot = _nema17_12v_shot()  # the ramp's start would leave the bus at the full rate
    assert shot.ramp < 1.0
    md = _Model(NEMA17, v, 0.995, cap, shot.h)
    md.end_rate = shot.ramp * md.rate
    assert ramp_voltage(md, shot.end) <= 1.0
    again = shoot(0.3, NEMA17, v, 0.995, cap, shot.ramp)  # from the found rate: no further fall
    assert again is not None and again.ramp == shot.ramp
    assert again.end.t_end == pytest.approx(shot.end.t_end, rel=1e-9)  # (the root finder's tolerance)


def test_terminal_ramp_ends_near_the_bus_with_its_d_share_balancing_start_and_end() -> None:
    """The terminal ramp ends near the bus, within it, its d share balancing the voltage at its start and end."""
    v, cap, shot = _nema17_12v_shot()
    md = _Model(NEMA17, v, 0.995, cap, shot.h)
    md.end_rate = shot.ramp * md.rate
    assert RAMP_LOW <= ramp_voltage(md, shot.end) <= 1.0  # the fallen rate raised once, within the bus
    e = shot.end
    assert 0.0 <= e.d_share < 1.0  # the braking current beyond the envelope: the d current leaves later
    start, end = ramp_ends(md, e.omega1, e.i_d1, e.i_q1, e.tau, e.d_share)
    assert start == pytest.approx(end, rel=0.02)  # balanced at the bridge's start; the bridge moves it a little
    linear_start, _ = ramp_ends(md, e.omega1, e.i_d1, e.i_q1, e.tau, 1.0)
    assert linear_start > start


@pytest.mark.parametrize("v_bus,beyond", [(12.0, True), (24.0, False)])
def test_braking_target_beyond_the_envelope_only_where_the_bus_binds_the_whole_move(v_bus: float,
                                                                                    beyond: bool) -> None:
    """The braking target goes beyond the steady envelope at 12 V, where the bus binds the whole move, not at 24 V."""
    lim = limits(v_bus)
    v = 0.98 * lim.v_use * lim.v_bus  # R i_max / V: 0.41 at 12 V, 0.20 at 24 V
    md = _Model(NEMA17, v, 0.995, speed_cap(NEMA17, lim, 20000.0), 1e-5)
    for w in (30.0, 50.0, 70.0):
        t_d, t_q = md.target(w, True)
        steady = best_currents(w, NEMA17, v, 0.995)
        assert math.hypot(t_d, t_q) <= 0.995 * (1 + 1e-12)
        if beyond:
            assert t_q < steady[3] - 0.02
        else:
            assert abs(t_q - steady[3]) < 0.01  # R i_max / V 0.21: the disc scaled by 1.01


def test_speeding_up_weakens_ahead_of_the_steady_envelope_at_12_v() -> None:
    """Speeding up at 12 V weakens the field never later than the steady envelope, and well ahead of it."""
    lim = limits(12.0)
    v = 0.98 * lim.v_use * lim.v_bus
    shot = shoot(1.0, NEMA17, v, 0.995, 0.995 * speed_cap(NEMA17, lim, 20000.0))
    assert shot is not None
    a = shot.accel
    steady = np.array([best_currents(float(w), NEMA17, v, 0.995)[0] for w in a.omega[:shot.n_acc]])
    ahead = a.t_d[:shot.n_acc] - steady
    assert np.all(ahead <= 1e-12)  # never less weakening than the envelope's
    assert np.min(ahead) < -0.3  # and well ahead of it where the envelope's d current starts to fall


@pytest.mark.parametrize("resistance,weakens", [(6.0, True), (14.0, False)])
def test_look_ahead_follows_the_reactance_at_the_cruise_not_the_resistive_share(resistance: float,
                                                                               weakens: bool) -> None:
    """The look-ahead weakens the field where the reactance at the cruise is high, not by the resistive share."""
    # R 6: R i_max / V 0.72 (a rule on the resistive share alone took the look-ahead from it), N_r W L / R 7;
    # R 14: N_r W L / R below 3, where the d current's own drop eats what it saves
    m = replace(NEMA17, R=resistance)
    lim = limits(12.0)
    v = 0.98 * lim.v_use * lim.v_bus
    md = _Model(m, v, 0.995, 0.995 * speed_cap(m, lim, 20000.0), 1e-5)
    assert (md.reactance > 5.0) == weakens and (md.reactance < X_END) != weakens
    w = 0.2 * md.cap
    alpha = (m.Km * 0.5 - m.B * w) / m.J
    t_d, _ = md.next_target((0.0, w, 0.0, 0.5), False)
    plain, _ = md.target(w + md.h * alpha, False)
    if weakens:
        assert t_d < plain - 0.05
    else:
        assert t_d == plain


def _qsh5718_shot(v_bus: float) -> tuple:
    """The QSH5718-51 (a NEMA 23 at 2.83 A) at ``v_bus``: motor, i_max, limits, the shot's bus and its 0.3 rad shot."""
    from flatstep.bench.field_weakening import motor

    m, i_max = motor("trinamic-qsh5718-51-28-101", Path(__file__).resolve().parent.parent / "examples" / "motors")
    lim = MotorLimits(v_bus=v_bus, i_max=i_max, i_hold=0.01 * i_max, v_use=0.84)
    v = 0.98 * lim.v_use * lim.v_bus
    shot = shoot(0.3, m, v, 0.995 * i_max, 0.995 * speed_cap(m, lim, 20000.0))
    assert shot is not None
    return m, i_max, lim, v, shot


def test_speeding_up_d_target_moves_within_the_bus_rate() -> None:
    """The d target moves within the bus's rate, so the first shot's table keeps the bus."""
    m, i_max, lim, v, shot = _qsh5718_shot(12.0)
    step = np.abs(np.diff(shot.accel.t_d[:shot.n_acc]))
    assert np.max(step) <= D_SLEW * shot.h * v / m.L * (1 + 1e-9)
    # the d target no longer jumps at the look-ahead's knee: the fitted table keeps the bus on the first shot
    for d in (0.3, 1.0, 5.0):
        _, out = plan_raw(d, m, lim, 20000.0)
        assert out.tables == 1


def test_braking_current_held_to_the_current_limit_on_the_bus() -> None:
    """The braking current keeps to the current limit (0.5 % at most beyond it) and brakes on it; one shot suffices."""
    m, i_max, lim, _, shot = _qsh5718_shot(24.0)
    b = shot.brake
    current = np.hypot(b.i_d[:shot.n_brake], b.i_q[:shot.n_brake])
    assert np.max(current) <= 0.995 * i_max * 1.005  # (without the pull: 1.4 % beyond, and a second shot)
    assert np.max(current) >= 0.98 * 0.995 * i_max  # still braking on the limit
    _, out = plan_raw(0.3, m, lim, 20000.0)
    assert out.tables == 1


@pytest.mark.parametrize("distance,exact", [(5.0, True), (0.3, False)])
def test_root_finders_first_try_from_the_braking_distance(distance: float, exact: bool) -> None:
    """The root finder's first try from the braking distance lands where the bracket does (exactly on a cruise)."""
    lim = limits(24.0)
    v = 0.98 * lim.v_use * lim.v_bus
    md = _Model(NEMA17, v, 0.995, 0.995 * speed_cap(NEMA17, lim, 20000.0), NEMA17.L * 0.995 / v / 10)
    up = _speed_up(md, distance)
    assert up is not None
    acc, n_acc, cruise = up
    assert cruise == exact
    landed = _land(md, acc, n_acc, cruise, distance)
    assert landed is not None
    last = (n_acc - 1) * md.h
    top = last + (distance - acc[0][n_acc - 1]) / acc[1][n_acc - 1] if cruise else last
    top_end = _land(md, acc, n_acc, cruise, distance, top)  # a far guess: the whole bracket again
    assert top_end is not None and top_end[0] == pytest.approx(landed[0], rel=1e-6)
    end, _ = _brake(md, acc, n_acc, cruise, top, None)
    assert end is not None
    est = estimate(md, acc, n_acc, cruise, distance, top, end.angle - distance)
    assert est == pytest.approx(landed[0], rel=1e-9 if exact else 0.1)


def test_the_switch_guess_lands_where_the_whole_bracket_does() -> None:
    """A switch guess near, far or out of the phase lands the shot where the whole bracket does."""
    v, cap, first = _nema17_12v_shot()
    for guess in (first.t_s, 0.9 * first.t_s, 1.2 * first.t_s, -1.0, 1.0):  # near, far and out of the phase
        again = shoot(0.3, NEMA17, v, 0.995, cap, 1.0, guess)
        assert again is not None and again.ramp == pytest.approx(first.ramp, rel=1e-6)
        assert again.t_s == pytest.approx(first.t_s, rel=1e-6)
        assert abs(again.end.angle - 0.3) <= 1e-6 * 0.3


def _voltages(plan: object, d_current: DCurrentPlan, m: MotorParams, n: int = 20000) -> tuple[np.ndarray, ...]:
    """The d-q flat inverse along the plan on a fine grid: (|v|, |i|, omega)."""
    t = np.linspace(plan.t0, plan.tf, n)  # type: ignore[attr-defined]
    f = plan.flag(t)  # type: ignore[attr-defined]
    i_d, di_d = d_current.flag(t, f.dtheta, f.ddtheta)
    i_q = (m.J * f.ddtheta + m.B * f.dtheta) / m.Km
    di_q = (m.J * f.dddtheta + m.B * f.ddtheta) / m.Km
    x = m.Nr * f.dtheta * m.L
    v_d = m.R * i_d + m.L * di_d - x * i_q
    v_q = m.R * i_q + m.L * di_q + x * i_d + m.Km * f.dtheta
    return np.hypot(v_d, v_q), np.hypot(i_d, i_q), f.dtheta


@pytest.mark.parametrize("v_bus,distance", [(24.0, 1.0), (12.0, 5.0)])
def test_plan_keeps_its_limits_on_a_fine_grid_and_weakens_the_field(v_bus: float, distance: float) -> None:
    """The plan keeps its voltage, current and speed limits on a fine grid, and weakens the field at speed."""
    lim = limits(v_bus)
    fw = time_optimal_dq(distance, NEMA17, lim, theta1=0.5, t0=0.01)
    v, i, w = _voltages(fw.plan, fw.d_current, NEMA17)
    assert np.max(v) <= 1.002 * lim.v_use * lim.v_bus  # the search checks 8 samples per segment
    assert np.max(i) <= 1.002 * lim.i_max
    assert np.max(np.abs(w)) <= speed_cap(NEMA17, lim, 20000.0)
    assert fw.found.margins["i_d_min"] < -0.3  # the back EMF is cancelled at speed
    assert fw.plan.theta1 == 0.5 and fw.plan.theta2 == pytest.approx(0.5 + distance, abs=1e-9)
    assert fw.d_current.flag([0.0, fw.plan.tf + 1.0])[0] == pytest.approx([0.0, 0.0], abs=1e-9)


def test_negative_move_mirrors_and_faster_than_without_field_weakening() -> None:
    """A negative move mirrors the positive one, and field weakening goes beyond the bus's no-load speed."""
    lim = limits(24.0)
    up, down = time_optimal_dq(5.0, NEMA17, lim), time_optimal_dq(-5.0, NEMA17, lim)
    assert down.plan.tf == up.plan.tf and down.plan.theta2 == pytest.approx(-5.0, abs=1e-9)
    assert down.d_current.knot_id == up.d_current.knot_id  # the d current does not change sign
    # the same search with the envelope held at i_d = 0 would stop at the no-load speed of the bus: FW goes beyond
    no_load = lim.v_use * lim.v_bus / NEMA17.Km
    assert up.found.margins["speed_peak"] > 1.1 * no_load
    assert up.found.margins["speed_peak"] > 0.98 * speed_cap(NEMA17, lim, 20000.0)


def test_speed_cap_follows_the_control_rate_and_the_user() -> None:
    """The speed cap follows the control rate, and a user's speed_max caps it further."""
    lim = limits(24.0)
    assert speed_cap(NEMA17, lim, 20000.0) == pytest.approx(0.035 * 2 * math.pi * 20000 / 50)
    slow = plan_dq_move(20.0, NEMA17, lim, control_rate=10000.0)
    assert slow.margins["speed_peak"] <= speed_cap(NEMA17, lim, 10000.0)
    capped = plan_dq_move(20.0, NEMA17, limits(24.0, speed_max=40.0))
    assert capped.margins["speed_peak"] <= 40.0 and capped.tf > slow.tf


def test_envelope_currents_lie_on_both_limits() -> None:
    """The envelope's currents keep both limits and lie on one of them; its top speed is set by friction."""
    v, i_max = 0.84 * 24.0, 1.0
    for w in (0.0, 50.0, 150.0):
        i_d, i_q, i_d2, i_q2 = best_currents(w, NEMA17, v, i_max)
        for d, q in ((i_d, i_q), (i_d2, i_q2)):
            x = NEMA17.Nr * w * NEMA17.L
            volt = math.hypot(NEMA17.R * d - x * q, NEMA17.R * q + x * d + NEMA17.Km * w)
            assert math.hypot(d, q) <= i_max * (1 + 1e-12) and volt <= v * (1 + 1e-12)
            assert math.isclose(math.hypot(d, q), i_max, rel_tol=1e-9) or math.isclose(volt, v, rel_tol=1e-9)
    env = dq_envelope(NEMA17, v, i_max, 1e4)
    assert env.omega[-1] < 1e4 and env.a_plus[-1] < 1e-6 * env.a_plus[0] + 1e-9  # the top speed, from friction


def test_hermite_table_rate_is_the_derivative() -> None:
    """The Hermite table's rate is the derivative of its current, and zero outside the knots."""
    knots = np.array([0.0, 1e-3, 3e-3, 4e-3])
    dc = DCurrentPlan(t0=0.0, tf=4e-3, knot_t=tuple(knots), knot_id=(0.0, -0.4, -0.5, 0.0),
                      knot_did=(0.0, -200.0, 100.0, 0.0))
    t = np.linspace(0.0, 4e-3, 4001)
    y, dy = dc.flag(t)
    np.testing.assert_allclose(dy[1:-1], np.gradient(y, t)[1:-1], atol=2.0)
    assert y[1000] == pytest.approx(-0.4) and y[3000] == pytest.approx(-0.5)
    assert hermite_cubic(np.array([-1.0, 1.0]), knots, np.array([0.0, -0.4, -0.5, 0.1]), np.zeros(4))[1].tolist() \
        == [0.0, 0.0]


def test_bad_arguments_are_named() -> None:
    """Bad rates, voltages, engines and knot tables are refused, naming them; a short work array returns -4."""
    with pytest.raises(ValueError, match="control_rate"):
        plan_dq_move(1.0, NEMA17, limits(), control_rate=-1.0)
    with pytest.raises(ValueError, match="voltage"):
        plan_dq_move(1.0, NEMA17, limits(), voltage="star")
    with pytest.raises(ValueError, match="engine"):
        time_optimal_dq(1.0, NEMA17, limits(), engine="fortran")
    with pytest.raises(ValueError, match="rising times"):
        DCurrentPlan(knot_t=(0.0, 0.0), knot_id=(0.0, 0.0), knot_did=(0.0, 0.0))
    with pytest.raises(ValueError, match="2 to 72 knots"):
        DCurrentPlan(knot_t=(0.0, 1.0), knot_id=(0.0,), knot_did=(0.0, 0.0))
    rc, out = plan_raw(1.0, NEMA17, limits(), 20000.0, work_len=10)
    assert rc == -4 and out.n == 0


def test_plan_tracked_by_the_dq_law_on_a_20khz_drive() -> None:
    """The d-q law tracks the plan on a 20 kHz drive within 2 mrad, following its d current below -0.2 A."""
    lim = limits(24.0)
    fw = time_optimal_dq(0.3, NEMA17, lim)
    loop = drive_loop(24.0, 20000.0, 4000)
    d = design_gains(NEMA17, fw.plan, control_period=loop.control_period, v_bus=24.0, encoder_counts=4000,
                     current_step=4 / 4096)
    loop = replace(loop, observer=d.observer)
    ctrl = DQFlatnessSMC(NEMA17, fw.plan, d.gains, "observer", d_current=fw.d_current)
    r = simulate(NEMA17, fw.plan, ctrl, loop=loop, t_end=fw.plan.tf + 0.005, x0=[0.0, 0.0, 0.0, 0.0])
    during = r.t <= fw.plan.tf
    assert r.status == "ok"
    assert np.max(np.abs(r.theta_error[during])) < 2e-3
    # the law follows the planned d current: below -0.2 A at the peak speed
    i_d = np.cos(NEMA17.Nr * r.theta) * r.ia + np.sin(NEMA17.Nr * r.theta) * r.ib
    k = int(np.argmax(r.omega))
    assert i_d[k] < -0.2


_FILE = """
[motor]
preset = "nema17"
[drive]
v_bus = 24.0
control_rate = 20000.0
[limits]
i_max = 1.0
v_use = 0.84
[plan]
planner = "time_optimal"
field_weakening = true
waypoints = [0.5, {last}]
[controller]
type = "{ctrl}"
"""


def test_scenario_file_plans_field_weakening_for_the_dq_law(tmp_path: object) -> None:
    """A scenario file plans the field-weakening move for the d-q law, and refuses it for another law or plan."""
    from pathlib import Path

    from flatstep.studies.scenario_file import read_scenario_file

    p = Path(str(tmp_path)) / "fw.toml"
    p.write_text(_FILE.format(last=1.5, ctrl="dq_smc"))
    sf = read_scenario_file(p)
    direct = time_optimal_dq(1.0, NEMA17, limits(24.0), theta1=0.5)
    assert sf.scenario.plan.tf == pytest.approx(direct.plan.tf, rel=1e-12)
    assert sf.scenario.d_current.knot_id == direct.d_current.knot_id
    p.write_text(_FILE.format(last=1.5, ctrl="smc"))
    with pytest.raises(ValueError, match="fw.toml:controller: a field-weakening plan is tracked by a dq_smc"):
        read_scenario_file(p)
    p.write_text(_FILE.format(last="1.5, 2.5", ctrl="dq_smc"))
    with pytest.raises(ValueError, match="plan.waypoints: field_weakening plans one move"):
        read_scenario_file(p)
    p.write_text(_FILE.format(last=1.5, ctrl="dq_smc").replace("field_weakening = true", 'voltage = "phase"'))
    with pytest.raises(ValueError, match="plan.voltage: the bus limit is chosen for a field-weakening plan"):
        read_scenario_file(p)
