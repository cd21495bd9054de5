r"""The paper's interpolating polynomial psi (eq. 17) and its derivatives, held at 0 before t0 and at 1 after tf.

In normalised time :math:`\tau = (t - t_0)/(t_f - t_0)`,

.. math::
    \psi(\tau) = \tau^5 (252 - 1050\tau + 1800\tau^2 - 1575\tau^3 + 700\tau^4 - 126\tau^5),

a degree-10 polynomial whose first four derivatives vanish at :math:`t_0` and first five at :math:`t_f`. The
rest-to-rest plans (:mod:`flatstep.plan.rest_to_rest`) move along it, and a known load may change along it
(:mod:`flatstep.model.torque_model`): it lives with the model so that both can use it.
"""
from __future__ import annotations

import numpy as np
from numpy.polynomial import Polynomial
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_finite, check_integer

#: Coefficients r1..r6 of eq. (17).
PAPER_R = (252.0, 1050.0, 1800.0, 1575.0, 700.0, 126.0)
#: Highest derivative of psi available analytically (the controller needs theta''').
MAX_ORDER = 5

_PSI = Polynomial([0.0] * 5 + [r * (-1) ** i for i, r in enumerate(PAPER_R)])
_PSI_DERIVS = [_PSI.deriv(k) for k in range(MAX_ORDER + 1)]
_PSI_HORNER = [d.coef[::-1].copy() for d in _PSI_DERIVS]  # highest power first, for np.polyval


def psi(t: ArrayLike, t0: float, tf: float, order: int = 0) -> NDArray[np.float64]:
    r"""The paper's interpolating polynomial :math:`\psi(t, t_0, t_f)` (eq. 17) or its ``order``-th time derivative.

    It is held at 0 before :math:`t_0` and at 1 after :math:`t_f` (derivatives 0 outside).

    .. math:: \frac{d^k\psi}{dt^k} = \frac{\psi^{(k)}(\tau)}{(t_f - t_0)^k}
    """
    order = check_integer("order", order, low=0, high=MAX_ORDER, why="psi's analytic derivatives")
    t0, tf = check_finite("t0", t0), check_finite("tf", tf)
    if not tf > t0:
        raise InputError("tf", tf, f"tf={tf!r} must be greater than t0={t0!r}")
    t = np.asarray(t, dtype=float)
    T = tf - t0
    tau = np.clip((t - t0) / T, 0.0, 1.0)
    value = np.polyval(_PSI_HORNER[order], tau) / T**order
    if order > 0:
        value = np.where((t > t0) & (t < tf), value, 0.0)
    return value
