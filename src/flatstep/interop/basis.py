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
from ..validate import InputError, check_integer, check_quantity, check_sequence

#: Most flat outputs a basis serves (a two-phase motor has two).
MAX_OUTPUTS = 8


class PsiFamily(BasisFamily):
    """Polynomials of degree ``2 q - 2`` and the paper's psi on ``[t0, tf]``, one set per flat output.

    Parameters
    ----------
    flaglen : sequence of int
        The flag length ``q`` of each flat output (e.g. ``(2, 4)`` for ``(rho, theta)``); 1 <= q <= 5, at most
        :data:`MAX_OUTPUTS` outputs.
    t0, tf : float
        The start and end of the move [s], ``0 <= t0 < tf`` (the range of ``time``).
    """

    def __init__(self, flaglen: Sequence[int], t0: float, tf: float) -> None:
        check_sequence("flaglen", flaglen, low=1, high=MAX_OUTPUTS, what="flag lengths (one per flat output)")
        lengths = [check_integer("flaglen", q, low=1, high=MAX_ORDER, why="psi has analytic derivatives up to that "
                                 f"order: flaglen={list(flaglen)!r}") for q in flaglen]
        self.t0 = check_quantity("time", t0, as_name="t0")
        self.tf = check_quantity("time", tf, as_name="tf")
        if not self.tf > self.t0:
            raise InputError("tf", tf, f"tf={tf!r} s must be greater than t0={t0!r} s")
        super().__init__(max(2 * q for q in lengths))
        self.nvars = len(lengths)
        self.coef_length = [2 * q for q in lengths]
        self.coef_offset = [sum(self.coef_length[:i]) for i in range(len(lengths))]

    def eval_deriv(self, i: int, k: int, t: ArrayLike, var: int | None = None) -> NDArray[np.float64]:
        """The ``k``-th time derivative of basis function ``i`` of flat output ``var`` at ``t``."""
        if var is not None:
            var = check_integer("var", var, low=0, high=self.nvars - 1, why="the flat output's index")
        n = self.coef_length[0 if var is None else var]
        i = check_integer("i", i, low=0, high=n - 1, why=f"basis function i does not exist; flat output {var} has {n}")
        k = check_integer("k", k, low=0, high=MAX_ORDER, why="the derivative's order")
        t = np.asarray(t, dtype=float)
        if i == n - 1:
            return psi(t, self.t0, self.tf, k)
        if k > i:
            return 0.0 * t
        T = self.tf - self.t0
        return math.factorial(i) / math.factorial(i - k) * ((t - self.t0) / T) ** (i - k) / T**k
