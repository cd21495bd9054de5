r"""Linear least squares for identification: conditioning check, estimates and a serial-correlation-robust covariance.

The equations of :mod:`flatstep.studies.identify` are low-pass filtered before they are fitted, so their
residuals are correlated over a few rows. The covariance is Newey and West's (Econometrica 55(3), 1987),
the "sandwich" with Bartlett weights over ``lags`` rows:

.. math::
    \hat\Sigma = (X^TX)^{-1}\Big(\sum_{|l|\le L}\big(1 - \tfrac{|l|}{L+1}\big)\sum_t x_t e_t e_{t-l} x_{t-l}^T\Big)
                 (X^TX)^{-1}

summed over independent blocks of rows (the two phases of the electrical equations).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
#: The largest condition number of the column-scaled regressors that :func:`fit` accepts.
COND_MAX = 1e4


@dataclass(frozen=True)
class Fit:
    """A least-squares fit: estimates, their covariance, the residuals' rms and the regressors' conditioning.

    ``vif`` holds each estimate's variance inflation: the diagonal of :math:`(X_s^TX_s)^{-1}` for the regressors
    ``X_s`` scaled to unit columns (1 for a column orthogonal to the others); ``gram`` is :math:`X^TX`.
    """

    names: tuple[str, ...]
    values: Array
    covariance: Array
    residual_rms: float
    condition: float
    vif: Array
    gram: Array


def _cond_or_refuse(X: Array, names: Sequence[str], source: str, hint: str) -> float:
    """The condition number of ``X`` with unit columns; a ValueError when a column is zero or it exceeds COND_MAX."""
    norms = np.linalg.norm(X, axis=0)
    zero = [n for n, v in zip(names, norms, strict=True) if not v > 1e-12 * max(float(norms.max()), 1e-300)]
    if zero:
        raise ValueError(f"{source}: the recording does not excite {zero} at all (their regressors are zero): "
                         f"not exciting enough; {hint}")
    _, s, vt = np.linalg.svd(X / norms, full_matrices=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else np.inf
    if not cond <= COND_MAX:
        weak = [n for n, w in zip(names, vt[-1], strict=True) if abs(w) > 0.3]
        raise ValueError(f"{source}: ill-conditioned regressors (condition number {cond:.3g} > {COND_MAX:.0e}): "
                         f"{weak} cannot be told apart in this recording; not exciting enough; {hint}")
    return cond


def fit(blocks: Sequence[tuple[Array, Array]], names: Sequence[str], *, lags: int, source: str,
        hint: str, noise_gram: Optional[Array] = None) -> Fit:
    """Fit ``y = X p`` over the stacked ``(X, y)`` blocks; refuse ill-conditioned regressors.

    Parameters
    ----------
    blocks : sequence of (ndarray, ndarray)
        Each block's regressors ``X`` (rows, len(names)) and observations ``y`` (rows,); residuals of different
        blocks are taken as independent.
    names : sequence of str
        The parameters, for messages.
    lags : int
        Rows over which the residuals are correlated (Bartlett window of the covariance), >= 0.
    source : str
        The recording's name, for messages.
    hint : str
        What to do about a recording that is not exciting enough, for messages.
    noise_gram : ndarray, optional
        The part of :math:`X^TX` that noise in the regressors adds, :math:`E[N^TN]`, removed from it (bias-compensated
        least squares: the noise in a regressor biases its estimate towards zero).

    Returns
    -------
    Fit
        The estimates and their covariance (module docstring).
    """
    X = np.concatenate([b[0] for b in blocks])
    y = np.concatenate([b[1] for b in blocks])
    cond = _cond_or_refuse(X, names, source, hint)
    XtX = X.T @ X if noise_gram is None else X.T @ X - noise_gram
    XtX_inv = np.linalg.inv(XtX)
    p = XtX_inv @ (X.T @ y)
    meat = np.zeros((len(names), len(names)))
    for Xb, yb in blocks:
        g = Xb * (yb - Xb @ p)[:, None]  # the score of each row
        meat += g.T @ g
        for lag in range(1, min(lags, len(yb) - 1) + 1):
            c = g[lag:].T @ g[:-lag]
            meat += (1.0 - lag / (lags + 1.0)) * (c + c.T)
    rms = float(np.sqrt(np.mean((y - X @ p) ** 2)))
    norms = np.linalg.norm(X, axis=0)
    vif = np.diag(np.linalg.inv((X / norms).T @ (X / norms))).copy()
    return Fit(tuple(names), p, XtX_inv @ meat @ XtX_inv, rms, cond, vif, X.T @ X)
