"""Permanent-magnet stepper parameters and the a-b model of eq. (1).

State order everywhere in flatstep: ``x = (ia, ib, omega, theta)``; inputs ``v = (va, vb)``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Callable, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import check_count, check_finite, check_quantity
from .datasheet_math import parameters_from_datasheet

Load = Union[float, Callable[[NDArray[np.float64]], ArrayLike]]

STATE_NAMES = ("ia", "ib", "omega", "theta")
INPUT_NAMES = ("va", "vb")


@dataclass(frozen=True)
class MotorParams:
    """Parameters of the two-phase PM stepper of eq. (1).

    Parameters
    ----------
    R : float
        Phase resistance [ohm], > 0.
    L : float
        Phase inductance [H], > 0.
    Km : float
        Torque (and back-emf) constant [N m/A = V s/rad], > 0.
    J : float
        Rotor and load inertia [kg m^2], > 0.
    B : float
        Viscous friction [N m s/rad], >= 0.
    Nr : int
        Number of rotor teeth, a positive integer.
    """

    R: float
    L: float
    Km: float
    J: float
    B: float
    Nr: int

    def __post_init__(self) -> None:
        for name in ("R", "L", "Km", "J", "B"):  # ranges: flatstep.validate.ranges
            object.__setattr__(self, name, check_quantity(name, getattr(self, name)))
        # a whole float such as 50.0 is 50 teeth
        object.__setattr__(self, "Nr", check_count("Nr", self.Nr, why="number of rotor teeth"))

    @classmethod
    def preset(cls, name: str) -> "MotorParams":
        """Return a named parameter set; see :data:`PRESETS`."""
        try:
            return PRESETS[name]
        except (KeyError, TypeError):
            raise ValueError(f"unknown motor preset {name!r}; valid presets: {sorted(PRESETS)}") from None

    @classmethod
    def from_datasheet(cls, **datasheet: Any) -> "MotorParams":
        """The parameters from a datasheet's figures.

        :func:`flatstep.model.datasheet.from_datasheet` takes the same keywords and also returns what it assumed
        and how sure that is; both derive the parameters with
        :func:`flatstep.model.datasheet_math.parameters_from_datasheet`.
        """
        return cls(**parameters_from_datasheet(**datasheet).params)

    def replace(self, **changes: float) -> "MotorParams":
        """Return a copy with some parameters changed (validated again)."""
        unknown = set(changes) - set(asdict(self))
        if unknown:
            raise ValueError(f"unknown motor parameter(s) {sorted(unknown)}; valid: {list(asdict(self))}")
        return MotorParams(**{**asdict(self), **changes})

    def as_dict(self) -> dict[str, float]:
        """The parameters by name (``R``, ``L``, ``Km``, ``J``, ``B``, ``Nr``)."""
        return asdict(self)

    def c_params(self) -> dict[str, float]:
        """The fields of the C ``struct motor_params`` (csrc/motor.h) holding these parameters."""
        return dict(R=self.R, L=self.L, Km=self.Km, J=self.J, B=self.B, Nr=self.Nr)


def full_step(Nr: int) -> float:
    r"""One full step of a two-phase motor with ``Nr`` rotor teeth [rad]: :math:`\pi/(2N_r)`.

    A two-phase motor makes four full steps per electrical period :math:`2\pi/N_r`.
    """
    return math.pi / (2 * Nr)


#: Named parameter sets. ``paper``: the motor of the paper's Section 3. ``nema17``: a NEMA 17-size hybrid
#: stepper, Beckhoff AS1010-0000 (1.8 deg, 200 steps: Nr = 50; 1.0 A rated; R = 4.10 ohm; L = 9.50 mH;
#: rotor inertia 0.056 kg cm^2; standstill torque 0.38 N m; cogging torque 0.014-0.016 N m), technical
#: data at https://infosys.beckhoff.com/content/1033/as1000_ba/1426750347.html . Km is the standstill
#: torque over the current-vector norm with both phases at rated current, 0.38 / (sqrt(2) * 1.0 A); B is
#: not in the datasheet and is taken as 1e-4 N m s/rad, the paper's value: what
#: ``MotorParams.from_datasheet`` derives from examples/motors/beckhoff-as1010-0000.toml (docs/motors.md).
PRESETS: dict[str, MotorParams] = {
    "paper": MotorParams(R=8.4, L=0.010, Km=0.05, J=3.6e-6, B=1e-4, Nr=50),
    "nema17": MotorParams(R=4.10, L=9.50e-3, Km=0.38 / math.sqrt(2.0), J=5.6e-6, B=1e-4, Nr=50),
}


def load_function(load: Load) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """Normalise a load torque (a constant [N m] or a function of time) to a vectorized function."""
    if callable(load):
        def tau(t: NDArray[np.float64]) -> NDArray[np.float64]:
            try:
                value = np.asarray(load(t), dtype=float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"load torque function {load!r} returned a value that is not a number at t={t!r}: "
                                 f"{exc}") from None
            if not np.all(np.isfinite(value)):
                raise ValueError(f"load torque function returned a non-finite value {value!r} at t={t!r}")
            return np.broadcast_to(value, np.shape(t)) if np.ndim(value) == 0 else value
        return tau
    constant = check_finite("load_torque", load)
    return lambda t: np.full(np.shape(t), constant)


def rhs(t: ArrayLike, x: ArrayLike, v: ArrayLike, motor: MotorParams, load: Load = 0.0) -> NDArray[np.float64]:
    r"""Right-hand side of the a-b model, eq. (1); vectorized over trailing axes.

    .. math::
        L\dot i_a = v_a - R i_a + K_m\omega\sin N_r\theta,\quad
        L\dot i_b = v_b - R i_b - K_m\omega\cos N_r\theta,\\
        J\dot\omega = K_m(-i_a\sin N_r\theta + i_b\cos N_r\theta) - B\omega - \tau,\quad
        \dot\theta = \omega
    """
    ia, ib, omega, theta = np.asarray(x, dtype=float)
    va, vb = np.asarray(v, dtype=float)
    tau = load_function(load)(np.asarray(t, dtype=float))
    s, c = np.sin(motor.Nr * theta), np.cos(motor.Nr * theta)
    return np.array([
        (va - motor.R * ia + motor.Km * omega * s) / motor.L,
        (vb - motor.R * ib - motor.Km * omega * c) / motor.L,
        acceleration(x, motor, tau),
        omega + 0.0 * theta,
    ])


def torque(x: ArrayLike, motor: MotorParams) -> NDArray[np.float64]:
    """Electromagnetic torque ``Km (ib cos Nr theta - ia sin Nr theta)`` [N m]."""
    ia, ib, _, theta = np.asarray(x, dtype=float)
    return motor.Km * (ib * np.cos(motor.Nr * theta) - ia * np.sin(motor.Nr * theta))


def acceleration(x: ArrayLike, motor: MotorParams, load: ArrayLike = 0.0) -> NDArray[np.float64]:
    r"""Rotor acceleration of eq. (1) [rad/s^2] under the load torque ``load``.

    ``load`` [N m] is a constant or an array like the state's trailing axes.

    .. math::
        \dot\omega = \big(K_m(i_b\cos N_r\theta - i_a\sin N_r\theta) - B\omega - \tau\big) / J
    """
    omega = np.asarray(x, dtype=float)[2]
    return (torque(x, motor) - motor.B * omega - load) / motor.J
