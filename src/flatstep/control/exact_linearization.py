r"""Exact feedback linearization in d-q (Zribi and Chiasson, 1991) with linear pole placement.

M. Zribi and J. Chiasson, "Position control of a PM stepper motor by exact linearization", IEEE Trans.
Automatic Control 36(5), 1991: in the rotor frame (:mod:`flatstep.control.loops`) the outputs
:math:`\theta` (relative degree 3) and :math:`i_d` (relative degree 1) linearize the model exactly. With
:math:`J\theta^{(3)} = K_m\dot i_q - B\ddot\theta` for a constant load, the law

.. math::
    v_q = R i_q + L N_r\omega i_d + K_m\omega + \frac{L}{K_m}\big(J u + B\ddot\theta\big),\qquad
    v_d = R i_d - L N_r\omega i_q - L k_d i_d

gives :math:`\theta^{(3)} = u` and :math:`\dot i_d = -k_d i_d`, and the tracking law

.. math:: u = \theta^{*(3)} - k_2\ddot e - k_1\dot e - k_0 e,\qquad e = \theta - \theta^*

places the error's poles at the roots of :math:`s^3 + k_2 s^2 + k_1 s + k_0`. :math:`\ddot\theta` is read
as the flatness controller reads it (``measurement``): the observer's estimate, the truth, or the
zero-load model :math:`(K_m i_q - B\omega)/J`, which is Zribi and Chiasson's state feedback.

**Tuning.** :math:`i_d` pole at :math:`\lambda = 0.3/T_s`; the angle's poles at
:math:`(s + \lambda)(s^2 + 2\xi\omega_n s + \omega_n^2)`, :math:`\omega_n = \lambda/4`, :math:`\xi = 0.9`:
exactly the dynamics the sliding controller imposes inside its boundary layer (:math:`\dot s_2 = -\lambda s_2`
on :math:`s_2 = \ddot e + 2\xi\omega_n\dot e + \omega_n^2 e`), so the two differ only in what they do
outside the layer, in keeping :math:`i_d = 0` instead of :math:`\rho = \rho^*`, and in their coordinates.

**Known torques** (``torques``, the ``feedforward`` option, as the flatness laws take them): with
:math:`J\ddot\theta = K_m i_q - B\dot\theta - E` the law adds :math:`L\dot E/K_m` to :math:`v_q`, and the ``model``
acceleration is :math:`(K_m i_q - B\omega - E)/J`; the drive's observer shares them. None by default (the law
above bit for bit).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.protocol import Plan
from ..validate import check_finite, check_positive
from .build import XI
from .loops import BaselineController, inverse_park, park

if TYPE_CHECKING:
    from .build import BuildContext
    from .spec import ControllerSpec


@dataclass(frozen=True)
class LinearizationGains:
    r"""Poles of the linearized loops [rad/s].

    The angle error's :math:`(s + p_3)(s^2 + 2\xi\omega_n s + \omega_n^2)` and the d current's :math:`s + p_d`.
    """

    wn: float
    xi: float
    p3: float
    pd: float

    def __post_init__(self) -> None:
        for name in ("wn", "p3", "pd"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name), unit=" rad/s"))
        xi = check_finite("xi", self.xi)
        if xi <= 0:
            raise ValueError(f"xi={xi!r} must be > 0 for stable error poles")
        object.__setattr__(self, "xi", xi)

    @property
    def k(self) -> tuple[float, float, float]:
        """``(k0, k1, k2)`` of :math:`s^3 + k_2 s^2 + k_1 s + k_0`."""
        a1, a2 = self.wn**2, 2 * self.xi * self.wn
        return self.p3 * a1, a1 + self.p3 * a2, a2 + self.p3

    def as_dict(self) -> dict[str, float]:
        """The poles and the gains ``k0, k1, k2`` they give, for JSON."""
        k0, k1, k2 = self.k
        return {**asdict(self), "k0": k0, "k1": k1, "k2": k2}


class ExactLinearization(BaselineController[LinearizationGains]):
    """Zribi-Chiasson exact linearization in d-q with pole placement on theta and i_d.

    Parameters
    ----------
    motor : MotorParams
        The controller's nominal model.
    plan : Plan
        The move (its theta*, theta*', theta*'', theta*''').
    gains : LinearizationGains
        The poles of the linearized loops.
    measurement : str
        Where theta'' comes from, as for :class:`~flatstep.control.smc.FlatnessSMC`.
    control_period : float, optional
        Accepted for a uniform interface; the law is static.
    v_limit : float
        The bus voltage [V]; the C twin only flags saturation against it (the law is static, no windup).
    torques : TorqueModel
        The torques the law knows beyond eq. (1) (module docstring; default none).
    """

    #: The C twin: csrc/exact_linearization.h.
    c_name = "exact_linearization"

    def __init__(self, motor: MotorParams, plan: Plan, gains: LinearizationGains, *,
                 measurement: str = "observer", control_period: Optional[float] = None,
                 v_limit: float = math.inf, torques: TorqueModel = NO_TORQUES) -> None:
        super().__init__(motor, plan, gains, measurement=measurement, control_period=control_period,
                         v_limit=v_limit)
        if not isinstance(torques, TorqueModel):
            raise ValueError(f"torques={torques!r} is not a TorqueModel")
        self.torques = torques

    @property
    def observer_torques(self) -> TorqueModel:
        """The torques the drive loop's observer predicts with: the law's own (the observer shares its model)."""
        return self.torques

    def voltages(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """Phase voltages (va, vb) of the law, vectorized over time; ``ddtheta`` is not read in ``model`` mode."""
        m, (k0, k1, k2) = self.motor, self.gains.k
        ia, ib, omega, theta = np.asarray(x, dtype=float)
        p = m.Nr * theta
        i_d, i_q = park(ia, ib, p)
        if self.measurement == "model":
            acc = (m.Km * i_q - m.B * omega - self.torques.torque(t, theta, omega, m.Nr)) / m.J
        else:
            acc = np.asarray(ddtheta, dtype=float)
        dE = self.torques.torque_rate(t, theta, omega, acc, m.Nr)
        ref = self.plan.flag(t)
        u = ref.dddtheta - k2 * (acc - ref.ddtheta) - k1 * (omega - ref.dtheta) - k0 * (theta - ref.theta)
        v_q = m.R * i_q + m.L * m.Nr * omega * i_d + m.Km * omega + m.L / m.Km * (m.J * u + m.B * acc + dE)
        v_d = m.R * i_d - m.L * m.Nr * omega * i_q - m.L * self.gains.pd * i_d
        return np.array(inverse_park(v_d, v_q, p))

    def step(self, state: None, measurement: ArrayLike, t: float) -> tuple[NDArray[np.float64], None]:
        """Controller step ``(state, (ia, ib, omega, theta, ddtheta), t) -> (voltages, state)``; static law."""
        y = np.asarray(measurement, dtype=float)
        return self.voltages(t, y[:4], None if self.measurement == "model" else y[4]), state

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct exact_linearization_params`` (csrc/exact_linearization.h)."""
        g = self.gains
        return dict(motor=self.motor.as_dict(), plan=self.plan.c_plan(),
                    gains=dict(wn=g.wn, xi=g.xi, p3=g.p3, pd=g.pd),
                    measurement=1 if self.measurement == "model" else 0, v_limit=self.v_limit,
                    torques=self.torques.as_dict())


def from_spec(spec: ControllerSpec, context: BuildContext) -> ExactLinearization:
    """Exact linearization (flatstep.control.spec), its poles by rule (flatstep.control.build).

    The angle's at ``(s + lambda)(s^2 + 2 xi omega_n s + omega_n^2)``, the d current's at ``lambda``; any of
    :class:`LinearizationGains`'s fields given in ``context.law_gains`` replaces the rule's; ``feedforward`` gives it
    the known torques.
    """
    lam, wn = context.bandwidths()
    gains = context.gains(LinearizationGains, dict(wn=wn, xi=XI, p3=lam, pd=lam))
    return ExactLinearization(context.motor, context.plan, gains,
                              control_period=context.period, measurement=context.measurement,
                              v_limit=context.v_limit, torques=context.torques)
