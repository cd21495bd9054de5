r"""The flat feedforward of any plan, for any controller: the reference state, currents, voltages and torque.

The d-q flat map (:func:`flatstep.model.flat_dq.dq_to_state`, the one the d-q flatness law uses) turns the plan's
angle and its derivatives, a planned d current :math:`i_d^*` and the torques a controller knows beyond eq. (1)
(:math:`E`, a :class:`~flatstep.model.torque_model.TorqueModel`) into the currents and voltages that make the
nominal motor follow the plan exactly:

.. math::
    T^* = J\ddot\theta^* + B\dot\theta^* + E^*,\qquad i_q^* = T^*/K_m,\qquad
    \dot i_q^* = (J\theta^{*(3)} + B\ddot\theta^* + \dot E^*)/K_m,

    v_d^* = R i_d^* + L\dot i_d^* - LN_r\dot\theta^* i_q^*,\qquad
    v_q^* = R i_q^* + L\dot i_q^* + LN_r\dot\theta^* i_d^* + K_m\dot\theta^*

with :math:`E^*, \dot E^*` along the plan. In the phase frame (``frame="ab"``) the currents, their rates and the
voltages are the inverse Park transform by :math:`N_r\theta^*` (:math:`\dot i_{ab}` carries the rotation's
:math:`N_r\dot\theta^*` term). A drive's firmware or a user's own controller takes :attr:`Reference.voltages` as its
feedforward and :attr:`Reference.currents` as its current reference; the cascade's ``voltage_feedforward`` is
:math:`R i_q^* + L\dot i_q^*` of it.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat_dq import dq_voltages, inverse_park
from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.protocol import Plan, check_plan
from ..validate import InputError

Array = NDArray[np.float64]
#: The frames :func:`reference` gives currents and voltages in.
FRAMES = ("ab", "dq")


class Reference(NamedTuple):
    """The reference state and the feedforward along a plan, each an array over the times asked for.

    ``currents``, ``current_rates`` and ``voltages`` are (2, n): ``(a, b)`` or ``(d, q)`` by the frame asked for.
    """

    t: Array
    theta: Array  #: theta* [rad]
    omega: Array  #: theta*' [rad/s]
    acceleration: Array  #: theta*'' [rad/s^2]
    currents: Array  #: the reference currents [A]
    current_rates: Array  #: their time derivatives [A/s]
    voltages: Array  #: the feedforward voltages [V]
    torque: Array  #: the motor torque the move needs, J theta*'' + B theta*' + E* [N m]
    known_torque: Array  #: E* of the torque model along the plan [N m]

    @property
    def state(self) -> Array:
        """The reference state ``(ia, ib, omega, theta)`` (4, n) for a phase-frame reference."""
        return np.array([self.currents[0], self.currents[1], self.omega, self.theta])


def reference(plan: Plan, motor: MotorParams, t: ArrayLike, *, torques: TorqueModel = NO_TORQUES,
              frame: str = "ab", d_current: DCurrentPlan = ZERO_D_CURRENT) -> Reference:
    r"""The reference state and the feedforward currents, voltages and torque of ``plan`` at times ``t``.

    Parameters
    ----------
    plan : Plan
        Any plan (:class:`~flatstep.plan.protocol.Plan`): its angle and three derivatives are read.
    motor : MotorParams
        The nominal model the feedforward inverts.
    t : array_like
        Times [s], any shape (the outputs follow it).
    torques : TorqueModel
        The torques known beyond eq. (1) (detent, Coulomb friction, load), along the plan (default none).
    frame : str
        ``"ab"`` (phase currents and voltages) or ``"dq"`` (rotor frame at :math:`N_r\theta^*`).
    d_current : DCurrentPlan
        The planned d current (default 0: every ampere makes torque).

    Returns
    -------
    Reference
        The module docstring's quantities.

    Raises
    ------
    InputError
        For an unknown frame, a plan, motor, torque model or d current of the wrong type.
    """
    check_plan(plan)
    for name, value, kind in (("motor", motor, MotorParams), ("torques", torques, TorqueModel),
                              ("d_current", d_current, DCurrentPlan)):
        if not isinstance(value, kind):
            raise InputError(name, value, f"{name}={value!r} is not a {kind.__name__}")
    if frame not in FRAMES:
        raise InputError("frame", frame, f"frame={frame!r} is unknown; valid: {list(FRAMES)}")
    m = motor
    t = np.asarray(t, dtype=float)
    ref = plan.flag(t)
    E = np.asarray(torques.torque(t, ref.theta, ref.dtheta, m.Nr), dtype=float) + 0.0 * t
    dE = torques.torque_rate(t, ref.theta, ref.dtheta, ref.ddtheta, m.Nr)
    i_d, di_d = d_current.flag(t, ref.dtheta, ref.ddtheta)
    torque = m.J * ref.ddtheta + m.B * ref.dtheta + E
    i_q = torque / m.Km
    di_q = (m.J * ref.dddtheta + m.B * ref.ddtheta + dE) / m.Km
    v_d, v_q = dq_voltages(m, i_d, i_q, ref.dtheta, ref.ddtheta, di_d, ref.dddtheta, dE)
    if frame == "dq":
        currents, rates, volts = np.array([i_d, i_q]), np.array([di_d, di_q]), np.array([v_d, v_q])
    else:
        p = m.Nr * ref.theta
        w = m.Nr * ref.dtheta
        currents = np.array(inverse_park(i_d, i_q, p))
        turn = np.array(inverse_park(-i_q, i_d, p))  # d/dp of the inverse Park transform of (i_d, i_q)
        rates = np.array(inverse_park(di_d, di_q, p)) + w * turn
        volts = np.array(inverse_park(v_d, v_q, p))
    if not (np.all(np.isfinite(currents)) and np.all(np.isfinite(volts))):
        raise InputError("plan", plan, "the plan's feedforward is not finite (a NaN or infinite flag value)")
    return Reference(t, np.asarray(ref.theta, dtype=float) + 0.0 * t, np.asarray(ref.dtheta, dtype=float) + 0.0 * t,
                     np.asarray(ref.ddtheta, dtype=float) + 0.0 * t, currents, rates, volts, torque, E)
