r"""Motor identification: R, L, Km, J, B (and detent, Coulomb friction) from a recording, by linear least squares.

**Electrical equations.** Eq. (1) per phase, with the back-emf written as an exact time derivative
(:math:`K_m\omega\sin N_r\theta = -\frac{K_m}{N_r}\frac{d}{dt}\cos N_r\theta`) so that no speed is needed, and
integrated over each sampling period under the held voltage :math:`v_k` (trapezoid on the current):

.. math::
    R\,\frac{i_{a,k} + i_{a,k+1}}{2} + L\,\frac{i_{a,k+1} - i_{a,k}}{T_s}
    + \frac{K_m}{N_r}\,\frac{\cos N_r\theta_{k+1} - \cos N_r\theta_k}{T_s} + o_a = v_{a,k}

and the same for phase b with :math:`\sin N_r\theta`; :math:`o_a, o_b` absorb constant voltage (or current
sensor) offsets. Linear in :math:`(R, L, K_m, o_a, o_b)`.

**Mechanical equation.** With :math:`i_q = i_b\cos N_r\theta - i_a\sin N_r\theta` from the measured
currents,

.. math::
    K_m i_q = J\ddot\theta + B\dot\theta + \tau + T_d\sin(hN_r\theta + \varphi_d) + T_c\tanh(\dot\theta/\omega_s),

linear in :math:`(J, B, \tau, T_d\cos\varphi_d, T_d\sin\varphi_d, T_c)/K_m` (the last three on request, with
:math:`h` = ``detent_harmonic``, the plant's :class:`~flatstep.model.plant.PlantEffects` form).

**Filtering without bias.** Every term of an equation is passed through the same zero-phase low-pass filter
(4th-order Butterworth, forward and backward, :func:`scipy.signal.sosfiltfilt`): the equations are linear in the
parameters, so they hold for the filtered terms as they do for the raw ones, while the ADC noise, the encoder's
quantization and the differences' noise are removed above the cutoff. :math:`\dot\theta, \ddot\theta` are the
derivatives of the filtered angle. At rest, an encoder that toggles between two counts makes a motion that is
not there, of which the filtered derivatives make a back emf, speeds and accelerations: where the encoder does
not resolve a motion of :data:`MOVING_COUNTS` counts per cutoff period, the electrical fit takes the back emf as
zero and the mechanical fit leaves the rows out (:mod:`.identify_terms`; a choice on a regressor, which does not
bias least squares), and rows near a current at the ADC's full scale are left out of both. The filter's start-up
is cut off at both ends, the rows are thinned to four per cutoff period, and the covariance allows for the
residuals' correlation (:mod:`.identify_ls`).

**Intervals.** To the fits' covariance are added the noise compensation's correction (as uncertain as it is
large), the encoder's and the ADC's steps (:mod:`.identify_quantization`) and the method's floor
(:data:`FLOOR`, :data:`LOAD_FLOOR`). The mechanical estimates carry the uncertainty of :math:`K_m` too (delta
method); J/Km, B/Km and load/Km are reported without it.

**Current noise.** Noise in a regressor biases its estimate towards zero (errors in variables): the ADC noise in
the current differences lowers L, and Km, correlated with L through the q-axis, rises. The electrical fit removes
the noise's expected share :math:`E[N^TN]` from :math:`X^TX` (bias-compensated least squares), the noise variance
estimated from the high-pass part of the raw equations' residual in the periods without an encoder step (median
absolute deviation), in :data:`NOISE_ITERATIONS` rounds. In closed loop the controller's feedback also correlates
the noise with the true currents, which this does not model: docs/identification.md shows what it gains and where
it over-corrects.

**What the data cannot support** is refused, and what is atypical of a stepping motor flagged
(:mod:`.identify_checks`): values beyond any motor's in the recording's units (before the fit), the current
noise's share of the R and L regressors, estimates outside their ranges, a fitted R far from the raw
``sum(v i) / sum(i^2)``. A pair of estimates the recording cannot separate is refused with the combination it
determines (:mod:`.identify_separable`); a shifted voltage log is refused, a dead time, a detent torque or a
Coulomb friction left out of the model flagged (:mod:`.identify_detect`).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from statistics import NormalDist
from typing import Optional, Union

import numpy as np

from ..validate import InputError, check_integer, check_positive, check_quantity
from .identify_checks import atypical, check_estimates, check_noise_share, check_resistance, check_units
from .identify_detect import check_alignment, confirm_clipping, dead_time_flag, effect_flags
from .identify_ls import Fit, fit
from .identify_quantization import electrical_quantization
from .identify_result import Identification
from .identify_separable import check_separable
from .identify_terms import (
    MOVING_COUNTS,
    clipped_samples,
    electrical_blocks,
    filtered,
    kept_rows,
    mechanical_terms,
    moving_rows,
    moving_samples,
    optional,
    sosfiltfilt,
)
from .record import Recording, read_recording

#: A recording is refused when one of these is known to no better than +-this fraction (at the confidence level).
CORE = ("R", "L", "Km", "J", "B")
MAX_REL_HALF_WIDTH = 0.5
#: The fewest (thinned) rows per estimated parameter a fit accepts.
ROWS_PER_PARAMETER = 10
#: The method's systematic floor: a relative standard error every estimate carries beyond the fit's own (what
#: the method leaves with exact sensors, docs/identification.md), J, B and the load's in units of Km.
FLOOR = {"R": 0.002, "L": 0.005, "Km": 0.005, "J": 0.01, "B": 0.05, "load_torque": 0.01}
#: The load's floor in absolute terms: this fraction of the torque of the recording's rms current norm.
LOAD_FLOOR = 0.0005
#: Rounds of the electrical fit's noise-bias compensation (module docstring).
NOISE_ITERATIONS = 2
HINT = ("record a run that moves the rotor back and forth and changes the current norm, such as the move sequence "
        "of 'flatstep identify --excite SCENARIO --record DATA.csv' (docs/identification.md)")


def _unit_noise_gram(sos: np.ndarray, Ts: float, cut: int) -> np.ndarray:
    """Covariance of the filtered (R, L) columns' noise per row for a unit-variance white current noise."""
    impulse = np.zeros(8 * cut + 1)
    impulse[4 * cut] = 1.0
    g = sosfiltfilt(sos, np.array([0.5 * (impulse[1:] + impulse[:-1]), np.diff(impulse) / Ts]), axis=-1)
    return g @ g.T


