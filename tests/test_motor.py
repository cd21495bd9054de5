import math

import numpy as np
import pytest

import flatstep as fs
from flatstep.model.motor import load_function, torque


def test_paper_preset_values(motor):
    assert (motor.R, motor.L, motor.Km, motor.J, motor.B, motor.Nr) == (8.4, 0.010, 0.05, 3.6e-6, 1e-4, 50)


@pytest.mark.parametrize("name, value, match", [
    ("R", 0.0, "R=0.0"), ("R", -1.0, "R=-1.0"), ("L", 0.0, "L=0.0"), ("Km", -0.05, "Km=-0.05"),
    ("J", 0.0, "J=0.0"), ("B", -1e-4, "B=-0.0001"), ("R", float("nan"), "R=nan"), ("J", math.inf, "J=inf"),
    ("B", float("nan"), "B=nan"), ("Nr", 0, "Nr=0"), ("Nr", -3, "Nr=-3"), ("Nr", 50.5, "Nr=50.5"),
    ("Nr", float("nan"), "Nr=nan"), ("Nr", "50", "Nr='50'"), ("Km", "abc", "Km='abc'"),
])
def test_invalid_parameters_raise(motor, name, value, match):
    with pytest.raises(ValueError, match=match):
        motor.replace(**{name: value})


def test_integral_float_Nr_is_accepted(motor):
    assert motor.replace(Nr=50.0).Nr == 50


def test_unknown_preset_and_parameter(motor):
    with pytest.raises(ValueError, match="unknown motor preset 'nema99'"):
        fs.MotorParams.preset("nema99")
    with pytest.raises(ValueError, match="unknown motor parameter"):
        motor.replace(Rs=1.0)


def test_rhs_matches_eq1_by_hand(motor):
    x = np.array([0.3, -0.2, 1.5, 0.013])
    v = np.array([2.0, -1.0])
    s, c = math.sin(50 * 0.013), math.cos(50 * 0.013)
    expected = [(2.0 - 8.4 * 0.3 + 0.05 * 1.5 * s) / 0.01, (-1.0 + 8.4 * 0.2 - 0.05 * 1.5 * c) / 0.01,
                (0.05 * (-0.3 * s - 0.2 * c) - 1e-4 * 1.5 - 2e-5) / 3.6e-6, 1.5]
    np.testing.assert_allclose(fs.rhs(0.0, x, v, motor, load=2e-5), expected, rtol=1e-14)


def test_rhs_is_vectorized_and_accepts_load_function(motor):
    rng = np.random.default_rng(1)
    X, V, t = rng.normal(size=(4, 7)), rng.normal(size=(2, 7)), np.linspace(0, 1, 7)
    out = fs.rhs(t, X, V, motor, load=lambda t: 1e-5 * t)
    for k in range(7):
        np.testing.assert_allclose(out[:, k], fs.rhs(t[k], X[:, k], V[:, k], motor, load=1e-5 * t[k]), rtol=1e-14)


def test_load_function_rejects_nan():
    with pytest.raises(ValueError, match="load_torque=nan"):
        load_function(float("nan"))
    with pytest.raises(ValueError, match="non-finite"):
        load_function(lambda t: np.nan * t)(np.array([0.0, 1.0]))


def test_torque_is_km_times_q_current(motor):
    theta = 0.011
    ia, ib = 0.4 * math.cos(50 * theta + 0.3), 0.4 * math.sin(50 * theta + 0.3)
    # rotating the current 0.3 rad ahead of the rotor gives Km rho sin(0.3)
    assert torque([ia, ib, 0.0, theta], motor) == pytest.approx(0.05 * 0.4 * math.sin(0.3), rel=1e-13)
