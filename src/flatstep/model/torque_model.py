r"""A controller's model of the torques eq. (1) leaves out: detent, Coulomb friction, a known load.

Every one keeps the model flat: they depend on the flat outputs and their derivatives only. With them the
shaft equation reads

.. math::
    J\ddot\theta = K_m i_q - B\dot\theta - E(t, \theta, \dot\theta),\qquad
    E = \tau(t) + T_d\sin(hN_r\theta + \varphi_d) + T_c\tanh(\dot\theta/\omega_s),

    \dot E = \dot\tau(t) + T_d hN_r\cos(hN_r\theta + \varphi_d)\,\dot\theta
             + \frac{T_c}{\omega_s}\big(1 - \tanh^2(\dot\theta/\omega_s)\big)\ddot\theta,

    \tau(t) = \tau_0 + \Delta\tau\,\psi(t, t_{\tau 0}, t_{\tau f})

(:math:`\psi` the paper's polynomial, eq. (17)). The detent and Coulomb terms are those of
:class:`~flatstep.model.plant.PlantEffects` (whose detent has phase 0); :meth:`TorqueModel.of_plant` builds the
model that knows the simulated plant's. With every amplitude 0 the model is eq. (1) itself: :math:`E = \dot E = 0`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import check_finite, check_integer, check_nonnegative, check_positive
from .plant import Plant
from .psi import psi

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TorqueModel:
    r"""The torques a controller knows beyond eq. (1) (module docstring); all zero by default.

    Parameters
    ----------
    detent_torque : float
        :math:`T_d` [N m], >= 0.
    detent_harmonic : int
        :math:`h`, a positive integer (4 for a two-phase hybrid stepper).
    detent_phase : float
        :math:`\varphi_d` [rad] of :math:`\sin(hN_r\theta + \varphi_d)`.
    coulomb_torque : float
        :math:`T_c` [N m], >= 0.
    coulomb_speed : float
        :math:`\omega_s` [rad/s] of the smooth sign, > 0.
    load : float
        :math:`\tau_0` [N m], the constant part of the load.
    load_step : float
        :math:`\Delta\tau` [N m], a load change along :math:`\psi` from ``load_t0`` to ``load_tf``.
    load_t0, load_tf : float
        Start and end [s] of the load change, ``load_tf > load_t0``.
    """

    detent_torque: float = 0.0
    detent_harmonic: int = 4
    detent_phase: float = 0.0
    coulomb_torque: float = 0.0
    coulomb_speed: float = 0.01
    load: float = 0.0
    load_step: float = 0.0
    load_t0: float = 0.0
    load_tf: float = 1.0

    def __post_init__(self) -> None:
        for name in ("detent_torque", "coulomb_torque"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name), unit=" N m",
                                                             why="an amplitude"))
        object.__setattr__(self, "detent_harmonic", check_integer("detent_harmonic", self.detent_harmonic))
        object.__setattr__(self, "coulomb_speed", check_positive("coulomb_speed", self.coulomb_speed, unit=" rad/s"))
        for name in ("detent_phase", "load", "load_step", "load_t0", "load_tf"):
            object.__setattr__(self, name, check_finite(name, getattr(self, name)))
        if not self.load_tf > self.load_t0:
            raise ValueError(f"load_tf={self.load_tf!r} s must be greater than load_t0={self.load_t0!r} s "
                             "(the load change runs from load_t0 to load_tf)")

    @classmethod
    def of_plant(cls, plant: Plant, detent_phase: float = 0.0) -> "TorqueModel":
        """The model that knows the plant's detent, Coulomb friction and constant load exactly.

        Iron loss is not modelled; a load that is a function of time is refused.
        """
        if plant.constant_load is None:
            raise ValueError(f"Plant.load={plant.load!r} is a function: a TorqueModel knows a constant load "
                             "and a psi-shaped change (load, load_step, load_t0, load_tf)")
        e = plant.effects
        if e is None:
            return cls(load=plant.constant_load, detent_phase=detent_phase)
        return cls(detent_torque=e.detent_torque, detent_harmonic=e.detent_harmonic, detent_phase=detent_phase,
                   coulomb_torque=e.coulomb_torque, coulomb_speed=e.coulomb_speed, load=plant.constant_load)

    @property
    def active(self) -> bool:
        r"""Whether any torque is modelled (``False``: :math:`E = \dot E = 0`)."""
        return bool(self.detent_torque or self.coulomb_torque or self.load or self.load_step)

    def load_torque(self, t: ArrayLike) -> tuple[Array, Array]:
        r"""The load :math:`\tau(t)` and its rate :math:`\dot\tau(t)` [N m, N m/s]."""
        t = np.asarray(t, dtype=float)
        if not self.load_step:
            return np.full(t.shape, self.load), np.zeros(t.shape)
        return (self.load + self.load_step * psi(t, self.load_t0, self.load_tf),
                self.load_step * psi(t, self.load_t0, self.load_tf, 1))

    def torque(self, t: ArrayLike, theta: ArrayLike, dtheta: ArrayLike, Nr: int) -> Array:
        r""":math:`E(t, \theta, \dot\theta)` [N m] (module docstring), vectorized."""
        theta, dtheta = np.asarray(theta, dtype=float), np.asarray(dtheta, dtype=float)
        tau, _ = self.load_torque(t)
        return (tau + self.detent_torque * np.sin(self.detent_harmonic * Nr * theta + self.detent_phase)
                + self.coulomb_torque * np.tanh(dtheta / self.coulomb_speed))

    def torque_rate(self, t: ArrayLike, theta: ArrayLike, dtheta: ArrayLike, ddtheta: ArrayLike, Nr: int) -> Array:
        r""":math:`\dot E` [N m/s] along a motion with angle, speed and acceleration given (module docstring)."""
        theta, dtheta, ddtheta = (np.asarray(a, dtype=float) for a in (theta, dtheta, ddtheta))
        _, dtau = self.load_torque(t)
        h_Nr = self.detent_harmonic * Nr
        th = np.tanh(dtheta / self.coulomb_speed)
        return (dtau + self.detent_torque * h_Nr * np.cos(h_Nr * theta + self.detent_phase) * dtheta
                + self.coulomb_torque / self.coulomb_speed * (1.0 - th * th) * ddtheta)

    def as_dict(self) -> dict[str, Any]:
        """The fields by name: a result's metadata and the C ``struct torque_model``."""
        return asdict(self)


#: No torque beyond eq. (1).
NO_TORQUES = TorqueModel()
