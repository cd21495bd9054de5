r"""The d-q flat outputs :math:`(\theta, i_d)` of the a-b model: Park transform, forward and reverse maps.

The Park transform by the electrical angle :math:`N_r\theta` (:math:`c = \cos N_r\theta`,
:math:`s = \sin N_r\theta`) turns the phase currents and voltages of eq. (1) into

.. math::
    i_d = i_a c + i_b s,\qquad i_q = i_b c - i_a s,\qquad
    v_d = v_a c + v_b s,\qquad v_q = v_b c - v_a s,

and eq. (1) into the d-q model (the torque is :math:`K_m i_q`, as in
:func:`flatstep.model.motor.torque`):

.. math::
    L\dot i_d = v_d - R i_d + L N_r\omega i_q,\qquad
    L\dot i_q = v_q - R i_q - K_m\omega - L N_r\omega i_d,\qquad
    J\dot\omega = K_m i_q - B\omega - \tau,\qquad \dot\theta = \omega.

The pair :math:`(\theta, i_d)` is flat for any :math:`K_m \ne 0`, with no singularity (unlike
:math:`(\rho, \theta)`, which needs :math:`|J\ddot\theta + B\dot\theta + \tau| < K_m\rho`): for a constant
load :math:`\tau`,

.. math::
    i_q = \frac{J\ddot\theta + B\dot\theta + \tau}{K_m},\qquad
    \dot i_q = \frac{J\theta^{(3)} + B\ddot\theta}{K_m},

and the voltages follow from the d-q model solved for :math:`v_d, v_q`. Only the nominal model of eq. (1)
is mapped (no plant effects).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams

Array = NDArray[np.float64]


class DQFlag(NamedTuple):
    """The d-q flat outputs and the derivatives the maps need, each an array over time."""

    theta: Array
    dtheta: Array
    ddtheta: Array
    dddtheta: Array
    i_d: Array
    di_d: Array


def park(a: ArrayLike, b: ArrayLike, theta: ArrayLike, Nr: int) -> tuple[Array, Array]:
    r"""The d-q components of the a-b pair ``(a, b)`` at rotor angle ``theta``: :math:`(a c + b s,\ b c - a s)`."""
    c, s = np.cos(Nr * np.asarray(theta, dtype=float)), np.sin(Nr * np.asarray(theta, dtype=float))
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a * c + b * s, b * c - a * s


def inverse_park(d: ArrayLike, q: ArrayLike, theta: ArrayLike, Nr: int) -> tuple[Array, Array]:
    r"""The a-b components of the d-q pair ``(d, q)``: :math:`(d c - q s,\ d s + q c)` (inverse of :func:`park`)."""
    c, s = np.cos(Nr * np.asarray(theta, dtype=float)), np.sin(Nr * np.asarray(theta, dtype=float))
    d, q = np.asarray(d, dtype=float), np.asarray(q, dtype=float)
    return d * c - q * s, d * s + q * c


def dq_state_to_flag(x: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: float = 0.0) -> DQFlag:
    r"""The d-q flat flag of the state ``x = (ia, ib, omega, theta)`` and the input ``v = (va, vb)``.

    Vectorized over trailing axes.

    .. math::
        J\ddot\theta = K_m i_q - B\omega - \tau,\quad
        L\dot i_d = v_d - R i_d + L N_r\omega i_q,\quad
        J\theta^{(3)} = K_m\dot i_q - B\ddot\theta
    """
    m = motor
    ia, ib, omega, theta = np.asarray(x, dtype=float)
    va, vb = np.asarray(v, dtype=float)
    i_d, i_q = park(ia, ib, theta, m.Nr)
    v_d, v_q = park(va, vb, theta, m.Nr)
    ddtheta = (m.Km * i_q - m.B * omega - load_torque) / m.J
    di_d = (v_d - m.R * i_d + m.L * m.Nr * omega * i_q) / m.L
    di_q = (v_q - m.R * i_q - m.Km * omega - m.L * m.Nr * omega * i_d) / m.L
    dddtheta = (m.Km * di_q - m.B * ddtheta) / m.J
    return DQFlag(theta, omega, ddtheta, dddtheta, i_d, di_d)


def dq_flag_to_state(flag: DQFlag, motor: MotorParams, load_torque: float = 0.0) -> tuple[Array, Array]:
    r"""The state ``x = (ia, ib, omega, theta)`` and input ``v = (va, vb)`` along a d-q flat flag.

    Vectorized over time; the inverse of :func:`dq_state_to_flag`. Raises a ValueError for a non-finite flag.

    .. math::
        v_d = L\dot i_d + R i_d - L N_r\dot\theta i_q,\qquad
        v_q = L\dot i_q + R i_q + K_m\dot\theta + L N_r\dot\theta i_d
    """
    m = motor
    theta, dtheta, ddtheta, dddtheta, i_d, di_d = (np.asarray(f, dtype=float) for f in flag)
    if not all(np.all(np.isfinite(f)) for f in (theta, dtheta, ddtheta, dddtheta, i_d, di_d)):
        raise ValueError("the d-q flat flag (theta, theta', theta'', theta''', i_d, i_d') contains NaN or "
                         "infinite values")
    i_q = (m.J * ddtheta + m.B * dtheta + load_torque) / m.Km
    di_q = (m.J * dddtheta + m.B * ddtheta) / m.Km
    v_d = m.L * di_d + m.R * i_d - m.L * m.Nr * dtheta * i_q
    v_q = m.L * di_q + m.R * i_q + m.Km * dtheta + m.L * m.Nr * dtheta * i_d
    ia, ib = inverse_park(i_d, i_q, theta, m.Nr)
    va, vb = inverse_park(v_d, v_q, theta, m.Nr)
    return np.array([ia, ib, dtheta + 0.0 * ia, theta + 0.0 * ia]), np.array([va, vb])
