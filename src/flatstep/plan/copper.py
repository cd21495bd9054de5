r"""The rest-to-rest plan of least copper loss for a given duration.

The planned currents cost :math:`R\int\rho^{*2}\,dt` with :math:`\rho^{*2} = i_q^2 + i_d^2`, the torque current
:math:`i_q = (J\ddot\theta + B\dot\theta)/K_m` and the planned current across the torque axis
(:meth:`~flatstep.plan.limits.MotorLimits.across`). The move is :math:`\theta = \theta_1 + D\,p(\tau)`,
:math:`\tau = (t - t_0)/T`, with :math:`p` of degree 10 at rest at both ends up to the third derivative
(:math:`p(0) = 0`, :math:`p(1) = 1`, :math:`p^{(k)}(0) = p^{(k)}(1) = 0` for :math:`k = 1, 2, 3`): three free
coefficients, of which the paper's psi is one choice. :func:`min_copper_plan` starts from psi and minimizes
the loss over the three (:func:`scipy.optimize.minimize`, the loss on a 401-point grid), then
checks the result against the limits.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import NDArray
from scipy.integrate import trapezoid

from ..model.motor import MotorParams
from ..validate import InputError, check_quantity
from .arguments import check_angle, check_limits, check_motor, check_plan_table, check_samples_per_segment, check_t0
from .baselines import _split, with_torque_current
from .limits import MotorLimits
from .margins import plan_margins
from .piecewise import NCOEF, PiecewisePlan, horner
from .rest_to_rest import _PSI_HORNER

Array = NDArray[np.float64]
_TAU = np.linspace(0.0, 1.0, 401)


def _family() -> tuple[Array, Array]:
    """The ascending coefficients of psi, and a basis (11, 3) of the degree-10 polynomials at rest at both ends."""
    from scipy.linalg import null_space

    rows = []
    for k in range(4):
        rows.append([math.perm(j, k) * (1.0 if j == k else 0.0) for j in range(NCOEF)])  # p^(k)(0)
        rows.append([float(math.perm(j, k)) for j in range(NCOEF)])  # p^(k)(1)
    return _PSI_HORNER[0][::-1].copy(), null_space(np.array(rows))


def _loss(c: Array, distance: float, duration: float, motor: MotorParams, limits: MotorLimits) -> float:
    """R times the integral of rho*^2 over the move for the ascending coefficients ``c``."""
    speed = distance * P.polyval(_TAU, P.polyder(c)) / duration
    acc = distance * P.polyval(_TAU, P.polyder(c, 2)) / duration**2
    rho = limits.rho((motor.J * acc + motor.B * speed) / motor.Km, speed)
    return float(motor.R * duration * trapezoid(rho**2, _TAU))


def copper_loss(plan: PiecewisePlan, motor: MotorParams, samples_per_segment: int = 64) -> float:
    r"""The planned copper loss :math:`R\int\rho^{*2}\,dt` [J] over the plan's move (midpoint rule)."""
    plan, motor = check_plan_table(plan), check_motor(motor)
    samples_per_segment = check_samples_per_segment(samples_per_segment, plan.n)
    tau = (np.arange(samples_per_segment) + 0.5) / samples_per_segment
    rho = horner(np.repeat(plan.rho, tau.size, axis=0), np.tile(tau, plan.n))
    return float(motor.R * np.sum(rho**2 * np.repeat(plan.durations / tau.size, tau.size)))


def min_copper_plan(distance: float, duration: float, motor: MotorParams, limits: MotorLimits, *,
                    theta1: float = 0.0, t0: float = 0.0) -> PiecewisePlan:
    """The rest-to-rest move over ``distance`` [rad] in ``duration`` [s] of least planned copper loss.

    Raises
    ------
    ValueError
        For a zero distance, or when even this plan exceeds the limits (the duration is too short).
    """
    from scipy.optimize import minimize

    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    T = check_quantity("time", duration, as_name="duration")
    if T <= 0:
        raise InputError("duration", duration, f"duration={T!r} s must be > 0")
    check_motor(motor)
    check_limits(limits)
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    psi, basis = _family()
    res = minimize(lambda z: _loss(psi + basis @ z, abs(d), T, motor, limits), np.zeros(basis.shape[1]),
                   method="BFGS")
    c = psi + basis @ res.x
    rows, h = _split(abs(d) * c[::-1][None, :], np.array([T]), 8)
    plan = with_torque_current(rows, h, motor, limits, theta1=theta1, t0=t0, sign=1.0 if d > 0 else -1.0)
    m = plan_margins(plan, motor, limits)
    if m["worst"] > 1.0 or m["voltage"] > limits.v_use:
        raise ValueError(f"the least-loss move of {d} rad in {T} s exceeds the limits (voltage {m['voltage']:.3f} "
                         f"of the bus, current {m['current']:.3f}, torque angle {m['torque_angle']:.3f}): "
                         "give a longer duration (time_optimal gives the shortest)")
    return plan
