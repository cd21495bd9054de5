r"""The encoder's and the ADC's steps, propagated to each estimate of the electrical fit.

A reading is the true value plus an error bounded by half a step (:math:`q/2` for the angle, :math:`\Delta/2`
for a current), the same error while the reading stays on one count or code, and an independent one on the next
(the steps' sawtooth). Each estimate is a linear functional of the filtered regressors, so its error from these
errors is :math:`\delta p_j = \sum_t a_{jt} e_t`, with the sensitivities :math:`a_{jt}` obtained by passing the
rows' least-squares weights :math:`(X^TX)^{-1}X^T` back through the filter and the differences (their
adjoints). With one uniform error per count or code,

.. math:: \operatorname{Var}\delta p_j = \frac{q^2}{12}\sum_{\text{counts } c}\Big(\sum_{t\in c} a_{jt}\Big)^2,

which is added to the fit's covariance. At rest the encoder's count edge is out of the fit
(:func:`~flatstep.studies.identify_terms.moving_samples`); in motion, and with a dithered ADC, these terms are
small beside the noise, and this shows it rather than assumes it.
"""
from __future__ import annotations

import numpy as np

from .identify_terms import Blocks, sosfiltfilt


def _per_step(a: np.ndarray, reading: np.ndarray, step: float) -> np.ndarray:
    """The variance of ``a @ e`` per row of ``a``, ``e`` uniform within one step, one value per run of ``reading``."""
    if not step > 0:
        return np.zeros(a.shape[0])
    run = np.concatenate([[0], np.cumsum(np.diff(reading) != 0)])
    sums = np.array([np.bincount(run, weights=row) for row in a])
    return step**2 / 12.0 * np.einsum("ij,ij->i", sums, sums)


def _smallest_step(x: np.ndarray) -> float:
    """The smallest non-zero step between readings (0 for a constant column)."""
    steps = np.abs(np.diff(x))
    return float(steps[steps > 1e-12].min()) if np.any(steps > 1e-12) else 0.0


def electrical_quantization(theta: np.ndarray, currents: tuple[np.ndarray, np.ndarray], Nr: int, period: float,
                            sos: np.ndarray, rows: slice, keep: np.ndarray, moving: np.ndarray, blocks: Blocks,
                            values: np.ndarray, gram: np.ndarray) -> np.ndarray:
    """The variances the encoder's and the ADC's steps add to each electrical estimate (module docstring).

    Parameters
    ----------
    theta : ndarray
        The recorded angle [rad].
    currents : (ndarray, ndarray)
        The recorded phase currents [A].
    Nr : int
        Rotor teeth.
    period : float
        The sampling period [s].
    sos, rows : ndarray, slice
        The filter and the filtered rows.
    keep : ndarray of bool
        The rows fitted.
    moving : ndarray of bool
        The periods whose back-emf term is kept.
    blocks : list of (ndarray, ndarray)
        The fit's blocks, one per phase (R, L, Km columns first).
    values : ndarray
        The estimates (R, L, Km first).
    gram : ndarray
        The :math:`X^TX` the estimates were solved with.

    Returns
    -------
    ndarray
        One variance per estimate.
    """
    n, size = len(values), theta.size
    weights = np.linalg.inv(gram)
    at = np.arange(size - 1)[rows][keep]
    pad = np.zeros((n, 1))
    encoder, adc = np.zeros((n, size)), [np.zeros((n, size)), np.zeros((n, size))]
    R, L, Km = values[:3]
    for k, (X, _) in enumerate(blocks):
        u = np.zeros((n, size - 1))
        u[:, at] = weights @ X.T
        u = sosfiltfilt(sos, u, axis=-1)  # the zero-phase filter is its own adjoint away from the ends
        back = (np.hstack([pad, u]) - np.hstack([u, pad])) / period  # adjoint of the forward difference
        mean = 0.5 * (np.hstack([pad, u]) + np.hstack([u, pad]))  # adjoint of the trapezoid's mean
        shape = -np.sin(Nr * theta) if k == 0 else np.cos(Nr * theta)  # d(cos, sin)(Nr theta) / (Nr dtheta)
        encoder -= Km * shape * (np.hstack([pad, u * moving]) - np.hstack([u * moving, pad])) / period
        adc[k] -= R * mean + L * back
    return (_per_step(encoder, theta, _smallest_step(theta))
            + sum(_per_step(a, i, _smallest_step(i)) for a, i in zip(adc, currents, strict=True)))
