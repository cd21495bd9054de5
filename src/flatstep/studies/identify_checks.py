r"""Plausibility of a recording and of what is fitted to it: units, ranges, and the current noise's share.

An identification or a calibration that the data cannot support is refused (a ``ValueError`` naming the recording,
the value and why), never printed as a result:

* **Units, before the fit** (:func:`check_units`). Currents beyond the range flatstep accepts for a current
  (1000 A), voltages beyond that of a bus (10 kV) or angles beyond that of an angle (1e6 rad) are the recording's
  units, not a motor's: currents in mA, voltages in mV, an angle in encoder counts. The message asks which.
* **The fit against the raw data** (:func:`check_resistance`): the resistance of the crude fit
  :math:`v \approx R' i` over every row (back-emf and inductance left in the residual) is within a factor of
  :data:`MAX_RESISTANCE_RATIO` of the fitted :math:`R` on any recording that follows eq. (1); orders of magnitude
  apart, the columns are not the applied voltages and the measured currents of one motor.
* **Ranges, after the fit** (:func:`check_estimates`): every estimate within the range of its quantity
  (:mod:`flatstep.validate.ranges`); a viscous or Coulomb friction whose whole interval is negative contradicts
  the model (one that is negative only within its interval is clipped to 0, and said so).
* **Typical of a stepping motor** (:func:`atypical`): an estimate within its range but beyond
  :data:`TYPICAL` (what hybrid and permanent-magnet stepping motors have, from NEMA 8 to NEMA 42) is returned
  with a flag, which the command line prints as a warning: it is what a recording in mV or mA looks like.
* **Current noise** (:func:`check_noise_share`): noise in the current regressors biases the electrical fit
  (errors in variables), and the intervals do not include that bias; the bias compensation
  (:mod:`flatstep.studies.identify`) removes it only while the noise is a small part of what is fitted. A fit in
  which the noise makes up more than :data:`MAX_NOISE_SHARE` of a current regressor's power is refused.
"""
from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from ..validate.ranges import QUANTITIES
from .record import Recording

#: The largest share of a current regressor's power (after the filter) that the current noise may make up.
MAX_NOISE_SHARE = 0.25
#: How far the crude resistance ``sum(v i) / sum(i i)`` may be from the fitted R (a factor either way).
MAX_RESISTANCE_RATIO = 10.0
#: Which quantity of :data:`flatstep.validate.ranges.QUANTITIES` bounds each estimate.
RANGE_OF = {"R": "R", "L": "L", "Km": "Km", "J": "J", "B": "B", "load_torque": "load", "load": "load",
            "detent_torque": "torque_amplitude", "coulomb_torque": "torque_amplitude"}
#: Estimates that may come out slightly negative within their interval, and are then clipped to 0.
CLIPPED = ("B", "coulomb_torque")
#: What stepping motors have (datasheets of NEMA 8 to NEMA 42 motors, with margin): an estimate beyond is flagged.
TYPICAL = {"R": (0.05, 500.0), "L": (1e-5, 1.0), "Km": (1e-3, 10.0), "J": (1e-8, 1e-2)}
UNITS_HINT = ("R, L and Km scale with the voltage unit, R and L inversely with the current unit, J and B with "
              "Km over the current unit: give the voltages in V, the currents in A, the angle in rad")


def check_units(rec: Recording) -> None:
    """Refuse a recording whose values are beyond any motor's in its units (module docstring)."""
    limits = (("ia", "ib", "current", "A", "are the currents in mA? give them in A"),
              ("va", "vb", "v_bus", "V", "are the voltages in mV? give them in V"),
              ("theta", "theta", "angle", "rad", "is theta in encoder counts or degrees? give it in rad"))
    for a, b, kind, unit, question in limits:
        peak = max(float(np.max(np.abs(getattr(rec, a)))), float(np.max(np.abs(getattr(rec, b)))))
        high = QUANTITIES[kind].high
        if peak > high:
            cols = f"columns {a!r}, {b!r} reach" if a != b else f"column {a!r} reaches"
            raise ValueError(f"{rec.source}: {cols} {peak:.6g} {unit}, beyond the {high:g} {unit} flatstep "
                             f"accepts ({QUANTITIES[kind].why}): {question}")


