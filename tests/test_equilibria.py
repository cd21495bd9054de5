import math

import numpy as np
import pytest

import flatstep as fs


@pytest.mark.parametrize("ia, ib", [(0.4, 0.0), (0.0, 0.4), (-0.3, 0.1), (0.21588, 0.3366), (-0.2, -0.25)])
def test_classification_matches_proposition_2_1(motor, ia, ib):
    points = fs.rest_positions(motor, ia, ib, ks=range(-4, 5))
    for p in points:
        # Proposition 2.1: even k stable (both eigenvalues in the open left half plane), odd k saddles
        assert p.stable == (p.k % 2 == 0)
        re = sorted(e.real for e in p.eigenvalues)
        if not p.stable:
            assert re[0] < 0 < re[1] and all(abs(e.imag) == 0 for e in p.eigenvalues)
        # each critical point is an equilibrium of eq. (1) at these currents: zero torque
        assert fs.model.motor.torque([ia, ib, 0.0, p.theta], motor) == pytest.approx(0.0, abs=1e-15)


def test_eigenvalues_include_the_missing_1_over_J(motor):
    p = fs.rest_positions(motor, 0.4, 0.0, ks=[0])[0]
    # char. poly s^2 + (B/J) s + Km Nr rho / J
    prod = p.eigenvalues[0] * p.eigenvalues[1]
    assert prod.real == pytest.approx(0.05 * 50 * 0.4 / 3.6e-6, rel=1e-12)
    assert (p.eigenvalues[0] + p.eigenvalues[1]).real == pytest.approx(-1e-4 / 3.6e-6, rel=1e-12)


def test_voltages_give_the_same_rest_positions(motor):
    by_v = fs.rest_positions(motor, va=0.4 * 8.4, vb=0.1 * 8.4)
    by_i = fs.rest_positions(motor, 0.4, 0.1)
    assert [p.theta for p in by_v] == pytest.approx([p.theta for p in by_i], rel=1e-14)


def test_stable_angle_aligns_rotor_with_current_vector(motor):
    th = fs.stable_angle(0.21588, 0.3366, 50, near=0.0)
    assert th == pytest.approx(math.atan2(0.3366, 0.21588) / 50, rel=1e-14)
    # the stable point found by classification is the same one, up to a tooth pitch
    stable = [p.theta for p in fs.rest_positions(motor, 0.21588, 0.3366, ks=range(-4, 5)) if p.stable]
    assert min(abs(s - th) for s in stable) < 1e-15
    assert fs.stable_angle(0.4, 0.0, 50, near=2 * math.pi / 50 * 3 + 0.01) == pytest.approx(2 * math.pi / 50 * 3)


def test_bad_inputs(motor):
    with pytest.raises(ValueError, match=r"\(0, 0\)"):
        fs.rest_positions(motor, 0.0, 0.0)
    with pytest.raises(ValueError, match="not both"):
        fs.rest_positions(motor, 0.4, 0.0, va=1.0, vb=0.0)
    with pytest.raises(ValueError, match="must be finite"):
        fs.rest_positions(motor, float("nan"), 0.1)
    with pytest.raises(ValueError, match="no rest position"):
        fs.stable_angle(0.0, 0.0, 50)


def test_equilibrium_currents_of_paper_end_point():
    ia, ib = fs.equilibrium_currents(0.02, 0.4, 50)
    # the paper quotes ia2 = 0.21588 A for rho2 = 0.4 A; exactly 0.4 cos(1) = 0.216121
    assert ia == pytest.approx(0.4 * math.cos(1.0)) and abs(ia - 0.21588) < 3e-4
    assert ib == pytest.approx(0.4 * math.sin(1.0))
    np.testing.assert_allclose(fs.rhs(0, [ia, ib, 0.0, 0.02], [8.4 * ia, 8.4 * ib], fs.MotorParams.preset("paper")),
                               0.0, atol=1e-12)
