r"""The filtered regressors of identification's equations (:mod:`flatstep.studies.identify`), and which rows hold.

:func:`electrical_blocks` and :func:`mechanical_terms` build the two equations' terms, pass them through the same
zero-phase low-pass filter and keep four rows per cutoff period. Rows are left out where the data do not hold
what the equations say: the back-emf column is zero where the encoder does not resolve a motion
(:func:`moving_samples`), and rows near a current at the ADC's full scale (:func:`clipped_samples`) are dropped.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

from .record import Recording

#: The mechanical fit keeps the rows where the filtered speed exceeds this many encoder counts per cutoff period.
MOVING_COUNTS = 2.0
#: A run of at least this many consecutive readings at the column's largest magnitude is an ADC at full scale.
CLIPPED_RUN = 4
Blocks = list[tuple[np.ndarray, np.ndarray]]


def sosfiltfilt(sos: np.ndarray, x: np.ndarray, axis: int = -1) -> np.ndarray:
    """:func:`scipy.signal.sosfiltfilt`, imported when first used (scipy.signal takes a second to import)."""
    from scipy.signal import sosfiltfilt as filtfilt

    return filtfilt(sos, x, axis=axis)


def filtered(rec: Recording, fc: float) -> tuple[np.ndarray, slice]:
    """The filter's ``sos`` at ``fc`` and the rows kept: the start-up cut off, four rows per cutoff period."""
    fs = 1.0 / rec.period
    if not fc < 0.25 * fs:
        raise ValueError(f"{rec.source}: bandwidth {fc!r} Hz must be below a quarter of the sampling rate "
                         f"({fs:.6g} Hz)")
    cut, step = math.ceil(3.0 * fs / fc), max(1, int(fs / (4.0 * fc)))
    need = 2 * cut + 40 * step
    if rec.t.size < need:
        raise ValueError(f"{rec.source}: {rec.duration:.4g} s ({rec.t.size} rows) is too short for a {fc:g} Hz "
                         f"bandwidth: at least {need * rec.period:.4g} s ({need} rows) at this sampling rate")
    from scipy.signal import butter

    return butter(4, fc, fs=fs, output="sos"), slice(cut, rec.t.size - 1 - cut, step)


def encoder_step(theta: np.ndarray) -> float:
    """The encoder's count [rad]: the smallest step of the recorded angle (0 for an angle that never steps)."""
    steps = np.abs(np.diff(theta))
    return float(steps[steps > 1e-12].min()) if np.any(steps > 1e-12) else 0.0


def _widen(mask: np.ndarray, width: int) -> np.ndarray:
    """``mask`` true within ``width`` samples of any true sample."""
    count = np.concatenate([[0], np.cumsum(mask, dtype=np.int64)])
    index = np.arange(mask.size)
    return count[np.minimum(index + width + 1, mask.size)] - count[np.maximum(index - width, 0)] > 0


def moving_samples(rec: Recording, fc: float) -> np.ndarray:
    """Per period, whether the encoder resolves the rotor's motion (its speed, filtered at ``fc``).

    The filtered angle's speed must exceed :data:`MOVING_COUNTS` counts per cutoff period; the periods are
    widened by one filter settling time (3 periods of ``fc``).

    At rest (or hunting across a count edge) the recorded angle's steps are the encoder's quantization, not a
    motion: a back-emf or a speed made of them is an error in a regressor, which biases least squares.
    """
    sos, _ = filtered(rec, fc)
    omega = np.gradient(sosfiltfilt(sos, rec.theta), rec.period)
    moving = np.abs(omega) >= MOVING_COUNTS * encoder_step(rec.theta) * fc
    return _widen(moving, math.ceil(3.0 / (fc * rec.period)))[:-1]


def clipped_samples(rec: Recording) -> np.ndarray:
    """Per sample, whether a current reading may sit at its ADC's full scale.

    A current beyond the ADC's range reads as the range's end, sample after sample: the candidates are runs of
    at least :data:`CLIPPED_RUN` equal readings at the column's largest magnitude. A slow current's peak makes
    such runs too: :func:`~flatstep.studies.identify_detect.confirm_clipping` keeps them only where the
    equations do not hold.
    """
    out = np.zeros(rec.t.size, dtype=bool)
    for i in (rec.ia, rec.ib):
        top = np.abs(i) >= np.max(np.abs(i))
        run = np.convolve(top.astype(float), np.ones(CLIPPED_RUN), mode="valid") >= CLIPPED_RUN
        if run.any():
            out |= _widen(np.concatenate([run, np.zeros(CLIPPED_RUN - 1, dtype=bool)]), CLIPPED_RUN) & top
    return out


