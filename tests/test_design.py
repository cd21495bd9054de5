import numpy as np
import pytest

import flatstep as fs
from flatstep.loop.design import LAMBDA_TS, design_gains


def test_rules_hold(motor, plan):
    d = design_gains(motor, plan, control_period=5e-5)
    g = d.gains
    lam = LAMBDA_TS / 5e-5
    assert g.W1 / g.eps1 == pytest.approx(lam) and g.W2 / g.eps2 == pytest.approx(lam)
    assert g.wn == pytest.approx(lam / 4) and d.observer.bandwidth == pytest.approx(g.wn)
    # reaching gains exceed the disturbance bound computed along the plan
    assert g.W1 > d.rationale["d1_max"] and g.W2 > d.rationale["d2_max"]
    # the rho channel bound, by hand: delta (R rho) / L with the paper's move at constant rho and peak speed
    omega_max = np.max(plan.flag(np.linspace(0.02, 0.04, 2001)).dtheta)
    assert d.rationale["d1_max"] == pytest.approx(0.1 * (8.4 * 0.4 + 0.05 * omega_max) / 0.01, rel=1e-6)
    assert d.warnings == ()


def test_scaling_with_rate_delay_and_uncertainty(motor, plan):
    fast, slow = design_gains(motor, plan, control_period=2.5e-5), design_gains(motor, plan, control_period=1e-4)
    assert fast.gains.wn == pytest.approx(4 * slow.gains.wn)
    delayed = design_gains(motor, plan, compute_delay=True)
    assert delayed.rationale["lambda_Ts"] == pytest.approx(0.15)
    assert design_gains(motor, plan, uncertainty=0.2).gains.W1 == pytest.approx(
        2 * design_gains(motor, plan, uncertainty=0.1).gains.W1)


def test_warnings(motor, plan):
    coarse = design_gains(motor, plan, current_step=0.05)
    assert any("ADC step" in w for w in coarse.warnings)
    low_bus = design_gains(motor, plan, v_bus=4.0)
    assert any("75 % of v_bus" in w for w in low_bus.warnings)
    fast = fs.RestToRest(0.0, 0.05, 0.4, 0.4, 0.02, 0.022)
    assert any("infeasible" in w for w in design_gains(motor, fast).warnings)


@pytest.mark.parametrize("kwargs, match", [
    (dict(control_period=0.0), "control_period=0.0"), (dict(uncertainty=0.6), "uncertainty=0.6"),
    (dict(v_bus=-24.0), "v_bus=-24.0"), (dict(load_torque=float("nan")), "load_torque=nan"),
    (dict(current_step=-1.0), "current_step=-1.0"),
])
def test_bad_design_inputs(motor, plan, kwargs, match):
    with pytest.raises(ValueError, match=match):
        design_gains(motor, plan, **kwargs)
