r"""A two-phase hybrid stepper from its datasheet: the model of eq. (1), what was assumed and how sure it is.

A datasheet gives the step angle, the rated current and the holding torque, the winding's R and L, and the rotor
inertia. The a-b model (:class:`~flatstep.model.motor.MotorParams`) needs the number of rotor teeth
:math:`N_r`, the torque constant :math:`K_m` of the current-vector norm :math:`\rho = \sqrt{i_a^2 + i_b^2}` and a
viscous friction :math:`B` that no datasheet gives. :func:`from_datasheet` derives them, and returns every
assumption it made with the uncertainty it carries (:class:`Assumption`); :func:`motor_from_table` does the same
for a ``[motor]`` table of a scenario or plan file. The keys, their units and the derivation: docs/motors.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

from ..validate import InputError
from .datasheet_math import (  # noqa: F401  (re-exported: this module's API, docs/motors.md)
    B_DEFAULT,
    DATASHEET_KEYS,
    DESCRIPTION_KEYS,
    parameters_from_datasheet,
    rotor_teeth,
    torque_constant,
)
from .motor import MotorParams

#: The datasheet keys a ``[motor]`` table must give (:data:`DATASHEET_KEYS`: all keys and their units).
REQUIRED = ("step_angle", "rated_current", "holding_torque", "resistance", "inductance", "rotor_inertia")
#: The model keys of a ``[motor]`` table (``preset`` or the parameters of eq. (1)).
MODEL_KEYS = ("preset", "R", "L", "Km", "J", "B", "Nr")

#: Relative uncertainty taken for a typical holding torque: an assumption, the tolerance Beckhoff states for its
#: motor data (+-10 %); Sanyo Denki quotes a minimum instead (``holding_torque_rating = "minimum"``).
HOLDING_TORQUE_TOLERANCE = 0.10
#: Relative tolerances of the winding resistance (+-10 %) and inductance (+-20 %), as stepper datasheets print
#: them (e.g. AKT Motor's 42HS general specification, Changzhou Songyang's SY28STH45 sheet).
RESISTANCE_TOLERANCE = 0.10
INDUCTANCE_TOLERANCE = 0.20
#: Temperature coefficient of copper's resistance [1/K] (0.393 %/K at 20 degC).
COPPER_TEMPCO = 0.00393
#: The winding temperature rise allowed at rated current [K] (80 K max., Sanyo Denki's general specifications).
RATED_TEMPERATURE_RISE = 80.0


@dataclass(frozen=True)
class Assumption:
    """One thing assumed on the way from a datasheet to the model, and the uncertainty it carries.

    Parameters
    ----------
    parameter : str
        The model parameter it bears on (``Km``, ``L``, ``R``, ``J``, ``B``, ``Nr``, ``i_max``).
    what : str
        What was assumed, and why.
    uncertainty : str
        The uncertainty it carries on that parameter, in words (e.g. ``+-10 %``).
    relative : float or None
        The same as a relative half-width (0.10 for +-10 %) where it is one; None where it is not (a guess).
    defaulted : bool
        Whether a key the datasheet (or the file) did not give was filled in.
    """

    parameter: str
    what: str
    uncertainty: str
    relative: Optional[float] = None
    defaulted: bool = False

    def as_dict(self) -> dict[str, Any]:
        """The assumption by field name (for JSON)."""
        return {"parameter": self.parameter, "what": self.what, "uncertainty": self.uncertainty,
                "relative": self.relative, "defaulted": self.defaulted}


@dataclass(frozen=True)
class MotorModel:
    r"""A motor built from its datasheet: the parameters of eq. (1), the figures they came from, the assumptions.

    Parameters
    ----------
    params : MotorParams
        R, L, Km, J, B, Nr of the a-b model.
    rated_rho : float
        The current-vector norm at the rated copper loss [A]: what ``i_max`` of a plan's ``[limits]`` means
        (:class:`flatstep.plan.limits.MotorLimits`), :math:`\sqrt 2 I` for a per-phase (RMS or DC) rating.
    datasheet : dict
        The figures as given, by key (SI units, :data:`DATASHEET_KEYS`).
    assumptions : tuple of Assumption
        Every assumption made, each with its uncertainty.
    defaults : dict
        The keys not given and the values taken for them (``current``, ``holding_torque_phases``,
        ``holding_torque_rating``, ``viscous_friction``).
    """

    params: MotorParams
    rated_rho: float
    datasheet: dict[str, Any]
    assumptions: tuple[Assumption, ...]
    defaults: dict[str, Any]

    @property
    def rated_torque(self) -> float:
        r"""The torque at the rated current-vector norm, :math:`K_m \rho_r` [N m] (the two-phase holding torque)."""
        return self.params.Km * self.rated_rho

    @property
    def time_constant(self) -> float:
        """The winding's electrical time constant L/R [s]."""
        return self.params.L / self.params.R

    @property
    def electrical_hz_per_rad_s(self) -> float:
        r"""The phase currents' electrical frequency per rad/s of rotor speed, :math:`N_r / 2\pi` [Hz per rad/s]."""
        return self.params.Nr / (2.0 * math.pi)

    @property
    def back_emf_per_rad_s(self) -> float:
        r"""The back-EMF amplitude per phase per rad/s, :math:`K_m` [V per rad/s] (eq. (1): :math:`K_m\omega`)."""
        return self.params.Km


