"""Rest positions of the motor for constant phase currents or voltages: eqs. (2)-(6), Proposition 2.1."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Optional

import numpy as np

from .motor import MotorParams


@dataclass(frozen=True)
class CriticalPoint:
    """A critical point ``(theta, omega = 0)`` of the zero dynamics (4) and its Jacobian (6)."""

    k: int
    theta: float
    eigenvalues: tuple[complex, complex]
    stable: bool

    @property
    def kind(self) -> str:
        """``"stable"`` or ``"saddle"``."""
        return "stable" if self.stable else "saddle"


def _currents(motor: MotorParams, ia: Optional[float], ib: Optional[float],
              va: Optional[float], vb: Optional[float]) -> tuple[float, float]:
    """The constant phase currents, given directly or through eq. (2) from constant voltages."""
    if (ia is None) == (va is None) or (ib is None) == (vb is None):
        raise ValueError("give the constant phase currents (ia, ib) or the constant voltages (va, vb), not both")
    # eq. (2): ia = va / R; the check above leaves exactly one of each pair given
    a = float(ia) if ia is not None else float(va / motor.R) if va is not None else math.nan
    b = float(ib) if ib is not None else float(vb / motor.R) if vb is not None else math.nan
    if not (math.isfinite(a) and math.isfinite(b)):
        raise ValueError(f"currents (ia, ib)=({a!r}, {b!r}) must be finite")
    if a == 0.0 and b == 0.0:
        raise ValueError("currents (ia, ib)=(0, 0) define no rest position: the rotor is free; "
                         "give a nonzero current vector")
    return a, b


def rest_positions(motor: MotorParams, ia: Optional[float] = None, ib: Optional[float] = None, *,
                   va: Optional[float] = None, vb: Optional[float] = None,
                   ks: Iterable[int] = range(-2, 3)) -> list[CriticalPoint]:
    r"""Critical points of the zero dynamics (4) for constant currents (or voltages), classified.

    With :math:`\bar\rho = |(\bar i_a, \bar i_b)|` and :math:`\bar\phi = \operatorname{atan2}(\bar i_a, \bar i_b)`,

    .. math::
        \bar\theta(k) = \frac{1}{N_r}\Big((2k+1)\frac{\pi}{2} - \bar\phi\Big),\qquad
        A_k = \begin{bmatrix} 0 & 1 \\ -K_m N_r \bar\rho \sin((2k+1)\pi/2)/J & -B/J \end{bmatrix}

    (eq. (6) with the :math:`1/J` the printed equation omits). Even ``k`` are stable (Proposition 2.1),
    odd ``k`` are saddles.
    """
    ia, ib = _currents(motor, ia, ib, va, vb)
    rho, phi = math.hypot(ia, ib), math.atan2(ia, ib)
    points = []
    for k in ks:
        angle = (2 * k + 1) * math.pi / 2
        jac = np.array([[0.0, 1.0], [-motor.Km * motor.Nr * rho * math.sin(angle) / motor.J, -motor.B / motor.J]])
        eig = np.linalg.eigvals(jac)
        points.append(CriticalPoint(k=int(k), theta=(angle - phi) / motor.Nr,
                                    eigenvalues=(complex(eig[0]), complex(eig[1])),
                                    stable=bool(np.all(eig.real < 0))))
    return points


def stable_angle(ia: float, ib: float, Nr: int, near: float = 0.0) -> float:
    r"""The stable rest angle for constant currents closest to ``near``.

    Stable equilibria satisfy :math:`N_r\theta + \phi = \pi/2 \pmod{2\pi}`, i.e. the rotor's electrical
    angle points along the current vector: :math:`N_r\bar\theta = \operatorname{atan2}(\bar i_b, \bar i_a)
    \pmod{2\pi}`. Eq. (2)'s ``arctan(ib/ia)`` cannot tell this from the saddle half a tooth pitch away.
    """
    if ia == 0.0 and ib == 0.0:
        raise ValueError("currents (0, 0) define no rest position; give a nonzero current vector")
    base = math.atan2(ib, ia) / Nr
    pitch = 2 * math.pi / Nr
    return base + pitch * round((near - base) / pitch)


def equilibrium_currents(theta: float, rho: float, Nr: int) -> tuple[float, float]:
    r"""Phase currents holding the rotor at rest at ``theta`` with current norm ``rho`` (eqs. (19)-(21)).

    .. math:: \bar i_a = \rho\cos N_r\theta,\qquad \bar i_b = \rho\sin N_r\theta
    """
    return rho * math.cos(Nr * theta), rho * math.sin(Nr * theta)
