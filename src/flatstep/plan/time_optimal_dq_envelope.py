r"""The d-q acceleration envelope with field weakening: the best torque at each speed over the d current.

In the rotor's frame, at a steady speed :math:`\omega` and steady currents, the voltages are

.. math::
    v_d = R i_d - N_r\omega L i_q,\qquad v_q = R i_q + N_r\omega L i_d + K_m\omega,

so :math:`v = Z I + jE` with :math:`I = i_d + j i_q`, :math:`Z = R + jX`, :math:`X = N_r\omega L` and
:math:`E = K_m\omega`. The bus :math:`|v| \le V` is then a disc in the current plane, centred at
:math:`c = -jE/Z` (:math:`c_d = -EX/|Z|^2`, :math:`c_q = -ER/|Z|^2`) of radius :math:`V/|Z|`; the current limit
:math:`|I| \le i_{max}` a disc at 0. The largest (smallest) torque current over both discs is the top (bottom) of
one disc inside the other or a point where their circles cross: a closed form per speed, and its :math:`i_d` is
the field weakening that pays (negative once the back EMF eats the bus). Accelerating, the optimum takes the
top; braking, the bottom. ``voltage="phase"`` (each phase within its share, two H-bridges) and ``"vector"`` give
the same disc here: a sinusoidally commutated law reaches each phase's limit once per electrical turn, where the
vector is on a phase axis.

The envelope samples :math:`a_\pm(\omega) = (K_m i_{q\pm} - B\omega)/J` on ``GRID`` speeds from 0 to the top
speed: the least of the speed cap and the speed where no torque is left (found by bisection on ``PROBE``
halvings).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams

Array = NDArray[np.float64]
#: Speed-grid points of the envelope (csrc/time_optimal_dq.h ``TOD_GRID``).
GRID = 192
#: Bisection halvings for the speed where no torque is left (csrc/time_optimal_dq.h ``TOD_PROBE``).
PROBE = 48


class DQEnvelope(NamedTuple):
    """The speeds [rad/s], the accelerations [rad/s^2] of either side and their d currents [A]."""

    omega: Array
    a_plus: Array
    a_minus: Array
    id_plus: Array
    id_minus: Array


def best_currents(omega: float, motor: MotorParams, v: float, i_max: float) -> tuple[float, float, float, float]:
    """``(i_d+, i_q+, i_d-, i_q-)`` [A]: the largest and the smallest torque current at ``omega`` >= 0 (module doc).

    ``i_q+ < i_q-`` (nan) when the discs do not meet: the speed cannot be held.
    """
    m = motor
    x, e = m.Nr * omega * m.L, m.Km * omega
    z2 = m.R * m.R + x * x
    if not z2 > 0.0:  # R^2 + (Nr w L)^2 underflows: no impedance to divide by, no envelope
        return math.nan, math.nan, math.nan, math.nan
    cd, cq, r = -e * x / z2, -e * m.R / z2, v / math.sqrt(z2)
    dist = math.sqrt(cd * cd + cq * cq)
    if dist > i_max + r:
        return math.nan, math.nan, math.nan, math.nan
    if dist <= abs(i_max - r) or not dist > 0.0:  # one disc inside the other (or the same disc)
        if r <= i_max:
            return cd, cq + r, cd, cq - r
        return 0.0, i_max, 0.0, -i_max
    # the circles cross at two points: a along the line of centres, h across it
    a = (i_max * i_max - r * r + dist * dist) / (2.0 * dist)
    h = math.sqrt(max(i_max * i_max - a * a, 0.0))
    ux, uy = cd / dist, cq / dist
    p1 = (a * ux - h * uy, a * uy + h * ux)
    p2 = (a * ux + h * uy, a * uy - h * ux)
    hi = max(p1, p2, key=lambda p: p[1])
    lo = min(p1, p2, key=lambda p: p[1])
    if (cd - 0.0) ** 2 + (cq - i_max) ** 2 <= r * r:  # the current's top inside the bus disc
        hi = (0.0, i_max)
    elif cd * cd + (cq + r) ** 2 <= i_max * i_max:  # the bus disc's top inside the current disc
        hi = (cd, cq + r)
    if cd * cd + (cq + i_max) ** 2 <= r * r:
        lo = (0.0, -i_max)
    elif cd * cd + (cq - r) ** 2 <= i_max * i_max:
        lo = (cd, cq - r)
    return hi[0], hi[1], lo[0], lo[1]


def _accel(omega: float, motor: MotorParams, v: float, i_max: float) -> float:
    """The largest acceleration [rad/s^2] at ``omega`` (-inf where the speed cannot be held)."""
    _, iq, _, _ = best_currents(omega, motor, v, i_max)
    return -math.inf if math.isnan(iq) else (motor.Km * iq - motor.B * omega) / motor.J


def top_speed(motor: MotorParams, v: float, i_max: float, cap: float) -> float:
    """The least of ``cap`` and the speed where the largest acceleration falls to 0 (bisection)."""
    if _accel(cap, motor, v, i_max) > 0:
        return cap
    lo, hi = 0.0, cap
    for _ in range(PROBE):
        mid = 0.5 * (lo + hi)
        if _accel(mid, motor, v, i_max) > 0:
            lo = mid
        else:
            hi = mid
    return lo


def dq_envelope(motor: MotorParams, v: float, i_max: float, cap: float) -> DQEnvelope:
    """The envelope at bus voltage ``v`` [V] (the planned share), current ``i_max`` [A] and speed cap ``cap``.

    Raises
    ------
    ValueError
        When the motor cannot start (no torque at rest).
    """
    m = motor
    if not _accel(0.0, m, v, i_max) > 0:
        raise ValueError(f"the motor cannot start: at rest {v:g} V and {i_max:g} A give no torque")
    top = top_speed(m, v, i_max, cap)
    omega = top * np.arange(GRID) / (GRID - 1)
    cur = np.array([best_currents(float(w), m, v, i_max) for w in omega])
    a_plus = (m.Km * cur[:, 1] - m.B * omega) / m.J
    a_minus = (m.Km * cur[:, 3] - m.B * omega) / m.J
    a_plus[-1] = max(a_plus[-1], 1e-12 * a_plus[0])  # the top speed is reached in finite time on the grid
    a_minus[-1] = min(a_minus[-1], 1e-12 * a_minus[0])
    return DQEnvelope(omega, a_plus, a_minus, cur[:, 0], cur[:, 2])
