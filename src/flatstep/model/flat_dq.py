r"""Flat outputs (theta, i_d) <-> state and inputs: the d-q parameterization, with no singularity while Km != 0.

The Park transform by the electrical angle :math:`N_r\theta` (the d axis along the rotor's magnet),

.. math::
    i_d = i_a\cos N_r\theta + i_b\sin N_r\theta,\qquad i_q = -i_a\sin N_r\theta + i_b\cos N_r\theta,

turns eq. (1), with the torques of a :class:`~flatstep.model.torque_model.TorqueModel` :math:`E`, into

.. math::
    L\dot i_d = v_d - R i_d + LN_r\omega i_q,\qquad
    L\dot i_q = v_q - R i_q - LN_r\omega i_d - K_m\omega,\qquad
    J\dot\omega = K_m i_q - B\omega - E.

So :math:`(\theta, i_d)` is flat: with the torque demand :math:`A = J\ddot\theta + B\dot\theta + E`,

.. math::
    \omega = \dot\theta,\quad i_q = \frac{A}{K_m},\quad
    \dot i_q = \frac{J\theta^{(3)} + B\ddot\theta + \dot E}{K_m},

    v_d = L\dot i_d + R i_d - LN_r\dot\theta\,i_q,\qquad
    v_q = L\dot i_q + R i_q + LN_r\dot\theta\,i_d + K_m\dot\theta,

and :math:`(v_a, v_b)` is the inverse Park transform of :math:`(v_d, v_q)`. Unlike the polar pair
:math:`(\rho, \theta)` of eqs. (7)-(10) there is no square root and no division by a current: every torque
demand has its state. tests/test_flat_dq.py proves in SymPy that the map satisfies eq. (1), extended by
:math:`E`, identically.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .motor import MotorParams
from .torque_model import NO_TORQUES, TorqueModel

Array = NDArray[np.float64]


class DQFlag(NamedTuple):
    """The flat outputs (theta, i_d) and the derivatives the maps need, each an array over time."""

    theta: Array
    dtheta: Array
    ddtheta: Array
    dddtheta: Array
    i_d: Array
    di_d: Array


def park(a: ArrayLike, b: ArrayLike, electrical_angle: ArrayLike) -> tuple[Array, Array]:
    r"""Phase quantities to the rotor frame at the electrical angle :math:`p = N_r\theta`.

    .. math:: d = a\cos p + b\sin p,\qquad q = -a\sin p + b\cos p
    """
    c, s = np.cos(electrical_angle), np.sin(electrical_angle)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a * c + b * s, -a * s + b * c


def inverse_park(d: ArrayLike, q: ArrayLike, electrical_angle: ArrayLike) -> tuple[Array, Array]:
    r"""Rotor frame to phases, the inverse of :func:`park`.

    .. math:: a = d\cos p - q\sin p,\qquad b = d\sin p + q\cos p
    """
    c, s = np.cos(electrical_angle), np.sin(electrical_angle)
    d, q = np.asarray(d, dtype=float), np.asarray(q, dtype=float)
    return d * c - q * s, d * s + q * c


def dq_voltages(motor: MotorParams, i_d: ArrayLike, i_q: ArrayLike, omega: ArrayLike, ddtheta: ArrayLike,
                di_d: ArrayLike, dddtheta: ArrayLike, torque_rate: ArrayLike = 0.0) -> tuple[Array, Array]:
    r"""The rotor-frame voltages that give :math:`\dot i_d` = ``di_d`` and :math:`\theta^{(3)}` = ``dddtheta``.

    They act from the current (i_d, i_q, omega, theta''), given the rate :math:`\dot E` of the modelled torques:
    the shared core of the feedforward (:func:`dq_to_state`) and of the d-q controller
    (:class:`~flatstep.control.dq_smc.DQFlatnessSMC`), where ``di_d`` and ``dddtheta`` are its
    :math:`\Gamma_1, \Gamma_2`.

    .. math::
        v_d = L\dot i_d + R i_d - LN_r\omega i_q,\qquad
        v_q = \frac{L}{K_m}(J\theta^{(3)} + B\ddot\theta + \dot E) + R i_q + LN_r\omega i_d + K_m\omega
    """
    m = motor
    i_d, i_q, w, acc, did, jerk, dE = (np.asarray(a, dtype=float)
                                      for a in (i_d, i_q, omega, ddtheta, di_d, dddtheta, torque_rate))
    v_d = m.L * did + m.R * i_d - m.L * m.Nr * w * i_q
    v_q = m.L * ((m.J * jerk + m.B * acc + dE) / m.Km) + m.R * i_q + m.L * m.Nr * w * i_d + m.Km * w
    return v_d, v_q


def dq_to_state(flag: DQFlag, motor: MotorParams, torques: TorqueModel = NO_TORQUES,
                t: ArrayLike = 0.0) -> tuple[Array, Array]:
    r"""The state ``x = (ia, ib, omega, theta)`` and inputs ``v = (va, vb)`` along a (theta, i_d) trajectory.

    ``torques`` are the torques the model knows beyond eq. (1), at times ``t`` (module docstring).

    .. math::
        i_q = \frac{J\ddot\theta + B\dot\theta + E}{K_m},\qquad
        \begin{bmatrix} i_a \\ i_b \end{bmatrix} = P(N_r\theta)^{-1}\begin{bmatrix} i_d \\ i_q \end{bmatrix},\qquad
        \begin{bmatrix} v_a \\ v_b \end{bmatrix} = P(N_r\theta)^{-1}\begin{bmatrix} v_d \\ v_q \end{bmatrix}
    """
    m = motor
    theta, dtheta, ddtheta, dddtheta, i_d, di_d = (np.asarray(a, dtype=float) for a in flag)
    if not all(np.all(np.isfinite(a)) for a in (theta, dtheta, ddtheta, dddtheta, i_d, di_d)):
        raise ValueError("the d-q flat flag contains NaN or infinite values")
    E = torques.torque(t, theta, dtheta, m.Nr)
    dE = torques.torque_rate(t, theta, dtheta, ddtheta, m.Nr)
    i_q = (m.J * ddtheta + m.B * dtheta + E) / m.Km
    v_d, v_q = dq_voltages(m, i_d, i_q, dtheta, ddtheta, di_d, dddtheta, dE)
    p = m.Nr * theta
    ia, ib = inverse_park(i_d, i_q, p)
    x = np.array([ia, ib, dtheta + 0.0 * ia, theta + 0.0 * ia])
    return x, np.array(inverse_park(v_d, v_q, p))


def state_to_dq(x: ArrayLike, v: ArrayLike, motor: MotorParams, torques: Optional[TorqueModel] = None,
                t: ArrayLike = 0.0) -> DQFlag:
    r"""The (theta, i_d) flag from state and input, the inverse of :func:`dq_to_state`, through the d-q model.

    .. math::
        J\ddot\theta = K_m i_q - B\omega - E,\qquad
        L\dot i_d = v_d - R i_d + LN_r\omega i_q,\qquad
        J\theta^{(3)} = \frac{K_m}{L}(v_q - R i_q - LN_r\omega i_d - K_m\omega) - B\ddot\theta - \dot E
    """
    m, torques = motor, NO_TORQUES if torques is None else torques
    ia, ib, omega, theta = np.asarray(x, dtype=float)
    va, vb = np.asarray(v, dtype=float)
    p = m.Nr * theta
    i_d, i_q = park(ia, ib, p)
    v_d, v_q = park(va, vb, p)
    ddtheta = (m.Km * i_q - m.B * omega - torques.torque(t, theta, omega, m.Nr)) / m.J
    di_d = (v_d - m.R * i_d + m.L * m.Nr * omega * i_q) / m.L
    di_q = (v_q - m.R * i_q - m.L * m.Nr * omega * i_d - m.Km * omega) / m.L
    dddtheta = (m.Km * di_q - m.B * ddtheta - torques.torque_rate(t, theta, omega, ddtheta, m.Nr)) / m.J
    return DQFlag(theta, omega, ddtheta, dddtheta, i_d, di_d)
