import numpy as np
import pytest

import flatstep as fs
from flatstep.loop.observers import Observer
from flatstep.loop.reference import DriveLoop, run_reference
from flatstep.loop.sensors import Sensors

TS = 5e-5


@pytest.mark.parametrize("load_states", [0, 1, 2])
def test_error_poles_are_placed(motor, load_states):
    obs = Observer(bandwidth=1500.0, load_states=load_states)
    Ad, Bd, Lc = obs.matrices(motor, TS)
    C = np.zeros((1, obs.order))
    C[0, 0] = 1.0
    # current-estimator error dynamics e+ = Ad (I - Lc C) e
    eig = np.sort(np.linalg.eigvals(Ad @ (np.eye(obs.order) - np.outer(Lc, C))).real)
    want = np.sort(np.exp(-1500.0 * TS * np.linspace(1.0, 1.3, obs.order)))
    np.testing.assert_allclose(eig, want, rtol=1e-9)
    # the model part is the exact ZOH discretization: theta advances by omega Ts for a coasting rotor
    assert Ad[0, 1] == pytest.approx((motor.J / motor.B) * (1 - np.exp(-motor.B / motor.J * TS)), rel=1e-12)


def test_estimates_converge_to_speed_and_load(motor, plan):
    """Exact sensors, the observer in the loop: after the move, the load estimate is the true load and the
    speed estimate follows the rotor."""
    g = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
    ctrl = fs.FlatnessSMC(motor, plan, g, measurement="observer")
    loop = DriveLoop(control_period=TS, sensors=Sensors(encoder_counts=None, current_bits=None),
                     observer=Observer(bandwidth=1500.0, load_states=1))
    r = run_reference(motor, ctrl, loop, plan.x0(50), 1e-5, 1200)
    omega_hat, acc_hat = r["y"][2], r["y"][4]
    during = (r["t"] > 0.022) & (r["t"] < 0.038)
    assert np.max(np.abs(omega_hat[during] - r["x"][2][during])) < 0.01 * np.max(r["x"][2])
    # at rest the acceleration estimate is (Te - B w - tau_hat)/J ~ 0, so tau_hat has converged to the load
    assert np.max(np.abs(acc_hat[r["t"] > 0.05])) < 0.05


def test_bad_observer_values(motor):
    with pytest.raises(ValueError, match="bandwidth=0.0"):
        Observer(bandwidth=0.0)
    with pytest.raises(ValueError, match="load_states=3"):
        Observer(load_states=3)
    with pytest.raises(ValueError, match="too high for control_period"):
        Observer(bandwidth=1e6).matrices(motor, TS)
