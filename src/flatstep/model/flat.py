r"""Flat outputs (rho, theta) <-> state and inputs: eqs. (7)-(10), derived again (the printed (9) has misprints).

With :math:`\delta = N_r\theta + \phi` and the torque demand :math:`A = J\ddot\theta + B\dot\theta + \tau`,
the model in polar form (8) gives

.. math::
    \cos\delta = \frac{A}{K_m\rho},\qquad
    \dot\phi = -\frac{(J\theta^{(3)} + B\ddot\theta)\rho - A\dot\rho}{\rho\sqrt{K_m^2\rho^2 - A^2}} - N_r\dot\theta,

    \begin{bmatrix} v_a \\ v_b \end{bmatrix} =
    \begin{bmatrix} \sin\phi & \cos\phi \\ \cos\phi & -\sin\phi \end{bmatrix}
    \begin{bmatrix} L\dot\rho + R\rho + K_m\dot\theta\cos\delta \\ L\rho\dot\phi - K_m\dot\theta\sin\delta \end{bmatrix}

(the matrix is its own inverse). The branch :math:`\delta = \arccos(A / K_m\rho) \in (0, \pi)` is the one
through the stable equilibria (:math:`\delta = \pi/2`); see docs/paper-notes.md.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .motor import MotorParams

Array = NDArray[np.float64]


class FlatFlag(NamedTuple):
    """The flat outputs and the derivatives the maps need, each an array over time."""

    rho: Array
    drho: Array
    theta: Array
    dtheta: Array
    ddtheta: Array
    dddtheta: Array


def polar(ia: ArrayLike, ib: ArrayLike) -> tuple[Array, Array]:
    r"""Eq. (7): the current vector's norm and phase.

    .. math:: \rho = \sqrt{i_a^2 + i_b^2},\qquad \phi = \operatorname{atan2}(i_a, i_b)

    (the quadrant-correct form of the printed :math:`\arctan(i_a/i_b)`).
    """
    ia, ib = np.asarray(ia, dtype=float), np.asarray(ib, dtype=float)
    return np.hypot(ia, ib), np.arctan2(ia, ib)


def cartesian(rho: ArrayLike, phi: ArrayLike) -> tuple[Array, Array]:
    """Inverse of :func:`polar`: ``ia = rho sin phi``, ``ib = rho cos phi``."""
    rho, phi = np.asarray(rho, dtype=float), np.asarray(phi, dtype=float)
    return rho * np.sin(phi), rho * np.cos(phi)


def polar_rhs(z: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: ArrayLike = 0.0) -> Array:
    r"""The model in polar coordinates, eq. (8), for ``z = (rho, phi, omega, theta)``.

    .. math::
        L\dot\rho = -R\rho - K_m\omega\cos\delta + v_b\cos\phi + v_a\sin\phi,\quad
        L\rho\dot\phi = K_m\omega\sin\delta - v_b\sin\phi + v_a\cos\phi,\\
        J\dot\omega = K_m\rho\cos\delta - B\omega - \tau,\quad \dot\theta = \omega
    """
    rho, phi, omega, theta = np.asarray(z, dtype=float)
    va, vb = np.asarray(v, dtype=float)
    delta = motor.Nr * theta + phi
    sp, cp = np.sin(phi), np.cos(phi)
    return np.array([
        (-motor.R * rho - motor.Km * omega * np.cos(delta) + vb * cp + va * sp) / motor.L,
        (motor.Km * omega * np.sin(delta) - vb * sp + va * cp) / (motor.L * rho),
        (motor.Km * rho * np.cos(delta) - motor.B * omega - load_torque) / motor.J,
        omega + 0.0 * theta,
    ])


def input_map(phi: ArrayLike, X: ArrayLike, Y: ArrayLike) -> Array:
    r"""Phase voltages from the polar-frame voltages (the corrected matrix of eqs. (9) and (13)).

    .. math:: v_a = X\sin\phi + Y\cos\phi,\qquad v_b = X\cos\phi - Y\sin\phi
    """
    sp, cp = np.sin(phi), np.cos(phi)
    x, y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
    return np.array([x * sp + y * cp, x * cp - y * sp])


def flat_voltages(motor: MotorParams, rho: ArrayLike, drho: ArrayLike, theta: ArrayLike, dtheta: ArrayLike,
                  ddtheta: ArrayLike, dddtheta: ArrayLike, phi: ArrayLike, torque_demand: ArrayLike) -> Array:
    r"""Voltages that give :math:`\dot\rho` = ``drho`` and :math:`\theta^{(3)}` = ``dddtheta``.

    They act from the current (rho, phi, theta, theta', theta''), given the torque demand ``A`` the model
    believes in. This is the shared core of the feedforward (eq. 9) and of the controller (eq. 13), where ``drho``
    and ``dddtheta`` are replaced by :math:`\Gamma_1, \Gamma_2` of eq. (14).
    """
    rho, A = np.asarray(rho, dtype=float), np.asarray(torque_demand, dtype=float)
    d_rho, d_theta, dd_theta, ddd_theta = (np.asarray(a, dtype=float) for a in (drho, dtheta, ddtheta, dddtheta))
    m = motor
    S = np.sqrt(m.Km**2 * rho**2 - A**2)
    dphi = -((m.J * ddd_theta + m.B * dd_theta) * rho - A * d_rho) / (rho * S) - m.Nr * d_theta
    delta = m.Nr * np.asarray(theta) + phi
    X = m.L * d_rho + m.R * rho + m.Km * d_theta * np.cos(delta)
    Y = m.L * rho * dphi - m.Km * d_theta * np.sin(delta)
    return input_map(phi, X, Y)


def check_flag_domain(flag: FlatFlag, motor: MotorParams, load_torque: float = 0.0) -> Array:
    """Return ``cos(delta) = A / (Km rho)``; raise a ValueError where the flag leaves the domain of the maps.

    The domain is rho > 0 and ``|J theta'' + B theta' + tau| < Km rho``.
    """
    rho = np.asarray(flag.rho, dtype=float)
    A = motor.J * np.asarray(flag.ddtheta) + motor.B * np.asarray(flag.dtheta) + load_torque
    if not (np.all(np.isfinite(rho)) and np.all(np.isfinite(A))):
        raise ValueError("the flat flag contains NaN or infinite values")
    if np.any(rho <= 0):
        i = int(np.argmin(rho))
        raise ValueError(f"rho={float(rho.flat[i])!r} A at sample {i}: the flat maps need rho > 0 "
                         "(phi is undefined at 0)")
    c = A / (motor.Km * rho)
    if np.any(np.abs(c) >= 1):
        i = int(np.argmax(np.abs(c)))
        raise ValueError(f"torque demand |J theta'' + B theta' + tau| = {abs(A.flat[i]):.6g} N m at sample {i} "
                         f"is not below Km rho = {motor.Km * rho.flat[i]:.6g} N m: the flat maps are singular there")
    return c


def flat_to_state(flag: FlatFlag, motor: MotorParams, load_torque: float = 0.0) -> tuple[Array, Array]:
    r"""Eqs. (9)-(10), corrected: the state ``x = (ia, ib, omega, theta)`` and inputs ``v = (va, vb)``.

    They are taken along a flat-output trajectory, for a known constant load torque :math:`\tau`.

    .. math::
        \phi = \arccos\frac{J\ddot\theta + B\dot\theta + \tau}{K_m\rho} - N_r\theta,\quad
        i_a = \rho\sin\phi,\ i_b = \rho\cos\phi,\ \omega = \dot\theta
    """
    c = check_flag_domain(flag, motor, load_torque)
    phi = np.arccos(c) - motor.Nr * np.asarray(flag.theta)
    ia, ib = cartesian(flag.rho, phi)
    x = np.array([ia, ib, np.asarray(flag.dtheta, dtype=float) + 0.0 * ia,
                  np.asarray(flag.theta, dtype=float) + 0.0 * ia])
    A = c * motor.Km * np.asarray(flag.rho)
    v = flat_voltages(motor, flag.rho, flag.drho, flag.theta, flag.dtheta, flag.ddtheta, flag.dddtheta, phi, A)
    return x, v


def state_to_flat(x: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: float = 0.0) -> FlatFlag:
    r"""The flat flag from state and input (the inverse of :func:`flat_to_state`), through eq. (8).

    .. math::
        J\ddot\theta = K_m\rho\cos\delta - B\omega - \tau,\quad
        J\theta^{(3)} = K_m\dot\rho\cos\delta - K_m\rho\sin\delta\,(N_r\omega + \dot\phi) - B\ddot\theta
    """
    ia, ib, omega, theta = np.asarray(x, dtype=float)
    rho, phi = polar(ia, ib)
    drho, dphi, ddtheta, _ = polar_rhs(np.array([rho, phi, omega, theta]), v, motor, load_torque)
    delta = motor.Nr * theta + phi
    dddtheta = (motor.Km * drho * np.cos(delta) - motor.Km * rho * np.sin(delta) * (motor.Nr * omega + dphi)
                - motor.B * ddtheta) / motor.J
    return FlatFlag(rho, drho, theta, omega, ddtheta, dddtheta)
