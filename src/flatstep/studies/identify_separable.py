r"""What a recording cannot separate: the weakest direction of a fit, the combination it determines, what to record.

A fit's condition number says how ill-posed it is as a whole; the variance inflation of each estimate, the
diagonal of :math:`(X_s^TX_s)^{-1}` for the regressors scaled to unit columns (:class:`~.identify_ls.Fit`), says
which estimates are lost in a near-collinearity, and by how much any error in a regressor (noise, quantization, a
left-out term) is multiplied on them. At a constant current norm with the current on the d axis,
:math:`L\,di/dt` and the back-emf have the same shape, :math:`-N_r i_d\omega\sin N_r\theta` and
:math:`-\omega\sin N_r\theta`: only :math:`K_m + N_r i_d L` is determined, however narrow the intervals of L and
Km look. A fit in which an estimate's variance inflation exceeds :data:`VIF_MAX` is refused, naming the pair that
spans the weakest direction, the combination :math:`p_i + c\,p_j` the recording does determine (``c`` the
regression of column j on column i) and the motion that would separate them (:data:`SEPARATE`).
"""
from __future__ import annotations

import math

import numpy as np

from .identify_ls import Fit

#: The largest variance inflation accepted (the suggested excitation gives about 40; one move at a constant
#: current norm thousands).
VIF_MAX = 300.0
#: What separates each pair of estimates.
SEPARATE = {
    frozenset({"L", "Km"}): "change the current norm while the rotor moves (moves at two or more current norms, or "
                            "a current step during a move), so that L di/dt no longer has the back-emf's shape",
    frozenset({"R", "L"}): "change the current at rest (steps of the current norm)",
    frozenset({"R", "Km"}): "move faster, or hold the rotor at rest for a while at a constant current",
    frozenset({"J", "B"}): "record moves of different durations (accelerations against speeds)",
    frozenset({"B", "load_torque"}): "record moves in both directions (the load keeps its sign, the friction follows "
                                     "the speed's)",
    frozenset({"J", "load_torque"}): "record moves in both directions and at several accelerations",
}
#: Which estimate a combination is written in, first in this order.
FIRST = ("Km", "J", "R", "B", "L", "load_torque")
GENERIC = "record several moves in both directions, of several lengths and speeds, with current changes"


def check_separable(fit: Fit, source: str, hint: str) -> None:
    """Refuse a fit in which an estimate's variance inflation exceeds :data:`VIF_MAX` (module docstring)."""
    worst = int(np.argmax(fit.vif))
    if not fit.vif[worst] > VIF_MAX:
        return
    norms = np.sqrt(np.diag(fit.gram))
    scaled = fit.gram / np.outer(norms, norms)
    _, vectors = np.linalg.eigh(scaled)
    weak = np.abs(vectors[:, 0])  # the direction of the smallest eigenvalue
    i, j = (int(k) for k in np.argsort(weak)[::-1][:2])
    rank = [FIRST.index(n) if n in FIRST else len(FIRST) for n in fit.names]
    if rank[j] < rank[i]:
        i, j = j, i  # the combination is written in the constant a motor is known by (Km + c L)
    a, b = fit.names[i], fit.names[j]
    c = fit.gram[i, j] / fit.gram[i, i]  # column b ~ c column a: y ~ (a + c b) column a
    value = fit.values[i] + c * fit.values[j]
    grad = np.zeros(len(fit.names))
    grad[i], grad[j] = 1.0, c
    std = math.sqrt(max(float(grad @ fit.covariance @ grad), 0.0))
    alone = math.sqrt(max(float(fit.covariance[i, i]), 0.0))
    what = SEPARATE.get(frozenset({a, b}), GENERIC)
    raise ValueError(f"{source}: {a} and {b} cannot be separated in this recording (variance inflation "
                     f"{fit.vif[worst]:.3g} > {VIF_MAX:g}: their regressors have nearly the same shape): only "
                     f"{a} + {c:.4g} {b} = {value:.6g} is determined (standard error "
                     f"{std / abs(value) if value else math.inf:.2%}; {a} alone shows "
                     f"{alone / abs(fit.values[i]) if fit.values[i] else 0:.2%}, but any error in the regressors is "
                     f"multiplied by {math.sqrt(fit.vif[worst]):.3g} on it); to separate them, {what}; {hint}")