def _electrical(rec: Recording, Nr: int, fc: float, offsets: bool, compensate: bool,
                moving: Optional[np.ndarray] = None, bad: Optional[np.ndarray] = None) -> tuple[Fit, dict[str, float]]:
    """The electrical fit of (R, L, Km[, va_offset, vb_offset]) (module docstring), with the noise bias removed.

    ``moving`` marks the periods whose motion the encoder resolves (:func:`.identify_terms.moving_samples`;
    ``None``: all), elsewhere the back-emf term is taken as zero (the encoder's toggling is not a motion); rows
    near a ``bad`` sample are left out (:func:`.identify_terms.clipped_samples`). Also returns the current
    noise's share of the power of the filtered R and L regressors
    (:func:`~flatstep.studies.identify_checks.check_noise_share`), estimated whether or not it is compensated.
    """
    sos, rows = filtered(rec, fc)
    keep = kept_rows(np.zeros(rec.t.size, dtype=bool) if bad is None else bad, rows, rows.start)
    blocks, names, raw, sos, rows = electrical_blocks(rec, Nr, fc, offsets, optional(moving, rec.t.size - 1), keep)
    Ts = rec.period
    result = plain = fit(blocks, names, lags=8, source=rec.source, hint=HINT)
    unit = _unit_noise_gram(sos, Ts, rows.start)
    still = np.diff(rec.theta) == 0  # periods without an encoder step: no quantization step in the back-emf term
    X = np.concatenate([b[0] for b in blocks])
    power = np.einsum("ij,ij->j", X[:, :2], X[:, :2])
    share: dict[str, float] = {}
    for _ in range(NOISE_ITERATIONS if compensate else 1):
        R, L, Km = result.values[:3]
        gram = np.zeros((len(names), len(names)))
        for k, terms in enumerate(raw):
            offset = result.values[3 + k] if offsets else 0.0
            r = terms[3] - R * terms[0] - L * terms[1] - Km * terms[2] - offset  # the raw equation's residual
            r = (r - sosfiltfilt(sos, r))[still if np.count_nonzero(still) > 100 else slice(None)]  # noise alone
            mad = 1.4826 * float(np.median(np.abs(r - np.median(r))))  # robust to what is left of the rest
            gain = 2.0 * L**2 / Ts**2 + 0.5 * R**2  # the raw residual's variance per unit current noise variance
            gram[:2, :2] += blocks[k][1].size * mad**2 / gain * unit if gain > 0 else np.inf
        share = {n: float(g / p) if p > 0 else math.inf for n, g, p in zip(("R", "L"), np.diag(gram)[:2], power,
                                                                           strict=True)}
        if compensate and share["L"] <= 1.0 and share["R"] <= 1.0:  # beyond 1 the compensated X^T X is not a Gram
            result = fit(blocks, names, lags=8, source=rec.source, hint=HINT, noise_gram=gram)
        elif compensate:
            break
    shift = result.values - plain.values  # the correction is as uncertain as it is large (closed loop)
    steps = electrical_quantization(rec.theta, (rec.ia, rec.ib), Nr, Ts, sos, rows, keep,
                                    optional(moving, rec.t.size - 1), blocks, result.values, result.gram)
    return replace(result, covariance=result.covariance + np.outer(shift, shift) + np.diag(steps)), share


