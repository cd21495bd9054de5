r"""Rest-to-rest plans of the flat outputs (rho, theta): the interpolating polynomial psi, eqs. (15)-(21).

The paper's psi (eq. 17) in normalised time :math:`\tau = (t - t_0)/(t_f - t_0)` is

.. math::
    \psi(\tau) = \tau^5 (252 - 1050\tau + 1800\tau^2 - 1575\tau^3 + 700\tau^4 - 126\tau^5),\qquad
    \psi'(\tau) = 1260\,\tau^4 (1 - \tau)^5,

a degree-10 polynomial (the regularized incomplete beta function :math:`I_\tau(5, 6)`): its first four
derivatives vanish at :math:`t_0` and its first five at :math:`t_f`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.equilibria import equilibrium_currents, stable_angle
from ..model.flat import FlatFlag
from ..model.motor import MotorParams
from ..validate import InputError, check_finite, check_instance, check_quantity

if TYPE_CHECKING:  # piecewise imports this module
    from .piecewise import PiecewisePlan

from ..model.psi import _PSI_DERIVS, _PSI_HORNER, MAX_ORDER, PAPER_R, psi  # noqa: F401 (re-exported)


@dataclass(frozen=True)
class RestToRest:
    r"""Equilibrium-to-equilibrium transfer of the flat outputs, eqs. (16) and (18).

    .. math::
        \theta^*(t) = \bar\theta^1 + \psi(t)(\bar\theta^2 - \bar\theta^1),\qquad
        \rho^*(t) = \bar\rho^1 + \psi(t)(\bar\rho^2 - \bar\rho^1)

    Build one with :func:`point_to_point` (which also checks feasibility) or directly.
    """

    theta1: float
    theta2: float
    rho1: float
    rho2: float
    t0: float = 0.02
    tf: float = 0.04

    def __post_init__(self) -> None:
        for name, kind in (("theta1", "angle"), ("theta2", "angle"), ("rho1", "current"), ("rho2", "current"),
                           ("t0", "time"), ("tf", "time")):  # ranges: flatstep.validate.ranges
            object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        if not self.tf > self.t0:
            raise InputError("tf", self.tf, f"tf={self.tf!r} s must be greater than t0={self.t0!r} s")

    @classmethod
    def from_currents(cls, ia1: float, ib1: float, ia2: float, ib2: float, Nr: int,
                      t0: float = 0.02, tf: float = 0.04, theta_near: float = 0.0) -> "RestToRest":
        """The transfer between the stable rest positions held by end currents (eq. 2 and eq. 20).

        The start angle is the stable equilibrium nearest ``theta_near``; the end angle the one nearest
        the start (a move of at most half an electrical period, ``pi / Nr``).
        """
        for name, value in (("ia1", ia1), ("ib1", ib1), ("ia2", ia2), ("ib2", ib2)):
            check_finite(name, value)
        theta1 = stable_angle(ia1, ib1, Nr, near=theta_near)
        theta2 = stable_angle(ia2, ib2, Nr, near=theta1)
        return cls(theta1, theta2, math.hypot(ia1, ib1), math.hypot(ia2, ib2), t0, tf)

    @property
    def knots(self) -> tuple[float, float]:
        """Where the plan's derivatives may jump: ``(t0, tf)`` (an integrator restarts there)."""
        return (self.t0, self.tf)

    def flag(self, t: ArrayLike) -> FlatFlag:
        """The planned flat flag (rho*, rho*', theta*, theta*', theta*'', theta*''') at times ``t``."""
        t = np.asarray(t, dtype=float)
        p = [psi(t, self.t0, self.tf, k) for k in range(4)]
        dth, drho = self.theta2 - self.theta1, self.rho2 - self.rho1
        return FlatFlag(self.rho1 + p[0] * drho, p[1] * drho,
                        self.theta1 + p[0] * dth, p[1] * dth, p[2] * dth, p[3] * dth)

    def x0(self, Nr: int) -> NDArray[np.float64]:
        """Initial equilibrium state (ia, ib, omega, theta), eq. (19)."""
        return np.array([*equilibrium_currents(self.theta1, self.rho1, Nr), 0.0, self.theta1])

    def xf(self, Nr: int) -> NDArray[np.float64]:
        """Final equilibrium state (ia, ib, omega, theta), eqs. (20)-(21)."""
        return np.array([*equilibrium_currents(self.theta2, self.rho2, Nr), 0.0, self.theta2])

    def as_dict(self) -> dict[str, float]:
        """The plan's fields by name, as the C ``struct plan`` and a result's metadata take them."""
        return dict(theta1=self.theta1, theta2=self.theta2, rho1=self.rho1, rho2=self.rho2, t0=self.t0, tf=self.tf)

    def to_table(self) -> PiecewisePlan:
        """The move as a segment table: psi's degree-10 segment on [t0, tf] between the two holds."""
        from .piecewise import PiecewisePlan

        return PiecewisePlan.from_rest_to_rest(self)

    def c_plan(self) -> dict[str, Any]:
        """The fields of the C ``struct plan``: the end points, no table (the C core evaluates psi, as :meth:`flag`)."""
        return self.as_dict()


#: The paper's move (Section 3): 0 -> 0.02 rad at constant rho = 0.4 A, t0 = 0.02 s, tf = 0.04 s.
PAPER_PLAN = RestToRest(theta1=0.0, theta2=0.02, rho1=0.4, rho2=0.4, t0=0.02, tf=0.04)


def point_to_point(motor: MotorParams, theta1: float, theta2: float, rho1: float, rho2: float,
                   t0: float = 0.02, tf: float = 0.04, *, load_torque: float = 0.0,
                   v_max: float | None = None, i_max: float | None = None) -> RestToRest:
    """Plan a rest-to-rest move and refuse it, before anything is simulated, if it is infeasible.

    Raises
    ------
    InfeasiblePlanError
        A ValueError carrying the :class:`~flatstep.plan.feasibility.FeasibilityReport` of the worst point.
    """
    from .feasibility import check_feasibility

    check_instance("motor", motor, MotorParams, "a MotorParams", "e.g. MotorParams.preset('paper')")
    plan = RestToRest(theta1, theta2, rho1, rho2, t0, tf)
    check_feasibility(plan, motor, load_torque=load_torque, v_max=v_max, i_max=i_max).raise_if_infeasible()
    return plan
