"""The result of an identification: estimates, confidence intervals, fit quality, and the [motor] table."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

from ..model.motor import MotorParams

#: Unit of each parameter an identification may report.
UNITS = {"R": "ohm", "L": "H", "Km": "V s/rad", "J": "kg m^2", "B": "N m s/rad", "load_torque": "N m",
         "va_offset": "V", "vb_offset": "V", "J/Km": "A s^2/rad", "B/Km": "A s/rad",
         "load_torque/Km": "A", "detent_torque": "N m", "detent_phase": "rad", "coulomb_torque": "N m"}
MOTOR_KEYS = ("R", "L", "Km", "J", "B")


@dataclass(frozen=True)
class Identification:
    """Estimated parameters with their standard errors and ``confidence`` intervals (``value +- z std``).

    Parameters
    ----------
    estimates : dict of str to float
        The estimates by name (:data:`UNITS`).
    std : dict of str to float
        Their standard errors, same units.
    z : float
        The normal quantile of the confidence level (1.96 for 95 %).
    confidence : float
        The intervals' level.
    Nr : int
        The rotor teeth the model was fitted with.
    residual_rms : dict of str to float
        The filtered equations' residual rms: ``electrical`` [V], ``mechanical`` [N m].
    condition : dict of str to float
        The condition numbers of the column-scaled regressors of both fits.
    source : str
        The recording's name.
    settings : dict
        The identification's settings (bandwidths, switches, samples, sampling period, the current noise's share).
    flags : tuple of str
        What is atypical of a stepping motor (:func:`~flatstep.studies.identify_checks.atypical`) or in the
        recording and not modelled (:mod:`~flatstep.studies.identify_detect`); empty when nothing is.
    notes : tuple of str
        What an estimate means on this recording (a load that includes the Coulomb friction of a motion in one
        direction).
    """

    estimates: dict[str, float]
    std: dict[str, float]
    z: float
    confidence: float
    Nr: int
    residual_rms: dict[str, float]
    condition: dict[str, float]
    source: str
    settings: dict[str, Any]
    flags: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()

    def interval(self, name: str) -> tuple[float, float]:
        """The confidence interval of ``name``."""
        value, half = self.estimates[name], self.z * self.std[name]
        return value - half, value + half

    def relative_half_width(self, name: str) -> float:
        """The interval's half-width over the estimate's magnitude (inf for a zero estimate)."""
        value = abs(self.estimates[name])
        return self.z * self.std[name] / value if value > 0 else math.inf

    def motor(self) -> MotorParams:
        """The estimates as :class:`~flatstep.model.motor.MotorParams` (B clipped at 0)."""
        e = self.estimates
        return MotorParams(R=e["R"], L=e["L"], Km=e["Km"], J=e["J"], B=max(e["B"], 0.0), Nr=self.Nr)

    def errors(self, truth: MotorParams) -> dict[str, float]:
        """Relative errors ``estimate / true - 1`` of R, L, Km, J, B against ``truth``."""
        return {k: self.estimates[k] / getattr(truth, k) - 1.0 for k in MOTOR_KEYS}

    def table(self, truth: Optional[MotorParams] = None) -> str:
        """The estimates, intervals and relative half-widths (and the errors against ``truth``) as text."""
        level = f"{self.confidence:.0%} interval"
        head = f"{'parameter':<15}{'estimate':>13}  {level:<29}{'+-':>9}  {'unit':<10}"
        lines = [head + ("      error" if truth is not None else "")]
        for name, value in self.estimates.items():
            lo, hi = self.interval(name)
            w = f"{self.relative_half_width(name):.2%}" if lo > 0 or hi < 0 else "-"  # relative to a non-zero value
            row = f"{name:<15}{value:>13.6g}  [{lo:>12.6g}, {hi:>12.6g}]{w:>9}  {UNITS[name]:<10}"
            if truth is not None and name in MOTOR_KEYS:
                row += f"{self.estimates[name] / getattr(truth, name) - 1.0:>+10.2%}"
            lines.append(row)
        lines.append(f"residual rms: electrical {self.residual_rms['electrical']:.3g} V, mechanical "
                     f"{self.residual_rms['mechanical']:.3g} N m; condition numbers: electrical "
                     f"{self.condition['electrical']:.3g}, mechanical {self.condition['mechanical']:.3g}")
        return "\n".join(lines)

    def as_toml(self) -> str:
        """A ``[motor]`` table for a scenario file, the intervals as comments (and the effects as a comment)."""
        lines = [f"# identified from {self.source} ({self.confidence:.0%} intervals in the comments)"]
        lines += [f"# flagged: {flag}" for flag in self.flags] + [f"# note: {n}" for n in self.notes] + ["[motor]"]
        for name in MOTOR_KEYS:
            value = self.estimates[name]
            note = f"  # [{self.interval(name)[0]:.6g}, {self.interval(name)[1]:.6g}] {UNITS[name]}"
            if name == "B" and value < 0:
                note += f"; the estimate {value:.6g} is negative, clipped to 0"
                value = 0.0
            lines.append(f"{name} = {value:.6g}{note}")
        lines.append(f"Nr = {self.Nr}  # given, not estimated")
        effects = [f"{k} = {self.estimates[k]:.6g}" for k in ("detent_torque", "coulomb_torque") if k in self.estimates]
        if effects:
            lines += ["# plant effects (a [plant] table of a scenario file takes them):"] + [f"# {e}" for e in effects]
        return "\n".join(lines) + "\n"

    def as_dict(self) -> dict[str, Any]:
        """Everything, for JSON."""
        return {"source": self.source, "Nr": self.Nr, "confidence": self.confidence,
                "estimates": self.estimates, "std": self.std,
                "intervals": {k: list(self.interval(k)) for k in self.estimates},
                "relative_half_width": {k: self.relative_half_width(k) for k in self.estimates},
                "units": {k: UNITS[k] for k in self.estimates}, "residual_rms": self.residual_rms,
                "condition": self.condition, "settings": self.settings, "flags": list(self.flags),
                "notes": list(self.notes)}