def _mechanical(rec: Recording, Nr: int, fc: float, detent: bool, coulomb: bool, harmonic: int,
                coulomb_speed: float, bad: np.ndarray) -> Fit:
    """The mechanical fit, in units of Km: (J, B, load_torque[, detent a, b][, coulomb_torque]) / Km."""
    extra = (["detent_a", "detent_b"] if detent else []) + (["coulomb_torque"] if coulomb else [])
    terms, iq, omega, rows = mechanical_terms(rec, Nr, fc, extra, harmonic, coulomb_speed)
    X = np.column_stack(list(terms.values()))
    moving = moving_rows(omega, rec.theta, fc) & kept_rows(bad, rows, rows.start)
    if np.count_nonzero(moving) < ROWS_PER_PARAMETER * X.shape[1]:
        row_time = (rows.step or 1) * rec.period
        need, moved = ROWS_PER_PARAMETER * X.shape[1] * row_time, np.count_nonzero(moving) * row_time
        raise ValueError(f"{rec.source}: the rotor moves (faster than {MOVING_COUNTS:g} encoder counts per "
                         f"{1e3 / fc:.3g} ms) during only {moved:.3g} s of the recording; {list(terms)} need at least "
                         f"{need:.3g} s of motion: not exciting enough; {HINT}")
    return fit([(X[moving], iq[moving])], list(terms), lags=8, source=rec.source, hint=HINT)


def _with_floor(result: Fit) -> Fit:
    """``result`` with the method's systematic floor (:data:`FLOOR`) added to its estimates' variances."""
    floor = np.array([FLOOR.get(n, 0.0) for n in result.names]) * np.abs(result.values)
    return replace(result, covariance=result.covariance + np.diag(floor**2))


