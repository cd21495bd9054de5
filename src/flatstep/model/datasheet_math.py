r"""The arithmetic from a datasheet's figures to the parameters of eq. (1), checked and named by datasheet key.

:math:`N_r` from the step angle (:func:`rotor_teeth`), :math:`K_m` and the rated current-vector norm
:math:`\rho_r` from the holding torque and the rated current (:func:`torque_constant`), :math:`B` given or
:data:`B_DEFAULT`; :func:`parameters_from_datasheet` does all of it and returns plain numbers. It builds
no :class:`~flatstep.model.motor.MotorParams`, so that both ``MotorParams.from_datasheet`` and
:func:`flatstep.model.datasheet.from_datasheet` (which adds the assumptions and their uncertainty) use it without
importing each other. The derivation with its equations: docs/motors.md.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple, Optional

from ..validate import InputError, check_choice, check_finite, check_integer, check_quantity

#: The datasheet keys of a ``[motor]`` table and their units; the first six are required.
DATASHEET_KEYS: dict[str, str] = {
    "step_angle": "deg", "rated_current": "A", "holding_torque": "N m", "resistance": "ohm", "inductance": "H",
    "rotor_inertia": "kg m^2", "detent_torque": "N m", "viscous_friction": "N m s/rad", "current": "",
    "holding_torque_phases": "", "holding_torque_rating": "", "maker": "", "part": "", "frame": "", "source": "",
}
#: Keys that only describe the motor (text): kept, not used by the derivation.
DESCRIPTION_KEYS = ("maker", "part", "frame", "source")

#: The viscous friction taken when the datasheet gives none [N m s/rad]: the paper's motor (Section 3,
#: B = 1e-4 N m s/rad beside Km = 0.05 N m/A and J = 3.6e-6 kg m^2, a small hybrid stepper), as flatstep's
#: ``nema17`` preset takes it.
B_DEFAULT = 1e-4


class Derived(NamedTuple):
    """What :func:`parameters_from_datasheet` computes from a datasheet's figures.

    Parameters
    ----------
    params : dict
        ``R``, ``L``, ``Km``, ``J``, ``B``, ``Nr`` of eq. (1), each checked against its range.
    rated_rho : float
        The current-vector norm at the rated copper loss [A].
    figures : dict
        The figures as given, by datasheet key (SI units), with the conventions taken.
    given : dict
        The conventions as the caller gave them (``None``: not given): ``current``, ``holding_torque_phases``,
        ``holding_torque_rating``.
    defaults : dict
        The keys not given and the values taken for them.
    """

    params: dict[str, Any]
    rated_rho: float
    figures: dict[str, Any]
    given: dict[str, Any]
    defaults: dict[str, Any]


def rotor_teeth(step_angle: float, *, name: str = "step_angle") -> int:
    r"""The number of rotor teeth of a two-phase hybrid stepper of full step ``step_angle`` [deg].

    A two-phase motor makes four full steps per rotor tooth pitch (one electrical period, :math:`360/N_r` deg):

    .. math::
        N_r = \frac{360}{4\,\Delta\theta_{step}} \qquad (1.8^\circ \to 50,\ 0.9^\circ \to 100)
    """
    angle = check_finite(name, step_angle)
    if not 0.0 < angle <= 90.0:
        raise InputError(name, step_angle, f"{name}={angle!r} deg is out of range: a full step of a two-phase motor "
                                           "is in (0, 90] deg (1.8 for 200 steps a turn)")
    teeth = 90.0 / angle
    if abs(teeth - round(teeth)) > 1e-6 * teeth:
        raise InputError(name, step_angle, f"{name}={angle!r} deg gives Nr = 90/{angle:g} = {teeth:.6g} rotor teeth, "
                                           "not a whole number: a two-phase hybrid stepper has a full step of "
                                           "90/Nr deg (1.8 deg for Nr = 50, 0.9 deg for Nr = 100)")
    return check_integer(name, round(teeth), low=1, high=1000, why="Nr = 90/step_angle rotor teeth")


def torque_constant(holding_torque: float, rated_current: float, *, current: str = "rms",
                    holding_torque_phases: int = 2) -> tuple[float, float]:
    r"""The torque constant :math:`K_m` [N m/A] and the rated current-vector norm :math:`\rho_r` [A].

    The torque of eq. (1) is :math:`K_m (i_b\cos N_r\theta - i_a\sin N_r\theta)`: with both phases at a DC
    current :math:`I` its peak over :math:`\theta` is :math:`\sqrt 2 K_m I`, with one phase :math:`K_m I`; so a
    one-phase holding torque is :math:`1/\sqrt 2` of the two-phase one. A per-phase rating (``current = "rms"``: the
    DC current of a full-step drive, the RMS of a sine drive of the same copper loss :math:`2RI^2`) gives
    :math:`\rho_r = \sqrt 2 I`; a rating of the phase current's peak (``"peak"``) gives :math:`\rho_r = I`:

    .. math::
        T_2 = \begin{cases} T_{hold} & \text{two phases} \\ \sqrt 2\,T_{hold} & \text{one phase}\end{cases},\quad
        \rho_r = \begin{cases} \sqrt 2\,I_{rated} & \text{rms} \\ I_{rated} & \text{peak}\end{cases},\quad
        K_m = \frac{T_2}{\rho_r}
    """
    check_choice("current", current, ("rms", "peak"))
    phases = check_integer("holding_torque_phases", holding_torque_phases, low=1, high=2,
                           why="the holding torque is measured with one or two phases energised")
    two_phase = holding_torque * (math.sqrt(2.0) if phases == 1 else 1.0)
    rho = rated_current * (math.sqrt(2.0) if current == "rms" else 1.0)
    return two_phase / rho, rho


def parameters_from_datasheet(*, step_angle: float, rated_current: float, holding_torque: float,
                              resistance: float, inductance: float, rotor_inertia: float,
                              detent_torque: Optional[float] = None, viscous_friction: Optional[float] = None,
                              current: Optional[str] = None, holding_torque_phases: Optional[int] = None,
                              holding_torque_rating: Optional[str] = None, **description: str) -> Derived:
    r"""The parameters of eq. (1) from a datasheet's figures, each checked, an error naming the datasheet key.

    The keywords are those of :func:`flatstep.model.datasheet.from_datasheet`.

    .. math::
        K_m = \frac{T_2}{\rho_r},\quad N_r = \frac{90}{\Delta\theta_{step}},\quad R, L, J \text{ as given},\quad
        B = B_{datasheet} \text{ or } 10^{-4}\ \mathrm{N\,m\,s/rad}
    """
    for key in description:
        if key not in DESCRIPTION_KEYS:
            raise TypeError(f"from_datasheet() got an unexpected keyword argument {key!r}; "
                            f"valid: {list(DATASHEET_KEYS)}")
        if not isinstance(description[key], str):
            raise InputError(key, description[key], f"{key}={description[key]!r} must be a string")
    given = {"current": current, "holding_torque_phases": holding_torque_phases,
             "holding_torque_rating": holding_torque_rating}
    current = "rms" if current is None else current
    phases = 2 if holding_torque_phases is None else holding_torque_phases
    rating = "typical" if holding_torque_rating is None else check_choice(
        "holding_torque_rating", holding_torque_rating, ("typical", "minimum"))
    amps = check_quantity("current", rated_current, as_name="rated_current")
    torque = _positive_torque("holding_torque", holding_torque)
    Km, rho = torque_constant(torque, amps, current=current, holding_torque_phases=phases)
    detent = None if detent_torque is None else check_quantity("torque_amplitude", detent_torque,
                                                                as_name="detent_torque")
    B = B_DEFAULT if viscous_friction is None else check_quantity("B", viscous_friction, as_name="viscous_friction")
    params = dict(R=_named("R", resistance, "resistance"), L=_named("L", inductance, "inductance"),
                  Km=_named("Km", Km, "holding_torque"), J=_named("J", rotor_inertia, "rotor_inertia"),
                  B=B, Nr=rotor_teeth(step_angle))
    figures = {"step_angle": float(step_angle), "rated_current": amps, "holding_torque": torque,
               "resistance": params["R"], "inductance": params["L"], "rotor_inertia": params["J"],
               "detent_torque": detent, "viscous_friction": viscous_friction, "current": current,
               "holding_torque_phases": phases, "holding_torque_rating": rating, **description}
    taken = {"current": current, "holding_torque_phases": phases, "holding_torque_rating": rating,
             "viscous_friction": B}
    defaults = {k: v for k, v in taken.items() if {**given, "viscous_friction": viscous_friction}[k] is None}
    return Derived(params, rho, figures, given, defaults)


def _positive_torque(name: str, value: Any) -> float:
    """A torque in (0, 1000] N m, or an InputError naming ``name``."""
    out = check_quantity("torque_amplitude", value, as_name=name)
    if out <= 0.0:
        raise InputError(name, value, f"{name}={out!r} N m must be > 0 (a motor that holds no torque has no Km)")
    return out


def _named(quantity: str, value: Any, key: str) -> float:
    """``value`` checked as ``quantity`` (its range), the error naming the datasheet key ``key``."""
    try:
        return check_quantity(quantity, value, as_name=key)
    except InputError as exc:
        if key == "holding_torque":  # Km out of range: say which figures made it
            raise InputError(key, value, f"the torque constant Km = {value!r} N m/A derived from holding_torque "
                                         f"and rated_current is out of range: {exc}") from None
        raise
