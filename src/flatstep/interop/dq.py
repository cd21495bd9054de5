r"""The d-q flat outputs :math:`(\theta, i_d)` for python-control, with a constant load torque.

The maps are those of :mod:`flatstep.model.flat_dq`, and the Park transform is taken by the rotor angle.

The pair :math:`(\theta, i_d)` is flat for any :math:`K_m \ne 0`, with no singularity:
:math:`i_q = (J\ddot\theta + B\dot\theta + \tau)/K_m`, and the voltages follow from the d-q model
(:mod:`flatstep.model.flat_dq` derives both and proves them against eq. (1) in SymPy). Only the nominal model of
eq. (1) with a constant load is mapped here.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model import flat_dq
from ..model.flat_dq import DQFlag
from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..validate import check_count, check_instance, check_quantity

Array = NDArray[np.float64]

__all__ = ["DQFlag", "park", "inverse_park", "dq_state_to_flag", "dq_flag_to_state"]


def _load(load_torque: float) -> TorqueModel:
    """The torque model of a constant load torque [N m]."""
    load_torque = check_quantity("load", load_torque, as_name="load_torque")
    return NO_TORQUES if load_torque == 0.0 else TorqueModel(load=load_torque)


def park(a: ArrayLike, b: ArrayLike, theta: ArrayLike, Nr: int) -> tuple[Array, Array]:
    r"""The d-q components of the a-b pair ``(a, b)`` at rotor angle ``theta``: :math:`(a c + b s,\ b c - a s)`."""
    return flat_dq.park(a, b, check_count("Nr", Nr) * np.asarray(theta, dtype=float))


def inverse_park(d: ArrayLike, q: ArrayLike, theta: ArrayLike, Nr: int) -> tuple[Array, Array]:
    r"""The a-b components of the d-q pair ``(d, q)`` at rotor angle ``theta`` (inverse of :func:`park`)."""
    return flat_dq.inverse_park(d, q, check_count("Nr", Nr) * np.asarray(theta, dtype=float))


def dq_state_to_flag(x: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: float = 0.0) -> DQFlag:
    """The d-q flat flag of the state ``x = (ia, ib, omega, theta)`` and the input ``v = (va, vb)``."""
    check_instance("motor", motor, MotorParams, "a flatstep MotorParams")
    return flat_dq.state_to_dq(x, v, motor, _load(load_torque))


def dq_flag_to_state(flag: DQFlag, motor: MotorParams, load_torque: float = 0.0) -> tuple[Array, Array]:
    """The state ``x`` and input ``v`` along a d-q flat flag (inverse of :func:`dq_state_to_flag`)."""
    check_instance("flag", flag, DQFlag, "a DQFlag", "theta, dtheta, ddtheta, dddtheta, i_d, di_d")
    check_instance("motor", motor, MotorParams, "a flatstep MotorParams")
    return flat_dq.dq_to_state(flag, motor, _load(load_torque))
