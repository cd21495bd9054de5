r"""What a recording holds that identification's equations leave out: detected, then refused, flagged or noted.

Each test refits an equation with one more term (or with its data moved) and asks whether the fit changes by
more than its noise:

* **A current at the ADC's full scale** (:func:`confirm_clipping`): the candidate runs of
  :func:`~flatstep.studies.identify_terms.clipped_samples` are left out of both fits when that lowers the
  electrical residual below :data:`CLIPPED_GAIN` of its value with them.
* **Alignment** (:func:`check_alignment`): the electrical fit with the voltage columns read
  :data:`SHIFTS` periods later or earlier; a log whose voltages fit best at another shift, with a residual below
  :data:`ALIGN_RATIO` of the recorded alignment's, is refused: a voltage one period late makes L and Km wrong by
  several times their value while their intervals stay narrow.
* **Dead time** (:func:`dead_time_flag`): a PWM dead time makes the applied voltage differ from the command by
  :math:`V_d\,\mathrm{sign}(i)` per phase (about :math:`2 v_{bus} f_{pwm} t_d`), which lands on R. A term
  :math:`V_d\,\mathrm{sign}(i)` in each phase's equation, significant at :data:`Z_DETECT` standard errors and
  moving R by more than :data:`MATERIAL`, is flagged.
* **Detent torque and Coulomb friction** (:func:`effect_flags`): the mechanical fit with the terms the user did
  not ask for; one significant at :data:`Z_DETECT` standard errors and larger than :data:`MATERIAL_TORQUE` of
  the motor's rms torque in motion is flagged, naming the flag that models it.
  A recording whose motion has one direction only cannot tell Coulomb friction from a constant load
  (:math:`\tanh(\dot\theta/\omega_s)` is constant where it moves): its ``load_torque`` is the load plus the
  friction in that direction, and a note says so.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .identify_ls import fit
from .identify_terms import Blocks, electrical_blocks, filtered, kept_rows, mechanical_terms, moving_rows, sosfiltfilt
from .record import Recording

#: Left-out candidates of a full-scale ADC are confirmed when the electrical residual drops below this fraction.
CLIPPED_GAIN = 0.25
#: The shifts [periods] of the voltage columns the alignment scan tries.
SHIFTS = (-3, -2, -1, 0, 1, 2, 3)
#: A shift is refused when its residual is below this fraction of the recorded alignment's.
ALIGN_RATIO = 0.5
#: A left-out term is detected beyond this many standard errors.
Z_DETECT = 5.0
#: A dead-time term is flagged when it also moves R by more than this fraction, a detent or Coulomb term when
#: its torque is more than this fraction of the rms motor torque while the rotor moves.
MATERIAL = 0.005
MATERIAL_TORQUE = 0.02


def _rms(blocks: Blocks) -> float:
    """The residual rms of the plain least-squares fit of ``blocks``."""
    X = np.concatenate([b[0] for b in blocks])
    y = np.concatenate([b[1] for b in blocks])
    p = np.linalg.lstsq(X, y, rcond=None)[0]
    return float(np.sqrt(np.mean((y - X @ p) ** 2)))


def confirm_clipping(rec: Recording, Nr: int, fc: float, offsets: bool, moving: np.ndarray,
                     candidates: np.ndarray) -> np.ndarray:
    """The samples to leave out: ``candidates`` if leaving them out makes the equations hold, else none."""
    if not candidates.any():
        return candidates
    _, rows = filtered(rec, fc)
    everything = kept_rows(np.zeros_like(candidates), rows, rows.start)
    without = kept_rows(candidates, rows, rows.start)
    if np.count_nonzero(without) < 0.2 * without.size:
        return np.zeros_like(candidates)  # too little left to tell
    r_all = _rms(electrical_blocks(rec, Nr, fc, offsets, moving, everything)[0])
    r_without = _rms(electrical_blocks(rec, Nr, fc, offsets, moving, without)[0])
    return candidates if r_without < CLIPPED_GAIN * r_all else np.zeros_like(candidates)


def check_alignment(rec: Recording, Nr: int, fc: float, offsets: bool, moving: np.ndarray,
                    keep: np.ndarray) -> dict[int, float]:
    """The electrical residual rms per shift of the voltage columns; refuse a log that fits best misaligned."""
    blocks, _, raw, sos, rows = electrical_blocks(rec, Nr, fc, offsets, moving, keep)
    voltages = [sosfiltfilt(sos, terms[3]) for terms in raw]  # each phase's filtered voltage, read at shifted rows
    scan = {s: _rms([(X, v[rows.start + s:rows.stop + s:rows.step][keep]) for (X, _), v in zip(blocks, voltages,
                                                                                               strict=True)])
            for s in SHIFTS}
    best = min(scan, key=lambda s: scan[s])
    if best != 0 and scan[best] < ALIGN_RATIO * scan[0]:
        shown = ", ".join(f"{s:+d}: {v:.3g} V" for s, v in scan.items())
        raise ValueError(f"{rec.source}: the voltage columns are shifted: the equations fit best with 'va', 'vb' read "
                         f"{abs(best)} period(s) {'later' if best > 0 else 'earlier'} than 'ia', 'ib', 'theta' "
                         f"(residual rms per shift {shown}); a misaligned log makes L and Km wrong by more than "
                         "their intervals show: write on each row the voltage applied from t_k to t_k+1 (with a "
                         "computation delay, the previous period's command) and the currents and angle read at t_k")
    return scan


def dead_time_flag(rec: Recording, Nr: int, fc: float, offsets: bool, moving: np.ndarray, keep: np.ndarray,
                   R: float) -> Optional[str]:
    """A flag when a voltage against each phase current's sign (a PWM dead time) is significant and moves R."""
    blocks, names, *_ = electrical_blocks(rec, Nr, fc, offsets, moving, keep, dead_time=True)
    try:
        result = fit(blocks, names, lags=8, source=rec.source, hint="")
    except ValueError:
        return None  # the sign of the current cannot be told from the other terms here
    vd, sd = float(result.values[-1]), math.sqrt(max(float(result.covariance[-1, -1]), 0.0))
    r_with = float(result.values[0])
    if not (abs(vd) > Z_DETECT * sd and abs(r_with - R) > MATERIAL * abs(R)):
        return None
    return (f"a voltage of {vd:.3g} V follows each phase current's sign ({abs(vd) / sd:.3g} standard errors): a PWM "
            f"dead time (about 2 v_bus f_pwm t_dead) that the model leaves out: R = {R:.6g} ohm is biased (with the "
            f"term, R = {r_with:.6g} ohm); record with the drive's dead-time compensation on, or the phase voltages "
            "as measured")


