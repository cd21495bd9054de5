r"""The planned d current :math:`i_d^*(t)`, the second flat output of the d-q parameterization.

.. math::
    i_d^*(t) = i_{d1} + \psi(t, t_0, t_f)\,(i_{d2} - i_{d1})
               - k_w\max(|\dot\theta^*(t)| - \omega_w, 0)

with the paper's :math:`\psi` (eq. 17) and the planned speed :math:`\dot\theta^*`. :math:`i_d^* = 0` (the default)
puts every ampere into torque, as field oriented control does. The last term weakens the field above the speed
:math:`\omega_w`: in :math:`v_q = L\dot i_q + Ri_q + LN_r\omega i_d + K_m\omega` a negative :math:`i_d` takes
:math:`LN_r\omega|i_d|` off the voltage the move needs at speed, for :math:`R i_d^2` more copper loss.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_nonnegative, check_quantity
from .rest_to_rest import psi


@dataclass(frozen=True)
class DCurrentPlan:
    r"""A rest-to-rest change of the d current from ``i_d1`` to ``i_d2`` [A] over ``[t0, tf]`` [s], weakened at speed.

    ``weakening`` is :math:`k_w` [A s/rad] >= 0 and ``weakening_speed`` :math:`\omega_w` [rad/s] >= 0 (module
    docstring).
    """

    i_d1: float = 0.0
    i_d2: float = 0.0
    t0: float = 0.0
    tf: float = 1.0
    weakening: float = 0.0
    weakening_speed: float = 0.0

    def __post_init__(self) -> None:
        for name in ("i_d1", "i_d2"):
            object.__setattr__(self, name, check_quantity("d_current", getattr(self, name), as_name=name))
        for name in ("t0", "tf"):
            object.__setattr__(self, name, check_quantity("time", getattr(self, name), as_name=name))
        for name, unit in (("weakening", " A s/rad"), ("weakening_speed", " rad/s")):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name), unit=unit))
        if not self.tf > self.t0:
            raise InputError("tf", self.tf, f"tf={self.tf!r} s must be greater than t0={self.t0!r} s (the d "
                             "current changes from t0 to tf)")

    def flag(self, t: ArrayLike, dtheta: ArrayLike = 0.0,
             ddtheta: ArrayLike = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""``(i_d*, i_d*')`` [A, A/s] at times ``t`` for the planned speed and acceleration there."""
        t = np.asarray(t, dtype=float)
        span = self.i_d2 - self.i_d1
        if span == 0:
            i_d, di_d = np.full(t.shape, self.i_d1), np.zeros(t.shape)
        else:
            i_d, di_d = self.i_d1 + psi(t, self.t0, self.tf) * span, psi(t, self.t0, self.tf, 1) * span
        if not self.weakening:
            return i_d, di_d
        w, a = np.asarray(dtheta, dtype=float), np.asarray(ddtheta, dtype=float)
        above = np.abs(w) > self.weakening_speed
        return (i_d - self.weakening * np.where(above, np.abs(w) - self.weakening_speed, 0.0),
                di_d - self.weakening * np.where(above, np.sign(w) * a, 0.0))

    def as_dict(self) -> dict[str, float]:
        """The fields by name, as the C ``struct dq_smc_current`` takes them."""
        return asdict(self)


#: The d current held at 0: every ampere makes torque.
ZERO_D_CURRENT = DCurrentPlan()
