r"""Loss-aware :math:`\rho^*(t)` for the paper's law: the current norm planned from the torque the move needs.

The paper holds :math:`\rho^*` at its end values, so the copper loss :math:`R\rho^2` is paid at rest and at
every speed. The flat outputs leave :math:`\rho^*` free as long as the torque demand stays below
:math:`K_m\rho`; planning it from the demand, with a margin :math:`\delta_m` from the singularity and a minimum
holding value :math:`\rho_h`,

.. math::
    A^* = J\ddot\theta^* + B\dot\theta^* + E(t, \theta^*, \dot\theta^*),\qquad
    \rho^* = \sqrt{\rho_h^2 + \Big(\frac{A^*}{K_m\cos\delta_m}\Big)^2},\qquad
    \dot\rho^* = \frac{A^*\dot A^*}{(K_m\cos\delta_m)^2\rho^*},

keeps :math:`|\cos\delta^*| = |A^*|/(K_m\rho^*) < \cos\delta_m` on the whole plan (the torque angle at least
:math:`\delta_m` from the singularity) and is smooth (:math:`E` the known torques,
:class:`~flatstep.model.torque_model.TorqueModel`).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat import FlatFlag
from ..model.motor import MotorParams
from ..model.torque_model import TorqueModel
from ..validate import InputError, check_finite, check_quantity
from .protocol import Plan


@dataclass(frozen=True)
class LossAwareRho:
    r"""The holding current :math:`\rho_h` [A], > 0, and the margin :math:`\delta_m` [rad], in [0, pi/2)."""

    rho_hold: float
    margin: float = math.pi / 4

    def __post_init__(self) -> None:
        margin = check_finite("margin", self.margin)
        if not 0.0 <= margin < math.pi / 2:
            raise InputError("margin", margin, f"margin={margin!r} rad must be in [0, pi/2): the torque angle's "
                             "distance from the singularity cos(delta) = 1")
        object.__setattr__(self, "margin", margin)
        object.__setattr__(self, "rho_hold", check_quantity("current", self.rho_hold, as_name="rho_hold"))

    def reference(self, flag: FlatFlag, t: ArrayLike, motor: MotorParams,
                  torques: TorqueModel) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""``(rho*, rho*')`` [A, A/s] along the planned angle of ``flag`` at times ``t`` (module docstring)."""
        m = motor
        A = m.J * flag.ddtheta + m.B * flag.dtheta + torques.torque(t, flag.theta, flag.dtheta, m.Nr)
        dA = (m.J * flag.dddtheta + m.B * flag.ddtheta
              + torques.torque_rate(t, flag.theta, flag.dtheta, flag.ddtheta, m.Nr))
        c = m.Km * math.cos(self.margin)
        rho = np.sqrt(self.rho_hold**2 + (A / c) ** 2)
        return rho, A * dA / (c * c) / rho

    def as_dict(self) -> dict[str, float]:
        """The fields by name (``margin``, ``rho_hold``)."""
        return asdict(self)

    @classmethod
    def for_plan(cls, plan: Plan, margin: float = math.pi / 4) -> "LossAwareRho":
        """Half the plan's smaller end current held (the default of :func:`flatstep.control.make_controller`)."""
        return cls(rho_hold=0.5 * min(plan.rho1, plan.rho2), margin=margin)