def from_datasheet(*, step_angle: float, rated_current: float, holding_torque: float, resistance: float,
                   inductance: float, rotor_inertia: float, detent_torque: Optional[float] = None,
                   viscous_friction: Optional[float] = None, current: Optional[str] = None,
                   holding_torque_phases: Optional[int] = None, holding_torque_rating: Optional[str] = None,
                   **description: str) -> MotorModel:
    r"""The model of eq. (1) of a two-phase hybrid stepper from its datasheet, with every assumption made.

    Parameters
    ----------
    step_angle : float
        Full step [deg] (1.8 for 200 steps a turn): :math:`N_r = 90/\Delta\theta_{step}` (:func:`rotor_teeth`).
    rated_current : float
        Rated current per phase [A], as ``current`` says.
    holding_torque : float
        Holding torque at the rated current [N m], with ``holding_torque_phases`` phases energised.
    resistance : float
        Winding resistance per phase [ohm] (at 20-25 degC, as datasheets quote it).
    inductance : float
        Winding inductance per phase [H].
    rotor_inertia : float
        Rotor inertia [kg m^2] (1 g cm^2 = 1e-7 kg m^2).
    detent_torque : float, optional
        Detent (cogging) torque [N m]: reported, not part of eq. (1) (a scenario's ``[plant] detent_torque``).
    viscous_friction : float, optional
        B [N m s/rad]; default :data:`B_DEFAULT` (the paper's), a guess that is reported as one.
    current : {"rms", "peak"}, optional
        Whether ``rated_current`` is the per-phase RMS (or DC) current, as most datasheets quote it (default), or
        the peak of a sine-drive phase current.
    holding_torque_phases : {2, 1}, optional
        Phases energised for the holding torque: 2, as datasheets quote it (default), or 1.
    holding_torque_rating : {"typical", "minimum"}, optional
        Whether the holding torque is a typical figure (default, +-10 %) or a guaranteed minimum.
    **description : str
        ``maker``, ``part``, ``frame``, ``source``: kept with the figures.

    Returns
    -------
    MotorModel
        The parameters, the rated current-vector norm, the figures and the assumptions.

    Notes
    -----
    .. math::
        K_m = \frac{T_2}{\rho_r},\quad N_r = \frac{90}{\Delta\theta_{step}},\quad R, L, J \text{ as given},\quad
        B = B_{datasheet} \text{ or } 10^{-4}\ \mathrm{N\,m\,s/rad}
    """
    d = parameters_from_datasheet(
        step_angle=step_angle, rated_current=rated_current, holding_torque=holding_torque, resistance=resistance,
        inductance=inductance, rotor_inertia=rotor_inertia, detent_torque=detent_torque,
        viscous_friction=viscous_friction, current=current, holding_torque_phases=holding_torque_phases,
        holding_torque_rating=holding_torque_rating, **description)
    params = MotorParams(**d.params)
    notes = _assumptions(params, d.rated_rho, d.figures, d.given, viscous_friction is None, d.figures["detent_torque"])
    return MotorModel(params, d.rated_rho, d.figures, notes, d.defaults)


