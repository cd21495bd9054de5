"""Every controller type tracks every plan (flatstep.plan.protocol.Plan), on the C engine and the Python reference.

The table runs each of :data:`flatstep.control.tuning.CONTROLLER_TYPES` on four plans: the paper's psi move
(a :class:`~flatstep.plan.rest_to_rest.RestToRest`, psi evaluated in C), a psi and a Hermite waypoint sequence with a
dwell (:func:`~flatstep.plan.waypoints.plan_waypoints`) and a time-optimal move whose rho* rises with the torque it
needs (:func:`~flatstep.plan.time_optimal.time_optimal`), all segment tables in C. The drive: 20 kHz, ideal sensors,
no bus limit, the flatness gains from :func:`~flatstep.loop.design.design_gains` for each plan, the baselines
tuned by rule; the plant is the controllers' model with a detent torque, which the ``_ff`` types know.

Tracking on the C engine: a closed-loop type within :data:`CLOSED_LOOP_TOL` of theta* all along the run and at its
end; the open-loop microstepping driver within one full step (it lags by its load angle and rings after the move,
but loses no step). Parity: the C loop against the Python reference over the first periods of each run.
"""
import math

import numpy as np
import pytest

import flatstep as fs
from flatstep import core
from flatstep.core.structs import controller_struct
from flatstep._flatstep_core import ffi
from flatstep.loop.design import design_gains
from flatstep.control.protocol import is_static
from flatstep.control.tuning import CONTROLLER_TYPES, make_controller
from flatstep.loop.reference import run_reference
from flatstep.plan.limits import MotorLimits
from flatstep.plan.piecewise import PiecewisePlan
from flatstep.plan.protocol import Plan, check_plan
from flatstep.plan.rest_to_rest import PAPER_PLAN
from flatstep.plan.time_optimal import time_optimal
from flatstep.plan.waypoints import Caps, Waypoint, plan_waypoints

MOTOR = fs.MotorParams.preset("paper")
TS = 5e-5
#: The plant: the controllers' model and a detent of 5 % of the holding torque Km rho at 0.4 A.
PLANT = fs.Plant(MOTOR, fs.PlantEffects(detent_torque=1e-3))
TORQUES = fs.TorqueModel.of_plant(PLANT)
#: Largest |theta - theta*| [rad] of a closed-loop type over the run (a sixtieth of a full step; measured: at most
#: 2.4e-4 rad, the rule-tuned cascade on the time-optimal move; 3.3e-5 rad or less for the flatness laws).
CLOSED_LOOP_TOL = 5e-4
#: Largest |theta - theta2| [rad] of a closed-loop type 10 ms after the plan ends.
CLOSED_LOOP_FINAL_TOL = 1e-5
#: One full step [rad]: the open-loop driver must stay within it (no step lost).
FULL_STEP = 2 * math.pi / (4 * MOTOR.Nr)
#: Periods of the parity runs (C against the Python reference, 8 ms from t = 0).
PARITY_PERIODS = 160


def _waypoints(family: str) -> PiecewisePlan:
    """Four waypoints with a dwell, at 0.4 A, from t = 2 ms."""
    return plan_waypoints([0.0, 0.02, Waypoint(0.05, dwell=0.01), -0.01], family=family, rho=0.4, t0=0.002,
                          caps=Caps(3.0, 300.0, 3e4))


PLANS = {
    "paper_psi": lambda: PAPER_PLAN,
    "psi_waypoints": lambda: _waypoints("psi"),
    "hermite": lambda: _waypoints("hermite"),
    # 0.2 rad at a 12 V bus and 0.6 A: rho* rises from the 0.3 A hold to 0.6 A while the move needs torque
    "time_optimal": lambda: time_optimal(0.2, MOTOR, MotorLimits(v_bus=12.0, i_max=0.6, torque_angle_max=0.6),
                                         t0=0.002),
}


