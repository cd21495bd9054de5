r"""The planned d current :math:`i_d^*(t)`, the second flat output of the d-q parameterization.

.. math::
    i_d^*(t) = i_{d1} + \psi(t, t_0, t_f)\,(i_{d2} - i_{d1})
               - k_w\max(|\dot\theta^*(t)| - \omega_w, 0)

with the paper's :math:`\psi` (eq. 17) and the planned speed :math:`\dot\theta^*`. :math:`i_d^* = 0` (the default)
puts every ampere into torque, as field oriented control does. The last term weakens the field above the speed
:math:`\omega_w`: in :math:`v_q = L\dot i_q + Ri_q + LN_r\omega i_d + K_m\omega` a negative :math:`i_d` takes
:math:`LN_r\omega|i_d|` off the voltage the move needs at speed, for :math:`R i_d^2` more copper loss.

A planner that plans :math:`i_d^*(t)` itself (:func:`flatstep.plan.time_optimal_dq.time_optimal_dq`) gives it as
a table: the cubic Hermite pieces through :math:`(i_d, \dot i_d)` at the knot times (:func:`hermite_cubic`, held
outside them), in place of the psi term.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_nonnegative, check_quantity
from .rest_to_rest import psi

#: Knots of a d-current table, at most (csrc/dq_smc.h ``DQ_SMC_ID_KNOTS``).
MAX_KNOTS = 72


def hermite_cubic(t: ArrayLike, knots: NDArray[np.float64], value: NDArray[np.float64],
                  slope: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The cubic Hermite interpolant through ``(value, slope)`` at ``knots`` and its rate at ``t``, held outside."""
    t = np.asarray(t, dtype=float)
    inside = (t > knots[0]) & (t < knots[-1])
    tc = np.clip(t, knots[0], knots[-1])
    i = np.clip(np.searchsorted(knots, tc, side="right") - 1, 0, knots.size - 2)
    h = knots[i + 1] - knots[i]
    u = (tc - knots[i]) / h
    p0, p1, m0, m1 = value[i], value[i + 1], slope[i] * h, slope[i + 1] * h
    y = ((2 * u - 3) * u * u + 1) * p0 + ((u - 2) * u + 1) * u * m0 + (3 - 2 * u) * u * u * p1 + (u - 1) * u * u * m1
    dy = (6 * (u - 1) * u * (p0 - p1) + ((3 * u - 4) * u + 1) * m0 + (3 * u - 2) * u * m1) / h
    return y, np.where(inside, dy, 0.0)


@dataclass(frozen=True)
class DCurrentPlan:
    r"""A rest-to-rest change of the d current from ``i_d1`` to ``i_d2`` [A] over ``[t0, tf]`` [s], weakened at speed.

    ``weakening`` is :math:`k_w` [A s/rad] >= 0 and ``weakening_speed`` :math:`\omega_w` [rad/s] >= 0 (module
    docstring). ``knot_t`` [s], ``knot_id`` [A], ``knot_did`` [A/s]: a table of 2 to ``MAX_KNOTS`` knots at rising
    times that replaces the psi term (empty: none).
    """

    i_d1: float = 0.0
    i_d2: float = 0.0
    t0: float = 0.0
    tf: float = 1.0
    weakening: float = 0.0
    weakening_speed: float = 0.0
    knot_t: tuple[float, ...] = ()
    knot_id: tuple[float, ...] = ()
    knot_did: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        self._check_table()
        for name in ("i_d1", "i_d2"):
            object.__setattr__(self, name, check_quantity("d_current", getattr(self, name), as_name=name))
        for name in ("t0", "tf"):
            object.__setattr__(self, name, check_quantity("time", getattr(self, name), as_name=name))
        for name, unit in (("weakening", " A s/rad"), ("weakening_speed", " rad/s")):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name), unit=unit))
        if not self.tf > self.t0:
            raise InputError("tf", self.tf, f"tf={self.tf!r} s must be greater than t0={self.t0!r} s (the d "
                             "current changes from t0 to tf)")

    def _check_table(self) -> None:
        """Raise an InputError unless the table is empty or 2..MAX_KNOTS finite knots at rising times."""
        n = len(self.knot_t)
        if n == 0 and not self.knot_id and not self.knot_did:
            return
        arrays = [np.asarray(getattr(self, k), dtype=float) for k in ("knot_t", "knot_id", "knot_did")]
        if not (2 <= n <= MAX_KNOTS and all(a.shape == (n,) for a in arrays)):
            sizes = [len(getattr(self, k)) for k in ("knot_t", "knot_id", "knot_did")]
            raise InputError("knot_t", self.knot_t, f"a d-current table has 2 to {MAX_KNOTS} knots, with as many "
                             f"values and rates (got {sizes})")
        if not (all(np.all(np.isfinite(a)) for a in arrays) and np.all(np.diff(arrays[0]) > 0)):
            raise InputError("knot_t", self.knot_t, "a d-current table's knots must be finite, at rising times")
        for k, a in zip(("knot_t", "knot_id", "knot_did"), arrays, strict=True):
            object.__setattr__(self, k, tuple(float(x) for x in a))

    def flag(self, t: ArrayLike, dtheta: ArrayLike = 0.0,
             ddtheta: ArrayLike = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""``(i_d*, i_d*')`` [A, A/s] at times ``t`` for the planned speed and acceleration there."""
        t = np.asarray(t, dtype=float)
        span = self.i_d2 - self.i_d1
        if self.knot_t:
            i_d, di_d = hermite_cubic(t, np.array(self.knot_t), np.array(self.knot_id), np.array(self.knot_did))
        elif span == 0:
            i_d, di_d = np.full(t.shape, self.i_d1), np.zeros(t.shape)
        else:
            i_d, di_d = self.i_d1 + psi(t, self.t0, self.tf) * span, psi(t, self.t0, self.tf, 1) * span
        if not self.weakening:
            return i_d, di_d
        w, a = np.asarray(dtheta, dtype=float), np.asarray(ddtheta, dtype=float)
        above = np.abs(w) > self.weakening_speed
        return (i_d - self.weakening * np.where(above, np.abs(w) - self.weakening_speed, 0.0),
                di_d - self.weakening * np.where(above, np.sign(w) * a, 0.0))

    def as_dict(self) -> dict[str, Any]:
        """The fields by name, as the C ``struct dq_smc_current`` takes them (and ``n_knots``)."""
        return {**asdict(self), "n_knots": len(self.knot_t)}


#: The d current held at 0: every ampere makes torque.
ZERO_D_CURRENT = DCurrentPlan()
