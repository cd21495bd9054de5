r"""The paper's interpolating polynomial as a python-control basis: :class:`PsiFamily`.

For a flat output whose flag has :math:`q` entries (the output and :math:`q - 1` derivatives), the basis is

.. math:: \{1, \tau, \dots, \tau^{2q-2}, \psi(t)\},\qquad \tau = \frac{t - t_0}{t_f - t_0},

:math:`2q` functions, as many as the :math:`2q` boundary conditions of a point-to-point move, and
:math:`\psi` is :func:`flatstep.plan.rest_to_rest.psi` (eq. 17). The boundary conditions then fix the
coefficients uniquely (a polynomial of degree :math:`2q - 2` plus :math:`c\psi` with all the conditions
zero is zero), and a rest-to-rest move is :math:`z_1 + \psi(t)(z_2 - z_1)`: python-control's
``point_to_point`` with this basis returns flatstep's :class:`~flatstep.plan.rest_to_rest.RestToRest`.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from control.flatsys import BasisFamily
from numpy.typing import ArrayLike, NDArray

from ..plan.rest_to_rest import MAX_ORDER, psi
from ..validate import check_finite, check_integer


class PsiFamily(BasisFamily):
    """Polynomials of degree ``2 q - 2`` and the paper's psi on ``[t0, tf]``, one set per flat output.

    Parameters
    ----------
    flaglen : sequence of int
        The flag length ``q`` of each flat output (e.g. ``(2, 4)`` for ``(rho, theta)``); 1 <= q <= 5.
    t0, tf : float
        The start and end of the move [s], ``tf > t0``.
    """

    def __init__(self, flaglen: Sequence[int], t0: float, tf: float) -> None:
        lengths = [check_integer("flaglen", q) for q in flaglen]
        if not lengths or any(q > MAX_ORDER for q in lengths):
            raise ValueError(f"flaglen={list(flaglen)!r} must name at least one flat output, each flag 1..{MAX_ORDER} "
                             "long (psi has analytic derivatives up to that order)")
        self.t0, self.tf = check_finite("t0", t0), check_finite("tf", tf)
        if not self.tf > self.t0:
            raise ValueError(f"tf={tf!r} s must be greater than t0={t0!r} s")
        super().__init__(max(2 * q for q in lengths))
        self.nvars = len(lengths)
        self.coef_length = [2 * q for q in lengths]
        self.coef_offset = [sum(self.coef_length[:i]) for i in range(len(lengths))]

    def eval_deriv(self, i: int, k: int, t: ArrayLike, var: int | None = None) -> NDArray[np.float64]:
        """The ``k``-th time derivative of basis function ``i`` of flat output ``var`` at ``t``."""
        n = self.coef_length[0 if var is None else var]
        if not 0 <= i < n:
            raise ValueError(f"basis function i={i!r} does not exist; flat output {var} has {n} (0..{n - 1})")
        t = np.asarray(t, dtype=float)
        if i == n - 1:
            return psi(t, self.t0, self.tf, k)
        if k > i:
            return 0.0 * t
        T = self.tf - self.t0
        return math.factorial(i) / math.factorial(i - k) * ((t - self.t0) / T) ** (i - k) / T**k