def check_resistance(rec: Recording, R: float) -> None:
    """Refuse a fitted ``R`` orders of magnitude from the crude ``sum(v i) / sum(i i)`` of the raw columns."""
    i = np.concatenate([rec.ia, rec.ib])
    v = np.concatenate([rec.va, rec.vb])
    ii = float(i @ i)
    if not ii > 0:
        return  # no current at all: the fit has refused it already
    crude = float(v @ i) / ii
    ratio = crude / R if R > 0 else math.inf
    if not 1.0 / MAX_RESISTANCE_RATIO <= ratio <= MAX_RESISTANCE_RATIO:
        question = ("are the voltages in mV, or the currents in A where mA are meant?" if ratio > 1
                    else "are the currents in mA, or the voltages in V where mV are meant?")
        raise ValueError(f"{rec.source}: the voltages over the currents, sum(v i)/sum(i^2) = {crude:.6g} ohm, are "
                         f"{ratio:.3g} times the fitted R = {R:.6g} ohm (at most {MAX_RESISTANCE_RATIO:g} times "
                         f"either way on a recording of eq. (1)): {question} Are 'va', 'vb' the applied voltages and "
                         "'ia', 'ib' the measured currents of the same phases?")


def check_estimates(estimates: Mapping[str, float], intervals: Mapping[str, tuple[float, float]], source: str,
                    confidence: float) -> None:
    """Refuse an estimate outside the range of its quantity (module docstring), naming it and the range."""
    for name, value in estimates.items():
        kind = RANGE_OF.get(name)
        if kind is None:
            continue
        q = QUANTITIES[kind]
        lo, hi = intervals[name]
        if name in CLIPPED and value < 0:
            if hi < 0:
                raise ValueError(f"{source}: {name} = {value:.6g} {q.unit}, and its whole {confidence:.0%} interval "
                                 f"[{lo:.6g}, {hi:.6g}] is negative: {q.why}; the recording contradicts the model "
                                 "(a load that varies, a drive that saturates, a wrong Nr?)")
            continue  # negative within the noise: clipped to 0 where it is written
        if not q.contains(value):
            side = "above" if value > q.high else "below"
            why = UNITS_HINT if not (name == "Km" and value < 0) else (
                "a negative back-emf constant is the angle's zero half an electrical period off (theta = 0 must be "
                "where phase a's current aligns the rotor) or the phases' polarity reversed")
            raise ValueError(f"{source}: {name} = {value:.6g} {q.unit} is {side} the range flatstep accepts, "
                             f"{q.describe()} ({q.why}); not a motor this recording can describe: {why}")


def check_noise_share(share: Mapping[str, float], source: str) -> None:
    """Refuse an electrical fit in which the current noise is more than :data:`MAX_NOISE_SHARE` of a regressor."""
    worst = max(share, key=lambda k: share[k])
    if not share[worst] <= MAX_NOISE_SHARE:
        raise ValueError(f"{source}: the current noise makes up {share[worst]:.0%} of the power of the filtered "
                         f"{worst} regressor (at most {MAX_NOISE_SHARE:.0%} accepted): the noise biases the "
                         "estimates by more than their intervals show; record with less current noise (a finer or "
                         "quieter ADC, larger currents) or a longer, faster excitation")


def atypical(estimates: Mapping[str, float]) -> tuple[str, ...]:
    """One flag per estimate beyond :data:`TYPICAL`, each asking about the recording's units."""
    flags = []
    for name, (low, high) in TYPICAL.items():
        value = estimates[name]
        if low <= value <= high:
            continue
        above = value > high
        if name in ("R", "L", "Km"):
            question = "are the voltages in mV?" if above else "are the currents in mA, or the voltages in kV?"
        else:
            question = "are the currents in mA?" if above else "are the currents in kA?"
        flags.append(f"{name} = {value:.6g} {QUANTITIES[name].unit} is {'above' if above else 'below'} what "
                     f"stepping motors have ({low:g} to {high:g} {QUANTITIES[name].unit}): {question}")
    return tuple(flags)
