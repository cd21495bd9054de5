r"""Segment families of a piecewise plan: rows of theta's coefficients in the local time :math:`\tau \in [0, 1]`.

Each builder returns the coefficient rows (highest power first, as :class:`~flatstep.plan.piecewise.PiecewisePlan`
takes them) of one or more segments, and, where the family fixes them, their durations.

* :func:`psi_rows`: the paper's rest-to-rest psi (eq. 17), degree 10; its first four derivatives vanish at both
  ends, so psi segments and dwells join with theta continuous up to theta''''.
* :func:`hermite_rows`: the degree-7 polynomial that meets given (theta, theta', theta'', theta''') at both ends:
  moves through via points at a speed, continuous up to theta'''.
* :func:`scurve_rows`: the jerk-limited S-curve (at most seven cubics, jerk in {-j, 0, +j}), the time-optimal
  rest-to-rest move under speed, acceleration and jerk caps; theta'' is continuous, theta''' jumps.
* :func:`dwell_row`: theta held.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .rest_to_rest import _PSI_HORNER

Array = NDArray[np.float64]
#: The largest |d^k psi / d tau^k| on [0, 1], k = 1, 2, 3: a psi move of step D and duration T peaks at
#: ``PSI_PEAKS[k - 1] |D| / T^k``.
PSI_PEAKS = tuple(float(np.max(np.abs(np.polyval(np.polyder(_PSI_HORNER[0], k), np.linspace(0, 1, 20001)))))
                  for k in (1, 2, 3))
_HERMITE_ORDER = 3  # derivatives met at each end: degree 2 * 3 + 1 = 7


def psi_rows(theta_a: Array, theta_b: Array) -> Array:
    """The psi segments from ``theta_a`` to ``theta_b`` (k,), rest to rest: rows (k, 11)."""
    step = np.asarray(theta_b, dtype=float) - np.asarray(theta_a, dtype=float)
    rows = step[:, None] * _PSI_HORNER[0][None, :]
    rows[:, -1] += theta_a
    return rows


def psi_duration(step: Array, v_max: float, a_max: float, j_max: float) -> Array:
    """The shortest durations of psi moves of ``step`` whose speed, acceleration and jerk stay within the caps."""
    d = np.abs(np.asarray(step, dtype=float))
    return np.maximum.reduce([PSI_PEAKS[0] * d / v_max, np.sqrt(PSI_PEAKS[1] * d / a_max),
                              np.cbrt(PSI_PEAKS[2] * d / j_max)])


def dwell_row(theta: float) -> Array:
    """A segment holding ``theta``: one row (11,)."""
    row = np.zeros(11)
    row[-1] = theta
    return row


def hermite_rows(start: Array, end: Array, h: Array) -> Array:
    r"""Degree-7 segments meeting the time derivatives ``start`` and ``end`` (k, 4) over durations ``h`` (k,).

    Column m of ``start`` is :math:`\theta^{(m)}` at the segment's start; in :math:`\tau` it is
    :math:`\theta^{(m)} h^m`. One 8 x 8 solve serves every segment. Rows (k, 11), the three leading zeros padded.
    """
    powers = np.arange(7, -1, -1)
    m = np.zeros((8, 8))
    for k in range(_HERMITE_ORDER + 1):
        m[k] = np.where(powers == k, math.factorial(k), 0.0)  # d^k tau^p at tau = 0
        m[4 + k] = [math.perm(int(p), k) for p in powers]  # at tau = 1
    scale = np.asarray(h, dtype=float)[:, None] ** np.arange(4)[None, :]
    rhs = np.hstack([np.asarray(start, dtype=float) * scale, np.asarray(end, dtype=float) * scale])
    coef = np.linalg.solve(m, rhs.T).T
    return np.hstack([np.zeros((coef.shape[0], 3)), coef])


def scurve_phases(distance: float, v_max: float, a_max: float, j_max: float) -> tuple[Array, Array]:
    """Durations and jerks of the seven phases of the fastest rest-to-rest S-curve over ``distance`` > 0.

    Phases: jerk +j, 0, -j (reach the peak speed), 0 (cruise), -j, 0, +j (stop). When the peak speed or the
    acceleration cap is not reached, the middle phases have zero duration.
    """
    a, j, v = a_max, j_max, v_max
    tj = a / j if v * j >= a * a else math.sqrt(v / j)
    ta = tj + v / a if v * j >= a * a else 2 * tj  # duration of the speed-up
    tv = distance / v - ta
    if tv < 0:  # the speed cap is not reached: the largest peak speed vp with vp (tj + vp / a) = distance
        tj = a / j
        vp = a * (-tj + math.sqrt(tj * tj + 4 * distance / a)) / 2
        if vp * j >= a * a:
            ta = tj + vp / a
        else:  # nor the acceleration cap: distance = 2 j tj^3
            tj = (distance / (2 * j)) ** (1 / 3)
            ta = 2 * tj
        tv = 0.0
    durations = np.array([tj, ta - 2 * tj, tj, tv, tj, ta - 2 * tj, tj])
    return np.maximum(durations, 0.0), np.array([j, 0.0, -j, 0.0, -j, 0.0, j])


def scurve_rows(theta_a: float, theta_b: float, v_max: float, a_max: float,
                j_max: float) -> tuple[Array, Array]:
    """The S-curve from ``theta_a`` to ``theta_b`` at rest: (rows (k, 11), durations (k,)), zero phases dropped."""
    step = theta_b - theta_a
    durations, jerks = scurve_phases(abs(step), v_max, a_max, j_max)
    keep = durations > 1e-12 * durations.sum()
    durations, jerks = durations[keep], np.sign(step) * jerks[keep]
    rows, p, v, acc = np.zeros((durations.size, 11)), theta_a, 0.0, 0.0
    for i, (h, jk) in enumerate(zip(durations, jerks, strict=True)):  # a loop over at most seven phases
        rows[i, -4:] = [jk * h**3 / 6, acc * h**2 / 2, v * h, p]
        p, v, acc = p + v * h + acc * h**2 / 2 + jk * h**3 / 6, v + acc * h + jk * h**2 / 2, acc + jk * h
    return rows, durations
