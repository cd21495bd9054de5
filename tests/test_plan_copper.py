"""The least-copper-loss plan for a given duration (flatstep.plan.copper)."""
import numpy as np
import pytest
from scipy.integrate import trapezoid

from flatstep.model.motor import PRESETS
from flatstep.plan.baselines import _split, with_torque_current
from flatstep.plan.copper import copper_loss, min_copper_plan
from flatstep.plan.limits import MotorLimits
from flatstep.plan.margins import plan_margins
from flatstep.plan.rest_to_rest import _PSI_HORNER

MOTOR = PRESETS["nema17"]
LIMITS = MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.1)


def psi_plan(distance, duration, theta1=0.0, t0=0.0):
    """The paper's psi over the same move, with the same current rule."""
    rows, h = _split(abs(distance) * _PSI_HORNER[0][None, :], np.array([duration]), 8)
    return with_torque_current(rows, h, MOTOR, LIMITS, theta1=theta1, t0=t0, sign=np.sign(distance))


@pytest.mark.parametrize("distance, duration", [(5.0, 0.2), (-1.0, 0.05)])
def test_less_loss_than_psi_in_the_same_time_within_the_limits(distance, duration):
    plan = min_copper_plan(distance, duration, MOTOR, LIMITS, theta1=1.0, t0=0.01)
    psi = psi_plan(distance, duration, theta1=1.0, t0=0.01)
    assert copper_loss(plan, MOTOR) < 0.95 * copper_loss(psi, MOTOR)
    assert abs(plan.theta2 - (1.0 + distance)) < 1e-9 and plan.t0 == 0.01 and abs(plan.tf - 0.01 - duration) < 1e-12
    assert plan_margins(plan, MOTOR, LIMITS)["worst"] <= 1.0
    assert np.all(np.abs(plan.continuity(3)) <= 1e-6 * np.array([1.0, 1e2, 1e4, 1e7]))
    t = np.linspace(plan.t0, plan.tf, 20001)
    # the midpoint loss agrees with a dense trapezoid of the flag's rho
    dense = MOTOR.R * trapezoid(plan.flag(t).rho ** 2, t)
    assert abs(copper_loss(plan, MOTOR) - dense) < 1e-4 * dense


def test_too_short_a_duration_is_refused():
    with pytest.raises(ValueError, match="give a longer duration"):
        min_copper_plan(5.0, 0.1, MOTOR, LIMITS)
    with pytest.raises(ValueError, match="distance=0.0"):
        min_copper_plan(0.0, 0.1, MOTOR, LIMITS)
    with pytest.raises(ValueError, match="duration"):
        min_copper_plan(1.0, -0.1, MOTOR, LIMITS)