def effect_flags(rec: Recording, Nr: int, fc: float, modelled: list[str], harmonic: int, coulomb_speed: float,
                 bad: np.ndarray, km: float) -> tuple[list[str], list[str]]:
    """Flags for a detent torque or Coulomb friction that is present and not modelled, and notes.

    Returns
    -------
    flags, notes
        What is flagged (a term the recording shows), and what is noted (a load that includes the Coulomb
        friction of a motion in one direction).
    """
    missing = [k for k in ("detent_a", "detent_b", "coulomb_torque") if k not in modelled]
    terms, iq, omega, rows = mechanical_terms(rec, Nr, fc, [*modelled, *missing], harmonic, coulomb_speed)
    moving = moving_rows(omega, rec.theta, fc) & kept_rows(bad, rows, rows.start)
    flags: list[str] = []
    notes: list[str] = []
    one_way = bool(np.all(omega[moving] > 0) or np.all(omega[moving] < 0))
    if one_way and "coulomb_torque" in missing:
        direction = "positive" if np.all(omega[moving] > 0) else "negative"
        notes.append(f"the rotor moves in one direction only ({direction}): load_torque includes the Coulomb "
                     "friction (a constant load and a friction cannot be told apart); record moves in both "
                     "directions to separate them")
        missing.remove("coulomb_torque")
        del terms["coulomb_torque"]
    if not missing:
        return flags, notes
    X = np.column_stack(list(terms.values()))
    try:
        result = fit([(X[moving], iq[moving])], list(terms), lags=8, source=rec.source, hint="")
    except ValueError:
        return flags, notes  # the terms cannot be told from the others here
    index = {n: k for k, n in enumerate(result.names)}
    floor = MATERIAL_TORQUE * float(np.sqrt(np.mean(iq[moving] ** 2)))  # in units of Km, as the estimates
    if "detent_a" in missing:
        k = [index["detent_a"], index["detent_b"]]
        ab = result.values[k]
        chi2 = float(ab @ np.linalg.solve(result.covariance[np.ix_(k, k)], ab))
        if chi2 > Z_DETECT**2 and math.hypot(*ab) > floor:
            flags.append(f"a detent torque of about {abs(km) * math.hypot(*ab):.3g} N m is in the recording "
                         f"({math.sqrt(chi2):.3g} standard errors) and not modelled: J, B and the load are biased; "
                         "give --detent")
    if "coulomb_torque" in missing:
        j = index["coulomb_torque"]
        c, sd = result.values[j], math.sqrt(max(float(result.covariance[j, j]), 0.0))
        if abs(c) > Z_DETECT * sd and abs(c) > floor:
            flags.append(f"a Coulomb friction of about {km * c:.3g} N m is in the recording ({abs(c) / sd:.3g} "
                         "standard errors) and not modelled: B and the load are biased; give --coulomb")
    return flags, notes