def identify(data: Union[Recording, str, Path], *, Nr: int = 50, detent: bool = False, coulomb: bool = False,
             offsets: bool = True, bandwidth: tuple[float, float] = (200.0, 100.0), detent_harmonic: int = 4,
             coulomb_speed: float = 0.3, confidence: float = 0.95, noise_compensation: bool = True) -> Identification:
    r"""Estimate the motor's parameters from a recording (module docstring for the method).

    Parameters
    ----------
    data : Recording or path
        The recording, or its CSV file (:mod:`flatstep.studies.record` for the format).
    Nr : int
        The number of rotor teeth (50 for a 1.8-degree motor); not estimated.
    detent : bool
        Also estimate the detent torque's amplitude [N m] and phase [rad], :math:`T_d\sin(hN_r\theta + \varphi)`.
    coulomb : bool
        Also estimate the Coulomb friction [N m], :math:`T_c\tanh(\dot\theta/\omega_s)`.
    offsets : bool
        Estimate a constant voltage offset per phase.
    bandwidth : (float, float)
        Cutoffs [Hz] of the electrical and the mechanical equations' filters.
    detent_harmonic : int
        :math:`h`, detent periods per electrical period (4 for a two-phase motor).
    coulomb_speed : float
        :math:`\omega_s` [rad/s] of the Coulomb term's smooth sign: 0.3 rad/s, a few times the resolution of
        the filtered speed; the split between Coulomb and viscous friction depends on it (docs/identification.md).
    confidence : float
        Level of the intervals, in (0, 1).
    noise_compensation : bool
        Remove the bias the current noise puts on the electrical estimates (module docstring).

    Returns
    -------
    Identification
        Estimates, intervals, residuals and the [motor] table.
    """
    rec = data if isinstance(data, Recording) else read_recording(data)
    Nr = check_integer("Nr", Nr, why="the number of rotor teeth")
    harmonic = check_integer("detent_harmonic", detent_harmonic)
    coulomb_speed = check_positive("coulomb_speed", coulomb_speed, unit=" rad/s")
    confidence = check_quantity("confidence", confidence)
    if len(bandwidth) != 2:
        raise InputError("bandwidth", bandwidth, f"bandwidth={bandwidth!r} must be two cutoffs [Hz]: (electrical, "
                         "mechanical)")
    fc_e, fc_m = (check_quantity("rate", b, as_name="bandwidth") for b in bandwidth)
    check_units(rec)
    moving = moving_samples(rec, fc_m)
    bad = confirm_clipping(rec, Nr, fc_e, offsets, moving, clipped_samples(rec))
    _, rows = filtered(rec, fc_e)
    scan = check_alignment(rec, Nr, fc_e, offsets, moving, kept_rows(bad, rows, rows.start))
    elec, share = _electrical(rec, Nr, fc_e, offsets, noise_compensation, moving, bad)
    check_noise_share(share, rec.source)
    check_separable(elec, rec.source, HINT)
    mech = _mechanical(rec, Nr, fc_m, detent, coulomb, harmonic, coulomb_speed, bad)
    check_separable(mech, rec.source, HINT)
    modelled = (["detent_a", "detent_b"] if detent else []) + (["coulomb_torque"] if coulomb else [])
    flags, notes = effect_flags(rec, Nr, fc_m, modelled, harmonic, coulomb_speed, bad, float(elec.values[2]))
    dead = dead_time_flag(rec, Nr, fc_e, offsets, moving, kept_rows(bad, rows, rows.start), float(elec.values[0]))
    flags += [dead] if dead else []
    elec, mech = _with_floor(elec), _with_floor(mech)
    km, var_km = elec.values[2], elec.covariance[2, 2]
    values = dict(zip(elec.names, elec.values, strict=True))
    var = dict(zip(elec.names, np.diag(elec.covariance), strict=True))
    p, cov = mech.values, mech.covariance
    values.update({f"{k}/Km": v for k, v in zip(mech.names[:3], p, strict=False)})
    var.update({f"{k}/Km": v for k, v in zip(mech.names[:3], np.diag(cov), strict=False)})
    k_load = mech.names.index("load_torque")
    cov = cov.copy()
    cov[k_load, k_load] += (LOAD_FLOOR * float(np.sqrt(np.mean(rec.ia**2 + rec.ib**2)))) ** 2  # a zero load too
    var["load_torque/Km"] = cov[k_load, k_load]
    cov_phys = km**2 * cov + np.outer(p, p) * var_km  # q = Km p, with Km's variance (delta method)
    values.update(zip(mech.names, km * p, strict=True))
    var.update(zip(mech.names, np.diag(cov_phys), strict=True))
    if detent:
        ia_, ib_ = mech.names.index("detent_a"), mech.names.index("detent_b")
        a, b = values.pop("detent_a"), values.pop("detent_b")
        del var["detent_a"], var["detent_b"]
        amp = math.hypot(a, b)
        grad_amp, grad_phase = np.array([a, b]) / amp, np.array([-b, a]) / amp**2
        sub = cov_phys[np.ix_([ia_, ib_], [ia_, ib_])]
        values.update(detent_torque=amp, detent_phase=math.atan2(b, a))
        var.update(detent_torque=float(grad_amp @ sub @ grad_amp), detent_phase=float(grad_phase @ sub @ grad_phase))
    z = NormalDist().inv_cdf(0.5 + 0.5 * confidence)
    std = {k: math.sqrt(max(v, 0.0)) for k, v in var.items()}
    result = Identification(estimates={k: float(v) for k, v in values.items()}, std=std, z=z, confidence=confidence,
                            Nr=Nr, residual_rms={"electrical": elec.residual_rms,
                                                 "mechanical": abs(km) * mech.residual_rms},
                            condition={"electrical": elec.condition, "mechanical": mech.condition}, source=rec.source,
                            settings={"bandwidth": [fc_e, fc_m], "offsets": offsets,
                                      "noise_compensation": noise_compensation, "detent_harmonic": harmonic,
                                      "coulomb_speed": coulomb_speed, "samples": int(rec.t.size),
                                      "period": rec.period, "noise_share": share,
                                      "clipped_samples": int(np.count_nonzero(bad)),
                                      "alignment_rms": {str(k): v for k, v in scan.items()}},
                            notes=tuple(notes))
    wide = {k: result.relative_half_width(k) for k in CORE if not result.relative_half_width(k) <= MAX_REL_HALF_WIDTH}
    if wide:
        shown = ", ".join(f"{k} +-{w:.0%}" for k, w in wide.items())
        left_out = "".join(f"; {flag}" for flag in flags)  # a term left out widens them too: say which
        raise ValueError(f"{rec.source}: not exciting enough: the {confidence:.0%} intervals are {shown} (at most "
                         f"+-{MAX_REL_HALF_WIDTH:.0%} accepted){left_out}; {HINT}")
    check_estimates(result.estimates, {k: result.interval(k) for k in result.estimates}, rec.source, confidence)
    check_resistance(rec, result.estimates["R"])
    return replace(result, flags=atypical(result.estimates) + tuple(flags))
