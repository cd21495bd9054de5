r"""The phase plane of the time-optimal planner: the speed-dependent acceleration envelope and the bang-bang move.

The first stage of :mod:`flatstep.plan.time_optimal` (csrc/time_optimal.c runs the same).

**Envelope.** At speed :math:`\omega`, with the current :math:`u = i_q` along the torque axis and the planned
:math:`i_d = \sqrt{f(\omega)^2 + k^2u^2}`, :math:`k = \cot\alpha_{max}` across it
(:meth:`~flatstep.plan.limits.MotorLimits.across`), the steady phase voltage (:math:`di/dt = 0`) is
:math:`v_d = R i_d - e u`, :math:`v_q = R u + e i_d + c` with :math:`e = N_r\omega L`, :math:`c = K_m\omega`, and
its square has the cross terms cancel:

.. math::
    h(u) = v_d^2 + v_q^2 - (\gamma V_{bus})^2
         = (R^2 + e^2)\bigl((1 + k^2)u^2 + f^2\bigr) + 2cRu + 2ce\sqrt{f^2 + k^2u^2} + c^2 - (\gamma V_{bus})^2,

convex in :math:`u`. Newton's method from the current cap ``i_max`` allows (where :math:`h > 0`) therefore falls
monotonically onto the largest :math:`\pm u` within the bus, in a few steps (:func:`iq_bounds`). They bound the
acceleration :math:`a_\pm(\omega) = (K_m u_\pm - B\omega)/J` (back EMF helps braking: :math:`|a_-| > a_+`).

**Bang-bang profile.** Accelerate on :math:`a_+`, cruise at the speed cap if reached, brake on :math:`a_-`:
the distances :math:`\int \omega/a\,d\omega` and times :math:`\int d\omega/a` over a speed grid give the peak
speed where acceleration and braking distances add up to the move. With :math:`\gamma = 1` and no inductance
this is the *bang-bang bound* :func:`bang_bang_time`, the lower bound the planned times are compared with.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from .limits import MotorLimits

Array = NDArray[np.float64]
_GRID = 192          # speed-grid points of the phase plane
_PROBE = 64          # speed-grid points of the probe for the top speed
_TOP_ACCEL = 0.01    # the top speed: where a+ falls to this fraction of a+ at rest
_NEWTON_TOL = 1e-12  # Newton stops when its step is below this fraction of i_max


class Envelope(NamedTuple):
    """The speed grid [rad/s] from rest to the top speed and the accelerations a+ > 0, a- < 0 on it [rad/s^2]."""

    omega: Array
    a_plus: Array
    a_minus: Array


def voltage_excess(u: Array, omega: Array, motor: MotorParams, limits: MotorLimits, v2: float) -> tuple[Array, Array]:
    """The squared steady voltage less the bus's, h(u), and dh/du at torque current ``u`` (module docstring).

    ``v2`` is the squared bus voltage it is measured against (0: the squared steady voltage itself).
    """
    m, k = motor, 1.0 / math.tan(limits.torque_angle_max)
    f, c, e = limits.floor(omega), m.Km * omega, m.Nr * omega * m.L
    z = m.R * m.R + e * e
    root = np.sqrt(f * f + k * k * u * u)
    h = z * ((1.0 + k * k) * u * u + f * f) + 2.0 * c * m.R * u + 2.0 * c * e * root + c * c - v2
    dh = 2.0 * z * (1.0 + k * k) * u + 2.0 * c * m.R + 2.0 * c * e * k * k * u / root
    return h, dh


def iq_bounds(omega: Array, motor: MotorParams, limits: MotorLimits, gamma: float = 1.0) -> tuple[Array, Array]:
    """The torque currents (lowest, highest) the bus and i_max allow at speeds ``omega`` >= 0 (module docstring).

    Newton from the cap on each side, vectorized over the speeds, until every step is below ``_NEWTON_TOL i_max``;
    0 on both sides where even no torque exceeds the bus.
    """
    omega = np.asarray(omega, dtype=float)
    cap = limits.iq_cap(omega)
    v2 = (gamma * limits.v_bus) ** 2
    reach = voltage_excess(np.zeros_like(omega), omega, motor, limits, v2)[0] <= 0
    bounds = []
    for sign in (-1.0, 1.0):
        u = sign * cap
        active = reach & (voltage_excess(u, omega, motor, limits, v2)[0] > 0)
        for _ in range(100):  # a loop over Newton steps, vectorized over the speeds; monotone (h is convex)
            if not active.any():
                break
            h, dh = voltage_excess(u[active], omega[active], motor, limits, v2)
            step = h / dh
            u[active] -= step
            active[active] = np.abs(step) > _NEWTON_TOL * limits.i_max
        bounds.append(np.where(reach, u, 0.0))
    return bounds[0], bounds[1]


def envelope(motor: MotorParams, limits: MotorLimits, gamma: float) -> Envelope:
    """The speed grid up to the top speed and the accelerations on it, at ``gamma`` of the bus.

    A probe grid up to the lesser of the speed cap and the back-EMF speed finds where a+ first falls to
    ``_TOP_ACCEL`` of its value at rest, interpolated between its points; the grid ends there. (Speeds above it take
    long to reach for little gain; a top that moves continuously with gamma keeps the search's measure smooth.)
    """
    m = motor
    w_emf = gamma * limits.v_bus / m.Km
    w_max = min(limits.speed_max, w_emf) if limits.speed_max else w_emf
    probe = np.linspace(0.0, w_max, _PROBE)
    acc = (m.Km * iq_bounds(probe, m, limits, gamma)[1] - m.B * probe) / m.J
    if not acc[0] > 0:
        raise ValueError(f"the motor cannot start: at rest the bus {limits.v_bus} V (x {gamma:.3g}) and the limits "
                         f"{limits} leave no torque")
    thr = _TOP_ACCEL * acc[0]
    below = np.flatnonzero(~(acc[1:] > thr)) + 1
    top = w_max
    if below.size:  # interpolated between the probe points: the top speed moves continuously with gamma
        j = below[0]
        top = probe[j - 1] + (probe[j] - probe[j - 1]) * ((acc[j - 1] - thr) / (acc[j - 1] - acc[j]))
    omega = np.linspace(0.0, top, _GRID)
    lo, hi = iq_bounds(omega, m, limits, gamma)
    a_plus = (m.Km * hi - m.B * omega) / m.J
    a_minus = (m.Km * lo - m.B * omega) / m.J
    if limits.accel_max:
        a_plus, a_minus = np.minimum(a_plus, limits.accel_max), np.maximum(a_minus, -limits.accel_max)
    a_plus[-1] = max(a_plus[-1], 1e-12 * a_plus[0])  # the top speed is reached in finite time on the grid
    a_minus[-1] = min(a_minus[-1], 1e-12 * a_minus[0])  # and left: without friction (B = 0) braking there is 0
    return Envelope(omega, a_plus, a_minus)


def _cumtrapz(y: Array, x: Array) -> Array:
    """The running trapezoidal integral of ``y`` over ``x``, from 0."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(x))])


class BangBang(NamedTuple):
    """The bang-bang move on an envelope: speed-up time [s], cruise time [s], braking time [s], peak speed [rad/s]."""

    t1: float
    cruise: float
    t2: float
    w_peak: float
    t_acc: Array
    t_dec: Array


def bang_bang(distance: float, env: Envelope) -> BangBang:
    """The bang-bang move over ``distance`` > 0 on ``env`` (module docstring)."""
    omega, a_plus, a_minus = env
    t_acc = _cumtrapz(1.0 / a_plus, omega)
    t_dec = _cumtrapz(1.0 / -a_minus, omega)
    d_both = _cumtrapz(omega / a_plus + omega / -a_minus, omega)
    if distance >= d_both[-1]:
        w_peak, cruise = float(omega[-1]), (distance - float(d_both[-1])) / float(omega[-1])
    else:
        w_peak, cruise = float(np.interp(distance, d_both, omega)), 0.0
    return BangBang(float(np.interp(w_peak, omega, t_acc)), cruise, float(np.interp(w_peak, omega, t_dec)), w_peak,
                    t_acc, t_dec)


def bang_bang_time(distance: float, motor: MotorParams, limits: MotorLimits) -> float:
    """The lower bound: the bang-bang move on the full bus ignoring inductance and jerk (module docstring)."""
    from .arguments import check_angle, check_limits, check_motor

    d = abs(check_angle(distance, "distance"))
    check_motor(motor)
    check_limits(limits)
    b = bang_bang(d, envelope(motor, limits, 1.0))
    return b.t1 + b.cruise + b.t2