@pytest.fixture(scope="module")
def plans() -> dict[str, Plan]:
    """Each plan of :data:`PLANS`, built once."""
    return {name: build() for name, build in PLANS.items()}


def _controller(kind: str, plan: Plan):
    """The type ``kind`` on ``plan`` for the 20 kHz drive, with the plan's designed flatness gains."""
    gains = design_gains(MOTOR, plan, control_period=TS, v_bus=48.0, encoder_counts=None).gains
    return make_controller(kind, MOTOR, plan, control_period=TS, measurement="ideal", smc_gains=gains,
                           torques=TORQUES)


def test_every_planner_output_is_a_plan(plans):
    for plan in plans.values():
        check_plan(plan)
        assert isinstance(plan, Plan)
    table = PAPER_PLAN.to_table()
    assert isinstance(table, PiecewisePlan) and table.to_table() is table and table.n == 1
    t = np.linspace(0.0, 0.05, 501)
    for a, b in zip(PAPER_PLAN.flag(t), table.flag(t), strict=True):  # psi as one segment: the same flag
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-11 * max(1.0, np.max(np.abs(a))))
    assert "traj" not in PAPER_PLAN.c_plan() and table.c_plan()["traj"] is table.c_struct()
    assert {k: v for k, v in table.c_plan().items() if k != "traj"} == pytest.approx(PAPER_PLAN.as_dict())
    for plan in (PAPER_PLAN, table, plans["time_optimal"]):  # C plan_eval on struct plan: psi, or the table
        tt = np.linspace(plan.t0 - 0.001, plan.tf + 0.001, 301)
        for a, b in zip(core.plan_flag(plan, tt), plan.flag(tt), strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13 * max(1.0, np.max(np.abs(b))))
    with pytest.raises(ValueError, match=r"not a flatstep plan: it lacks \['theta1'"):
        check_plan(type("Half", (), {"t0": 0.0, "tf": 1.0})())


@pytest.mark.parametrize("kind", CONTROLLER_TYPES)
def test_every_c_twin_reads_the_plan_it_is_given(kind, plans):
    """The C state's reference is the plan's table (struct plan.traj), or psi (NULL) for the paper's move."""
    for plan in plans.values():
        bound = controller_struct(_controller(kind, plan))
        expected = plan.c_struct() if isinstance(plan, PiecewisePlan) else ffi.NULL
        assert bound.state.plan.traj == expected and bound.state.p.plan.traj == expected
        assert bound.state.p.plan.tf == plan.tf and bound.state.p.plan.theta2 == plan.theta2


@pytest.mark.parametrize("plan_name", list(PLANS))
@pytest.mark.parametrize("kind", CONTROLLER_TYPES)
def test_every_type_tracks_every_plan_on_c(kind, plan_name, plans):
    plan = plans[plan_name]
    ctrl = _controller(kind, plan)
    r = fs.simulate(PLANT, plan, ctrl, loop=fs.DriveLoop(control_period=TS, substeps=2), t_end=plan.tf + 0.01)
    assert r.meta["engine"] == "c" and r.meta["controller_faults"] == 0
    np.testing.assert_allclose(r.theta_ref, plan.flag(r.t).theta, rtol=0, atol=1e-12)
    error, final = np.max(np.abs(r.theta - r.theta_ref)), abs(r.theta[-1] - plan.theta2)
    if kind == "microstep":
        assert error < FULL_STEP and final < FULL_STEP / 4, (error, final)
    else:
        assert error < CLOSED_LOOP_TOL and final < CLOSED_LOOP_FINAL_TOL, (error, final)


#: The parity plans: a short psi waypoint sequence at 0.8 A (3 moves of 2 ms and a 1 ms dwell from t = 2 ms, so that
#: the parity window crosses its breaks; its torque demand peaks at 0.38 Km rho) and the time-optimal move (its
#: segments are 0.3 ms long).
PARITY_PLANS = {
    "short_psi_waypoints": lambda: plan_waypoints([0.0, 0.001, Waypoint(0.002, dwell=0.001), 0.0005], family="psi",
                                                  rho=0.8, t0=0.002, durations=[2e-3, 2e-3, 2e-3]),
    "time_optimal": PLANS["time_optimal"],
}


