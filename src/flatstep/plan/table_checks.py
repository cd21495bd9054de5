r"""Exact checks of a segment table: rho > 0 on every whole segment, and a flat flag that cannot overflow.

**rho > 0.** A row :math:`p(\tau) = \sum_j c_j \tau^{d - j}` on :math:`\tau \in [0, 1]` has the Bernstein form
:math:`p = \sum_k b_k \binom{d}{k}\tau^k(1 - \tau)^{d - k}` with

.. math:: b_k = \sum_{i \le k} \frac{\binom{k}{i}}{\binom{d}{i}}\,a_i \qquad (a_i \text{ the coefficient of } \tau^i),

and :math:`\min_k b_k \le p(\tau) \le \max_k b_k` on the segment, with :math:`b_0 = p(0)`, :math:`b_d = p(1)`.
:func:`lowest_rho` certifies :math:`p > 0` on a segment when every :math:`b_k > 0`; where some is not, it halves the
segment (de Casteljau, exact in exact arithmetic) and looks again, vectorized over all the pieces left, until
every piece is certified, or an end value of a piece is :math:`\le 0` (rho falls to it there), or the pieces are
:math:`2^{-40}` of their segment and still not certified (rho comes within rounding of 0 there). Not samples:
a rho that dips below 0 between any sample points is found.

**The flag's bound.** On a segment of duration :math:`h`, :math:`|d^k\theta/dt^k| \le h^{-k}\sum_j |c_j|
(d - j)!/(d - j - k)!` for :math:`\tau \in [0, 1]`; :func:`flag_bound` is the largest such bound over a
table (theta's derivatives 0..4 and rho's 0..1 are bounded so), which
:class:`~flatstep.plan.piecewise.PiecewisePlan` holds to :data:`flatstep.validate.limits.MAX_FLAG_BOUND`.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
#: Halvings of a segment before a rho not yet certified > 0 is refused as within rounding of 0.
MAX_DEPTH = 40


def _to_bernstein(ncoef: int) -> Array:
    """The matrix (ncoef, ncoef) that takes a row of power coefficients (highest first) to Bernstein's on [0, 1]."""
    d = ncoef - 1
    m = np.zeros((ncoef, ncoef))
    for k in range(ncoef):
        for i in range(k + 1):
            m[d - i, k] = math.comb(k, i) / math.comb(d, i)  # row d - i holds tau^i (highest power first)
    return m


def _halves(b: Array) -> tuple[Array, Array]:
    """The Bernstein coefficients of each row on [0, 1/2] and on [1/2, 1] (de Casteljau at 1/2)."""
    left, right = [b[:, 0]], [b[:, -1]]
    work = b
    for _ in range(b.shape[1] - 1):  # a loop over the degree, vectorized over the pieces
        work = 0.5 * (work[:, :-1] + work[:, 1:])
        left.append(work[:, 0])
        right.append(work[:, -1])
    return np.column_stack(left), np.column_stack(right[::-1])


def lowest_rho(rows: Array) -> Optional[tuple[float, int, float]]:
    """None when every row (n, d + 1) is > 0 on all of [0, 1]; else ``(value, segment, tau)`` where it is not.

    ``value`` is rho at ``tau`` of ``segment`` (<= 0), or, for a rho that comes within rounding of 0 without an
    end value <= 0, the piece's lowest Bernstein coefficient (module docstring).
    """
    b = np.einsum("nj,jk->nk", rows, _to_bernstein(rows.shape[1]))
    seg = np.arange(rows.shape[0])
    lo, width = np.zeros(rows.shape[0]), 1.0
    for _ in range(MAX_DEPTH + 1):
        ends = np.minimum(b[:, 0], b[:, -1])
        if not (ends > 0).all():  # an end value <= 0 (or NaN): rho reaches it there
            i = int(np.argmin(np.where(np.isnan(ends), -np.inf, ends)))
            return float(ends[i]), int(seg[i]), float(lo[i] + (0.0 if b[i, 0] <= b[i, -1] else width))
        open_ = ~(b.min(axis=1) > 0)
        if not open_.any():
            return None
        b, seg, lo = b[open_], seg[open_], lo[open_]
        left, right = _halves(b)
        width *= 0.5
        b, seg, lo = np.vstack([left, right]), np.concatenate([seg, seg]), np.concatenate([lo, lo + width])
    i = int(np.argmin(b.min(axis=1)))
    return float(b[i].min()), int(seg[i]), float(lo[i] + 0.5 * width)


def flag_bound(breaks: Array, rows: Array, max_order: int) -> tuple[float, int]:
    """The largest bound on the derivatives 0..max_order of a table's rows (n, d + 1), and its segment.

    Infinite where the bound overflows (module docstring).
    """
    d = rows.shape[1] - 1
    fall = np.array([[math.perm(d - j, k) for j in range(d + 1)] for k in range(max_order + 1)], dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        ih = 1.0 / np.diff(breaks)
        sums = np.einsum("nj,kj->nk", np.abs(rows), fall)  # sum_j |c_j| (d - j)! / (d - j - k)!, per order k
        worst = np.max(sums * ih[:, None] ** np.arange(max_order + 1), axis=1)
    worst = np.where(np.isnan(worst), np.inf, worst)
    i = int(np.argmax(worst))
    return float(worst[i]), i
