r"""Building blocks of the baseline controllers: the Park transform, PI loops with anti-windup, the bus limit.

**Park transform** by the electrical angle :math:`N_r\theta` (the d axis along the rotor's magnet, so that
the torque of eq. (1) is :math:`K_m i_q`):

.. math::
    i_d = i_a\cos N_r\theta + i_b\sin N_r\theta,\qquad i_q = -i_a\sin N_r\theta + i_b\cos N_r\theta

and in these coordinates eq. (1) reads

.. math::
    L\dot i_d = v_d - R i_d + L N_r\omega i_q,\qquad
    L\dot i_q = v_q - R i_q - L N_r\omega i_d - K_m\omega,\qquad
    J\dot\omega = K_m i_q - B\omega - \tau.

**PI with pole-zero cancellation.** A PI :math:`k_p + k_i/s` on :math:`1/(Ls + R)` with
:math:`k_p = L\omega_c`, :math:`k_i = R\omega_c` cancels the winding's pole and leaves the closed loop
:math:`\omega_c/(s + \omega_c)`. Discretized forward (Euler) at the control period, sampled with a
zero-order hold, the current error decays by :math:`1 - \omega_c T_s` a period.

**Anti-windup by clamping.** The drive scales a voltage vector beyond the bus back onto it (direction kept,
:meth:`flatstep.loop.drive.Drive.saturate`); when the controller's own command is scaled, its integrators are
held for that period (conditional integration), so they do not wind up while the bus limits.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..plan.protocol import Plan
from ..validate import check_finite, check_positive
from .smc import MEASUREMENTS


def park(ia: ArrayLike, ib: ArrayLike,
         electrical_angle: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Phase currents (or voltages) to the rotor frame, at :math:`N_r\theta` = ``electrical_angle``.

    .. math:: i_d = i_a\cos N_r\theta + i_b\sin N_r\theta,\qquad i_q = -i_a\sin N_r\theta + i_b\cos N_r\theta
    """
    c, s = np.cos(electrical_angle), np.sin(electrical_angle)
    ia, ib = np.asarray(ia, dtype=float), np.asarray(ib, dtype=float)
    return ia * c + ib * s, -ia * s + ib * c


def inverse_park(d: ArrayLike, q: ArrayLike,
                 electrical_angle: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Rotor frame to phases, the inverse of :func:`park`.

    .. math:: a = d\cos N_r\theta - q\sin N_r\theta,\qquad b = d\sin N_r\theta + q\cos N_r\theta
    """
    c, s = np.cos(electrical_angle), np.sin(electrical_angle)
    d, q = np.asarray(d, dtype=float), np.asarray(q, dtype=float)
    return d * c - q * s, d * s + q * c


@dataclass(frozen=True)
class PIGains:
    """A PI law ``u = kp e + ki integral(e)``."""

    kp: float
    ki: float

    def __post_init__(self) -> None:
        for name in ("kp", "ki"):
            value = check_finite(name, getattr(self, name))
            if value < 0:
                raise ValueError(f"{name}={value!r} must be >= 0 (a PI gain)")
            object.__setattr__(self, name, value)

    @classmethod
    def current_loop(cls, motor: MotorParams, bandwidth: float) -> "PIGains":
        r"""Pole-zero cancellation on the winding: :math:`k_p = L\omega_c`, :math:`k_i = R\omega_c`."""
        wc = check_positive("bandwidth", bandwidth, unit=" rad/s")
        return cls(motor.L * wc, motor.R * wc)

    def as_dict(self) -> dict[str, float]:
        """The gains by name (``kp``, ``ki``)."""
        return asdict(self)


def pi_output(gains: PIGains, error: ArrayLike, integral: ArrayLike) -> NDArray[np.float64]:
    """The PI output ``kp e + integral`` (``integral`` already holds ``ki * integral(e)``)."""
    return gains.kp * np.asarray(error, dtype=float) + np.asarray(integral, dtype=float)


def pi_integrate(gains: PIGains, error: ArrayLike, integral: ArrayLike, Ts: float, hold: bool) -> NDArray[np.float64]:
    """The integral after one period: ``integral + ki Ts e``, or unchanged while ``hold`` (anti-windup)."""
    integral = np.asarray(integral, dtype=float)
    return integral if hold else integral + gains.ki * Ts * np.asarray(error, dtype=float)


def bus_scale(v: ArrayLike, v_limit: float) -> float:
    """The factor (<= 1) the drive applies to the voltage vector ``v`` so that ``max |v| <= v_limit``."""
    peak = float(np.max(np.abs(v)))
    return 1.0 if peak <= v_limit else v_limit / peak


def check_v_limit(v_limit: float) -> float:
    """Validate the bus voltage a controller saturates against (``inf``: no limit)."""
    v = float(v_limit)
    if not v > 0:
        raise ValueError(f"v_limit={v_limit!r} V must be > 0 (the bus voltage; inf for none)")
    return v


#: The gains type of a baseline (a frozen dataclass with ``as_dict()``).
GainsT = TypeVar("GainsT")


class BaselineController(Generic[GainsT]):
    """What every baseline shares.

    Its nominal model, the move, its gains, what it measures (as :class:`~flatstep.control.smc.FlatnessSMC`),
    its control period (``None``: continuous) and the bus its anti-windup knows.
    """

    def __init__(self, motor: MotorParams, plan: Plan, gains: GainsT, *, measurement: str,
                 control_period: float | None, v_limit: float) -> None:
        if measurement not in MEASUREMENTS:
            raise ValueError(f"measurement={measurement!r} is not a measurement mode; valid: {MEASUREMENTS}")
        self.motor, self.plan, self.gains, self.measurement = motor, plan, gains, measurement
        self.control_period = None if control_period is None else check_positive(
            "control_period", control_period, unit=" s")
        self.v_limit = check_v_limit(v_limit)

    def initial_state(self) -> Any:
        """The law's state at the start of a run: ``None`` for a static law (subclasses with state override)."""
        return None