def _assumptions(p: MotorParams, rho: float, f: dict[str, Any], given: dict[str, Any], b_default: bool,
                 detent: Optional[float]) -> tuple[Assumption, ...]:
    """Every assumption of :func:`from_datasheet`, each with its uncertainty."""
    notes = []
    if given["current"] is None:
        notes.append(Assumption("i_max", "rated_current taken as per-phase RMS (or DC) current, as most datasheets "
                                f"quote it (current = \"rms\" not given): i_max = sqrt(2) x {f['rated_current']:g} A "
                                f"= {rho:.4g} A, the current-vector norm at the rated copper loss", "exact if the "
                                "datasheet means RMS/DC; Km x1.41 too low and i_max x1.41 too high if it means peak "
                                "(give current = \"peak\")", defaulted=True))
    else:
        notes.append(Assumption("i_max", f"rated_current is the per-phase {f['current']} current: i_max = "
                                f"{rho:.4g} A (the current-vector norm at the rated copper loss)", "as given"))
    if given["holding_torque_phases"] is None:
        notes.append(Assumption("Km", "holding_torque taken with both phases energised at rated current, as datasheets "
                                "quote it (holding_torque_phases = 2 not given)", "a one-phase figure would make Km "
                                "x1.41 too low (give holding_torque_phases = 1)", defaulted=True))
    if f["holding_torque_rating"] == "minimum":
        notes.append(Assumption("Km", f"holding_torque {f['holding_torque']:g} N m is a guaranteed minimum: "
                                f"Km = {p.Km:.4g} N m/A is a lower bound", "0 to +20 % (the motor's own torque is "
                                "at or above the minimum; the margin above it is a guess)", 0.20))
    else:
        notes.append(Assumption("Km", f"holding_torque {f['holding_torque']:g} N m is a typical figure: "
                                f"Km = {p.Km:.4g} N m/A", f"+-{HOLDING_TORQUE_TOLERANCE:.0%} (datasheet tolerance "
                                "of the holding torque)", HOLDING_TORQUE_TOLERANCE,
                                defaulted=given["holding_torque_rating"] is None))
    notes.append(Assumption("Km", "torque linear in current (eq. (1): no saturation, no detent harmonics): Km is the "
                            "same at every current up to rated", "near rated current a hybrid stepper saturates: "
                            "the torque per ampere falls by some percent above it"))
    notes.append(Assumption("R", f"R = {p.R:g} ohm at 20-25 degC, as datasheets quote it",
                            f"+-{RESISTANCE_TOLERANCE:.0%} tolerance; "
                            f"x{1 + COPPER_TEMPCO * RATED_TEMPERATURE_RISE:.2f} in a winding "
                            f"{RATED_TEMPERATURE_RISE:g} K above ambient (copper, +{100 * COPPER_TEMPCO:.3g} %/K)",
                            RESISTANCE_TOLERANCE))
    notes.append(Assumption("L", f"L = {p.L:g} H, the datasheet's figure, typically measured at 1 kHz with an LCR "
                            "meter: the small-signal inductance of eq. (1) differs from it, and falls with current "
                            "as the iron saturates", f"+-{INDUCTANCE_TOLERANCE:.0%} tolerance, more at rated current "
                            "(identify it: flatstep identify)", INDUCTANCE_TOLERANCE))
    notes.append(Assumption("J", f"J = {p.J:g} kg m^2 is the rotor alone", "add the load's inertia (a coupling, "
                            "a pulley) to J; the rotor's own figure is typical"))
    if b_default:
        share = 100.0 * p.B / f["holding_torque"]
        notes.append(Assumption("B", f"B = {p.B:g} N m s/rad is not on the datasheet: the paper's motor's value "
                                f"(Section 3), as the nema17 preset takes it ({share:.3g} % of the holding torque "
                                "per rad/s)", "a guess: the real damping (bearings, iron losses) may be 10x smaller "
                                "or larger; identify it from a recording (flatstep identify)", defaulted=True))
    else:
        notes.append(Assumption("B", f"B = {p.B:g} N m s/rad as given (viscous_friction)", "as given"))
    notes.append(Assumption("Nr", f"Nr = 90 / {f['step_angle']:g} deg = {p.Nr} rotor teeth (a two-phase hybrid "
                            "stepper: four full steps per tooth pitch)", "exact"))
    if detent is not None:
        notes.append(Assumption("detent", f"detent_torque {detent:g} N m is reported, not part of eq. (1): give it to "
                                "the simulated plant ([plant] detent_torque in a scenario file)", "as given"))
    return tuple(notes)


def uses_datasheet(table: dict[str, Any]) -> bool:
    """Whether a ``[motor]`` table gives its motor by datasheet keys (any key of :data:`DATASHEET_KEYS`)."""
    return any(key in DATASHEET_KEYS for key in table)


def motor_from_table(table: dict[str, Any], where: str, section: str = "motor") -> MotorModel:
    """The motor of a ``[motor]`` table of datasheet keys; errors name ``where:section.key``.

    Mixing the two forms (datasheet keys beside ``preset`` or R, L, Km, J, B, Nr) is refused, naming both; a
    missing required key and an unknown key are refused, naming the valid ones.
    """
    model = sorted(k for k in table if k in MODEL_KEYS)
    sheet = sorted(k for k in table if k in DATASHEET_KEYS)
    if model:
        raise ValueError(f"{where}:{section}: the datasheet keys {sheet} and the model keys {model} cannot be mixed: "
                         f"give the motor either by its datasheet ({', '.join(REQUIRED)}, ...) or by preset / "
                         "R, L, Km, J, B, Nr (docs/motors.md)")
    unknown = sorted(set(table) - set(DATASHEET_KEYS))
    if unknown:
        raise ValueError(f"{where}:{section}: unknown key(s) {unknown}; valid datasheet keys: {list(DATASHEET_KEYS)}")
    missing = [k for k in REQUIRED if k not in table]
    if missing:
        raise ValueError(f"{where}:{section}: the datasheet key(s) {missing} are missing; a motor by its datasheet "
                         f"needs {list(REQUIRED)} (units: docs/motors.md)")
    try:
        return from_datasheet(**table)
    except InputError as exc:
        raise exc.at(f"{where}:{section}.{exc.name}") from None
