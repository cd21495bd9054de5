r"""The planned d current :math:`i_d^*(t)`, the second flat output of the d-q parameterization.

.. math:: i_d^*(t) = i_{d1} + \psi(t, t_0, t_f)\,(i_{d2} - i_{d1})

with the paper's :math:`\psi` (eq. 17). :math:`i_d^* = 0` (the default) puts every ampere into torque, as field
oriented control does; a negative :math:`i_d^*` at speed weakens the field.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import check_finite
from .rest_to_rest import psi


@dataclass(frozen=True)
class DCurrentPlan:
    """A rest-to-rest change of the d current from ``i_d1`` to ``i_d2`` [A] over ``[t0, tf]`` [s]."""

    i_d1: float = 0.0
    i_d2: float = 0.0
    t0: float = 0.0
    tf: float = 1.0

    def __post_init__(self) -> None:
        for name in ("i_d1", "i_d2", "t0", "tf"):
            object.__setattr__(self, name, check_finite(name, getattr(self, name)))
        if not self.tf > self.t0:
            raise ValueError(f"tf={self.tf!r} s must be greater than t0={self.t0!r} s (the d current changes "
                             "from t0 to tf)")

    def flag(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""``(i_d*, i_d*')`` at times ``t`` [A, A/s]."""
        t = np.asarray(t, dtype=float)
        span = self.i_d2 - self.i_d1
        if span == 0:
            return np.full(t.shape, self.i_d1), np.zeros(t.shape)
        return self.i_d1 + psi(t, self.t0, self.tf) * span, psi(t, self.t0, self.tf, 1) * span

    def as_dict(self) -> dict[str, float]:
        """The fields by name, as the C ``struct dq_smc_current`` takes them."""
        return asdict(self)


#: The d current held at 0: every ampere makes torque.
ZERO_D_CURRENT = DCurrentPlan()
