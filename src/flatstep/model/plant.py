r"""Plant effects the paper's model leaves out: detent torque, Coulomb friction, iron loss.

They act on the simulated plant only; every controller (and observer) keeps its nominal model of eq. (1).
The torque they add to the rotor, with the sign conventions of eq. (1) (:math:`e_a = -K_m\omega\sin N_r\theta`,
:math:`e_b = K_m\omega\cos N_r\theta`):

.. math::
    J\dot\omega = K_m(i_b\cos N_r\theta - i_a\sin N_r\theta) - B\omega - \tau
                  \underbrace{- T_d\sin(4N_r\theta)}_{\text{detent}}
                  \underbrace{- T_c\tanh(\omega/\omega_s)}_{\text{Coulomb}}
                  \underbrace{- \frac{K_m^2}{R_m}\omega}_{\text{iron loss}}

The detent and iron-loss terms are those of the MathWorks Simscape Electrical *Stepper Motor* block
(https://mathworks.com/help/sps/ref/steppermotor.html): its electrical torque is
:math:`K_m(i_b - e_b/R_m)\cos N_r\theta - K_m(i_a - e_a/R_m)\sin N_r\theta - T_d\sin 4N_r\theta`, i.e. the
magnetizing resistance :math:`R_m` carries the part :math:`e/R_m` of the winding current that makes no
torque; with the back-emfs above that is the drag :math:`K_m^2\omega/R_m` and the iron-loss power
:math:`K_m^2\omega^2/R_m`. The phase-current equations are unchanged. The Coulomb term is the usual smooth
sign, :math:`\tanh(\omega/\omega_s)` with a small speed :math:`\omega_s`, so that the fixed-step integrator
sees a Lipschitz right-hand side (keep :math:`T_c h/(J\omega_s)` below about 2 for an RK4 step ``h``).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import check_count, check_quantity
from .motor import Load, MotorParams, rhs


@dataclass(frozen=True)
class PlantEffects:
    r"""Detent torque, Coulomb friction and iron loss of the simulated plant.

    Parameters
    ----------
    detent_torque : float
        Amplitude :math:`T_d` [N m] of :math:`-T_d\sin(hN_r\theta)`, >= 0.
    coulomb_torque : float
        Coulomb friction :math:`T_c` [N m], >= 0.
    coulomb_speed : float
        :math:`\omega_s` [rad/s] of the smooth sign :math:`\tanh(\omega/\omega_s)`, > 0.
    magnetizing_resistance : float, optional
        :math:`R_m` [ohm] > 0, or ``None`` for no iron loss.
    detent_harmonic : int
        :math:`h`, the detent's harmonic of the electrical angle, a positive integer (4 for a two-phase hybrid
        or PM stepper: four detent periods per electrical period).
    """

    detent_torque: float = 0.0
    coulomb_torque: float = 0.0
    coulomb_speed: float = 0.01
    magnetizing_resistance: Optional[float] = None
    detent_harmonic: int = 4

    def __post_init__(self) -> None:
        for name in ("detent_torque", "coulomb_torque"):
            object.__setattr__(self, name, check_quantity("torque_amplitude", getattr(self, name), as_name=name))
        object.__setattr__(self, "coulomb_speed", check_quantity("coulomb_speed", self.coulomb_speed))
        object.__setattr__(self, "detent_harmonic", check_count("detent_harmonic", self.detent_harmonic))
        if self.magnetizing_resistance is not None:
            object.__setattr__(self, "magnetizing_resistance",
                               check_quantity("magnetizing_resistance", self.magnetizing_resistance))

    @property
    def active(self) -> bool:
        """Whether any effect is present."""
        return self.detent_torque > 0 or self.coulomb_torque > 0 or self.magnetizing_resistance is not None

    def torque(self, omega: ArrayLike, theta: ArrayLike, motor: MotorParams) -> NDArray[np.float64]:
        r"""The torque the effects add to the rotor [N m].

        .. math:: -T_d\sin hN_r\theta - T_c\tanh(\omega/\omega_s) - K_m^2\omega/R_m
        """
        omega, theta = np.asarray(omega, dtype=float), np.asarray(theta, dtype=float)
        out = (-self.detent_torque * np.sin(self.detent_harmonic * motor.Nr * theta)
               - self.coulomb_torque * np.tanh(omega / self.coulomb_speed))
        if self.magnetizing_resistance is not None:
            out = out - motor.Km**2 / self.magnetizing_resistance * omega
        return out

    def iron_loss_power(self, omega: ArrayLike, motor: MotorParams) -> NDArray[np.float64]:
        r"""Power dissipated in the magnetizing resistance, :math:`K_m^2\omega^2/R_m` [W] (0 without it)."""
        omega = np.asarray(omega, dtype=float)
        if self.magnetizing_resistance is None:
            return np.zeros_like(omega)
        return motor.Km**2 * omega**2 / self.magnetizing_resistance

    def as_dict(self) -> dict[str, Any]:
        """The effects' fields by name, for a result's metadata."""
        return asdict(self)

    def c_effects(self) -> dict[str, float]:
        """The fields of the C ``struct plant_effects`` (csrc/plant.h): no iron loss is ``magnetizing_resistance`` 0."""
        return dict(detent_torque=self.detent_torque, detent_harmonic=self.detent_harmonic,
                    coulomb_torque=self.coulomb_torque, coulomb_speed=self.coulomb_speed,
                    magnetizing_resistance=self.magnetizing_resistance or 0.0)


NO_EFFECTS = PlantEffects()


def plant_rhs(x: ArrayLike, v: ArrayLike, motor: MotorParams, load: float = 0.0,
              effects: Optional[PlantEffects] = None) -> NDArray[np.float64]:
    """Eq. (1) plus the effects' torque on the speed equation (vectorized like :func:`flatstep.model.motor.rhs`).

    ``load`` is a constant load torque [N m].
    """
    dx = rhs(0.0, x, v, motor, load)
    if effects is not None and effects.active:
        x = np.asarray(x, dtype=float)
        dx[2] = dx[2] + effects.torque(x[2], x[3], motor) / motor.J
    return dx


def plant_acceleration(x: ArrayLike, motor: MotorParams, load: float = 0.0,
                       effects: Optional[PlantEffects] = None) -> NDArray[np.float64]:
    r"""The true :math:`\ddot\theta` of the plant in state ``x`` (what the ``ideal`` measurement reads)."""
    return plant_rhs(x, np.zeros(2), motor, load, effects)[2]


@dataclass(frozen=True)
class Plant:
    """The simulated plant of a run: its motor, the effects eq. (1) leaves out, and its load.

    Parameters
    ----------
    motor : MotorParams
        The simulated motor (a controller keeps its own nominal model, which may differ).
    effects : PlantEffects, optional
        Detent torque, Coulomb friction and iron loss; ``None`` (or all zero) for none.
    load : float or callable
        Load torque [N m], a constant or a function of time (a function runs on the scipy engine only).
    """

    motor: MotorParams
    effects: Optional[PlantEffects] = None
    load: Load = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.motor, MotorParams):
            raise ValueError(f"Plant.motor={self.motor!r} is not a MotorParams")
        if self.effects is not None and not isinstance(self.effects, PlantEffects):
            raise ValueError(f"Plant.effects={self.effects!r} is not a PlantEffects (or None)")
        if self.effects is not None and not self.effects.active:
            object.__setattr__(self, "effects", None)
        if not callable(self.load):  # a function is checked where it is called
            object.__setattr__(self, "load", check_quantity("load", self.load))

    @property
    def constant_load(self) -> Optional[float]:
        """The load torque [N m] when it is a constant, else ``None``."""
        return None if callable(self.load) else float(self.load)

    def acceleration(self, x: ArrayLike, t: ArrayLike = 0.0) -> NDArray[np.float64]:
        r"""The plant's true :math:`\ddot\theta` in states ``x`` at times ``t`` (the ``ideal`` measurement)."""
        x = np.asarray(x, dtype=float)
        acc = rhs(t, x, np.zeros(2), self.motor, self.load)[2]
        return acc + self.effects.torque(x[2], x[3], self.motor) / self.motor.J if self.effects else acc

    def as_dict(self) -> dict[str, Any]:
        """The motor, the effects and (when constant) the load, for a result's metadata."""
        return {"motor": self.motor.as_dict(), "effects": self.effects.as_dict() if self.effects else None,
                "load": self.constant_load if not callable(self.load) else repr(self.load)}
