r"""The paper's flatness + sliding-mode law, eqs. (12)-(14), corrected, with the boundary layer of Section 3.

.. math::
    s_1 = \rho - \rho^*,\qquad s_2 = \ddot e + \alpha_2\dot e + \alpha_1 e,\quad e = \theta - \theta^*\\
    \Gamma_1 = \dot\rho^* - W_1\frac{s_1}{|s_1| + \epsilon_1},\qquad
    \Gamma_2 = \theta^{*(3)} - \alpha_2\ddot e - \alpha_1\dot e - W_2\frac{s_2}{|s_2| + \epsilon_2}

and the voltages are the flat inverse (eq. 9) with :math:`\dot\rho \to \Gamma_1`,
:math:`\theta^{(3)} \to \Gamma_2`, evaluated at the measured state (:func:`flatstep.flat.flat_voltages`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..flat import flat_voltages, polar
from ..motor import MotorParams, check_finite, check_positive
from ..plan import RestToRest

MEASUREMENTS = ("ideal", "model", "observer")


@dataclass(frozen=True)
class SMCGains:
    """Design constants of the controller; defaults are the paper's (Section 3)."""

    W1: float = 100.0
    W2: float = 100.0
    eps1: float = 0.005
    eps2: float = 0.005
    xi: float = 0.8
    wn: float = 10.0

    def __post_init__(self) -> None:
        for name in ("W1", "W2", "eps1", "eps2", "wn"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        xi = check_finite("xi", self.xi)
        if xi <= 0:
            raise ValueError(f"xi={xi!r} must be > 0 for the error dynamics e'' + 2 xi wn e' + wn^2 e = 0 to be stable")
        object.__setattr__(self, "xi", xi)

    @property
    def alpha1(self) -> float:
        """:math:`\\alpha_1 = \\omega_n^2`."""
        return self.wn**2

    @property
    def alpha2(self) -> float:
        """:math:`\\alpha_2 = 2\\xi\\omega_n`."""
        return 2 * self.xi * self.wn

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


class FlatnessSMC:
    """Flatness-based sliding-mode controller tracking a :class:`~flatstep.plan.RestToRest` plan.

    Parameters
    ----------
    motor : the controller's model of the motor (may differ from the plant's).
    plan : the planned flat-output trajectory.
    gains : :class:`SMCGains`.
    measurement : where theta'' comes from. ``"ideal"``: the true acceleration, passed by the simulator
        (the paper's assumption); ``"model"``: computed from the measured state by the zero-load model,
        ``J theta'' = Km (ib cos Nr theta - ia sin Nr theta) - B omega``; ``"observer"``: the estimate of a
        :class:`~flatstep.observers.Observer`, passed by the simulator like the ideal one.
    """

    def __init__(self, motor: MotorParams, plan: RestToRest, gains: SMCGains = SMCGains(),
                 measurement: str = "ideal"):
        if measurement not in MEASUREMENTS:
            raise ValueError(f"measurement={measurement!r} is not a measurement mode; valid: {MEASUREMENTS}")
        self.motor, self.plan, self.gains, self.measurement = motor, plan, gains, measurement

    def acceleration(self, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """theta'' as the controller sees it: the given value in ``ideal`` mode, the zero-load model otherwise."""
        if self.measurement != "model":
            if ddtheta is None:
                raise ValueError(f"measurement={self.measurement!r} needs the acceleration ddtheta; "
                                 "use measurement='model' to compute it from the state")
            return np.asarray(ddtheta, dtype=float)
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        m = self.motor
        return (m.Km * (ib * np.cos(m.Nr * theta) - ia * np.sin(m.Nr * theta)) - m.B * omega) / m.J

    def sliding_variables(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None):
        """Return ``(s1, s2)`` of eq. (12) at times ``t`` for states ``x`` (vectorized)."""
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        ref = self.plan.flag(t)
        acc = self.acceleration(x, ddtheta)
        g = self.gains
        return (np.hypot(ia, ib) - ref.rho,
                acc - ref.ddtheta + g.alpha2 * (omega - ref.dtheta) + g.alpha1 * (theta - ref.theta))

    def voltages(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """Phase voltages (va, vb) of eqs. (13)-(14), vectorized over time."""
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        m, g = self.motor, self.gains
        ref = self.plan.flag(t)
        rho, phi = polar(ia, ib)
        acc = self.acceleration(x, ddtheta)
        e, de, dde = theta - ref.theta, omega - ref.dtheta, acc - ref.ddtheta
        s1 = rho - ref.rho
        s2 = dde + g.alpha2 * de + g.alpha1 * e
        gamma1 = ref.drho - g.W1 * s1 / (np.abs(s1) + g.eps1)
        gamma2 = ref.dddtheta - g.alpha2 * dde - g.alpha1 * de - g.W2 * s2 / (np.abs(s2) + g.eps2)
        return flat_voltages(m, rho, gamma1, theta, omega, acc, gamma2, phi, m.J * acc + m.B * omega)

    def step(self, state: None, measurement: ArrayLike, t: float) -> tuple[NDArray[np.float64], None]:
        """Controller step ``(state, measurement, t) -> (voltages, new state)``; this law is static.

        ``measurement`` is ``(ia, ib, omega, theta, ddtheta)``; ``ddtheta`` is not read in ``model`` mode.
        """
        y = np.asarray(measurement, dtype=float)
        return self.voltages(t, y[:4], None if self.measurement == "model" else y[4]), state