@pytest.mark.parametrize("plan_name", list(PARITY_PLANS))
@pytest.mark.parametrize("kind", CONTROLLER_TYPES)
def test_c_loop_is_the_python_reference(kind, plan_name):
    plan = PARITY_PLANS[plan_name]()
    ctrl = _controller(kind, plan)
    loop = fs.DriveLoop(control_period=TS, substeps=1)
    x0 = plan.x0(MOTOR.Nr)
    X, V, _, status, _ = core.run_sampled(ctrl, MOTOR, 0.0, x0, PARITY_PERIODS, Ts=TS, substeps=1,
                                          effects=PLANT.effects)
    py = run_reference(MOTOR, ctrl, loop, x0, 0.0, PARITY_PERIODS, PLANT.effects)
    t = py["t"]
    assert np.sum(plan.breaks < t[-1]) >= 4 and np.ptp(X[3]) > 9e-4  # the window holds moves, and breaks of the table
    assert not (status & core.FAULT_BITS).any() and py["faults"].size == 0
    np.testing.assert_allclose(X, py["x"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(V, py["v"], rtol=0, atol=1e-7)


#: The static types, which also run in continuous time.
STATIC_TYPES = tuple(k for k in CONTROLLER_TYPES if is_static(_controller(k, PAPER_PLAN)))


@pytest.mark.parametrize("kind", [k if k == "exact_linearization" else pytest.param(k, marks=pytest.mark.slow)
                                  for k in STATIC_TYPES])  # about 2 s of SciPy each: one in the default run
def test_continuous_c_loop_tracks_a_table_as_scipy_does(kind):
    """C ``continuous_run`` against SciPy's DOP853 on the short waypoint table, restarted at its breaks."""
    plan = PARITY_PLANS["short_psi_waypoints"]()
    ctrl = _controller(kind, plan)
    solver = fs.Continuous(method="DOP853", rtol=1e-10, atol=1e-12, dt_out=1e-4, max_wall_time=300.0)
    c = fs.simulate(PLANT, plan, ctrl, solver=solver, t_end=plan.tf + 0.002)
    sp = fs.simulate(PLANT, plan, ctrl, solver=solver, t_end=plan.tf + 0.002, engine="scipy")
    np.testing.assert_array_equal(c.t, sp.t)
    assert np.max(np.abs(c.theta - c.theta_ref)) < 1e-5 and abs(c.theta[-1] - plan.theta2) < 1e-6
    np.testing.assert_allclose(c.theta, sp.theta, rtol=0, atol=1e-8)


def test_batch_summaries_measure_against_the_table(plans):
    """The C batch summaries read the plan's table (struct plan.traj), as SimResult.summary does."""
    plan = plans["hermite"]
    ctrl = _controller("cascade", plan)
    n = int(round((plan.tf + 0.01) / TS))
    rows = core.run_sampled_summaries([dict(controller=ctrl, motor=MOTOR, load=0.0, effects=PLANT.effects,
                                                x0=plan.x0(MOTOR.Nr), n_periods=n, Ts=TS, substeps=2)])
    r = fs.simulate(PLANT, plan, ctrl, loop=fs.DriveLoop(control_period=TS, substeps=2), t_end=n * TS)
    assert rows[0] is not None and rows[0]["status"] == "ok"
    summary = r.summary()
    assert rows[0]["max_abs_theta_error"] == pytest.approx(summary["max_abs_theta_error"], rel=1e-9, abs=1e-15)
    assert rows[0]["max_abs_theta_error"] < CLOSED_LOOP_TOL  # against psi of the end points it would be ~0.03 rad