def kept_rows(bad: np.ndarray, rows: slice, cut: int) -> np.ndarray:
    """The filtered rows (``rows``) farther than ``cut`` samples (the filter's settling) from any ``bad`` sample."""
    return ~_widen(bad, cut)[rows]


def electrical_blocks(rec: Recording, Nr: int, fc: float, offsets: bool, moving: np.ndarray, keep: np.ndarray, *,
                      shift: int = 0, dead_time: bool = False) -> tuple[Blocks, list[str], list[np.ndarray],
                                                                         np.ndarray, slice]:
    """Both phases' filtered electrical equations (:mod:`flatstep.studies.identify`) as least-squares blocks.

    Parameters
    ----------
    rec : Recording
        The recording.
    Nr : int
        Rotor teeth.
    fc : float
        The filter's cutoff [Hz].
    offsets : bool
        Add a constant voltage per phase.
    moving : ndarray of bool
        Per period, whether the back-emf term is resolved (:func:`moving_samples`); zero elsewhere.
    keep : ndarray of bool
        Per filtered row, whether it is fitted (:func:`kept_rows`).
    shift : int
        Periods by which the voltage columns are read later (positive) than the currents and the angle.
    dead_time : bool
        Add a voltage against each phase current's sign (a PWM dead time's average effect).

    Returns
    -------
    blocks, names, raw, sos, rows
        The fit's blocks and parameter names, each phase's raw terms (R, L, Km columns and the voltage), the
        filter and the rows.
    """
    sos, rows = filtered(rec, fc)
    Ts, blocks, raw = rec.period, [], []
    at = slice(rows.start + shift, rows.stop + shift, rows.step)
    for k, (i, c, v) in enumerate(((rec.ia, np.cos(Nr * rec.theta), rec.va), (rec.ib, np.sin(Nr * rec.theta),
                                                                             rec.vb))):
        terms = np.array([0.5 * (i[1:] + i[:-1]), np.diff(i) / Ts, moving * np.diff(c) / (Ts * Nr), v[:-1]])
        f = sosfiltfilt(sos, terms, axis=-1)
        X = [f[:3, rows].T]
        if offsets:
            X.append(np.ones((X[0].shape[0], 2)) * (np.arange(2) == k))
        if dead_time:
            X.append(sosfiltfilt(sos, np.sign(0.5 * (i[1:] + i[:-1])))[rows][:, None])
        blocks.append((np.hstack(X)[keep], f[3, at][keep]))
        raw.append(terms)
    names = ["R", "L", "Km"] + (["va_offset", "vb_offset"] if offsets else []) + (["dead_time_voltage"]
                                                                                  if dead_time else [])
    return blocks, names, raw, sos, rows


def mechanical_terms(rec: Recording, Nr: int, fc: float, extra: Sequence[str], harmonic: int,
                     coulomb_speed: float) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, slice]:
    """The filtered mechanical equation's regressors, ``iq``, the filtered speed (at the rows) and the rows.

    The regressors are J, B, load_torque and those of ``extra`` (``detent_a``, ``detent_b``, ``coulomb_torque``).
    """
    sos, rows = filtered(rec, fc)
    th = rec.theta
    omega = np.gradient(sosfiltfilt(sos, th), rec.period)
    terms = {"J": np.gradient(omega, rec.period), "B": omega, "load_torque": np.ones_like(th)}
    raw = {"iq": rec.ib * np.cos(Nr * th) - rec.ia * np.sin(Nr * th)}
    every = {"detent_a": lambda: np.sin(harmonic * Nr * th), "detent_b": lambda: np.cos(harmonic * Nr * th),
             "coulomb_torque": lambda: np.tanh(omega / coulomb_speed)}
    raw.update({k: every[k]() for k in extra})
    f = sosfiltfilt(sos, np.array(list(raw.values())), axis=-1)
    terms.update({k: f[j] for j, k in enumerate(raw) if k != "iq"})
    return {k: v[rows] for k, v in terms.items()}, f[0][rows], omega[rows], rows


def moving_rows(omega: np.ndarray, theta: np.ndarray, fc: float) -> np.ndarray:
    """The mechanical rows whose filtered speed ``omega`` exceeds :data:`MOVING_COUNTS` counts per cutoff period."""
    return np.abs(omega) >= MOVING_COUNTS * encoder_step(theta) * fc


def optional(mask: Optional[np.ndarray], size: int) -> np.ndarray:
    """``mask``, or all true of ``size``."""
    return np.ones(size, dtype=bool) if mask is None else mask
