r"""The one plan interface every controller tracks, in Python and (through ``c_plan``) in C.

A plan is a trajectory of the flat outputs :math:`(\rho, \theta)` from rest at :math:`t_0` to rest at :math:`t_f`.
A law reads it through the flat flag, vectorized over time,

.. math:: \big(\rho^*, \dot\rho^*, \theta^*, \dot\theta^*, \ddot\theta^*, \theta^{*(3)}\big)(t),

held at its start values before :math:`t_0` and at its end values from :math:`t_f` on, and through its end
points :math:`(\theta_1, \rho_1)` at :math:`t_0` and :math:`(\theta_2, \rho_2)` at :math:`t_f`. What a law needs
beyond the flag it derives from these: the loss-aware :math:`\rho^*(t)` from the flag's torque demand
(:mod:`flatstep.plan.loss_aware`), the d-q law's :math:`i_d^*(t)` weakening from the flag's speed
(:mod:`flatstep.plan.d_current`), the detent hold from :math:`t_f`, :math:`\theta_2` and :math:`\rho_2`.

Every plan is also a piecewise polynomial (:meth:`Plan.to_table`, a
:class:`~flatstep.plan.piecewise.PiecewisePlan`): the paper's move is one degree-10 segment of psi between two
holds. Its C form (:meth:`Plan.c_plan`) is the fields of the C ``struct plan`` (csrc/plan.h): the end points and,
for a table, a ``struct traj *`` (csrc/trajectory.h); with none the C core evaluates psi, the exact twin of
:class:`~flatstep.plan.rest_to_rest.RestToRest`'s flag. Every C controller initialises its reference with
``plan_init`` and reads it with ``plan_flag``, so every controller takes every plan.

The planners' outputs satisfy it: :class:`~flatstep.plan.rest_to_rest.RestToRest` (:func:`point_to_point`) and
:class:`~flatstep.plan.piecewise.PiecewisePlan` (:func:`~flatstep.plan.waypoints.plan_waypoints`,
:func:`~flatstep.plan.time_optimal.time_optimal`, :func:`~flatstep.plan.time_optimal.time_optimal_sequence`,
the baselines of :mod:`flatstep.plan.baselines`), as python-control's flatsys systems take any basis through
one ``eval_deriv``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat import FlatFlag
from ..validate import InputError
from ..validate.checks import short_repr

if TYPE_CHECKING:  # the table is built where a conversion needs it
    from .piecewise import PiecewisePlan


@runtime_checkable
class Plan(Protocol):
    """What a controller, the flat maps and the run loops need of a plan of the flat outputs (module docstring)."""

    @property
    def t0(self) -> float:
        """Start of the move [s]: the flag is held at its start values up to here."""
        ...

    @property
    def tf(self) -> float:
        """End of the move [s], > ``t0``: the flag is held at its end values from here on."""
        ...

    @property
    def theta1(self) -> float:
        """Start angle [rad]."""
        ...

    @property
    def theta2(self) -> float:
        """End angle [rad]."""
        ...

    @property
    def rho1(self) -> float:
        """Start current magnitude [A], > 0."""
        ...

    @property
    def rho2(self) -> float:
        """End current magnitude [A], > 0."""
        ...

    @property
    def knots(self) -> tuple[float, ...]:
        """Where the flag's derivatives may jump (an integrator restarts there)."""
        ...

    def flag(self, t: ArrayLike) -> FlatFlag:
        """The flat flag (rho*, rho*', theta*, theta*', theta*'', theta*''') at times ``t`` (vectorized)."""
        ...

    def x0(self, Nr: int) -> NDArray[np.float64]:
        """The start equilibrium (ia, ib, omega, theta), eq. (19)."""
        ...

    def xf(self, Nr: int) -> NDArray[np.float64]:
        """The end equilibrium (ia, ib, omega, theta), eqs. (20)-(21)."""
        ...

    def as_dict(self) -> dict[str, float]:
        """The end points by name (``theta1 theta2 rho1 rho2 t0 tf``), for a result's metadata."""
        ...

    def to_table(self) -> PiecewisePlan:
        """The plan as a segment table (the same flag, to rounding)."""
        ...

    def c_plan(self) -> dict[str, Any]:
        """The fields of the C ``struct plan`` (csrc/plan.h): the end points, and ``traj`` for a table."""
        ...


def check_plan(plan: object) -> None:
    """Raise a ValueError unless ``plan`` satisfies :class:`Plan` (a move every controller can track)."""
    if not isinstance(plan, Plan):
        missing = [name for name in _MEMBERS if not hasattr(plan, name)]
        raise InputError("plan", plan, f"plan={short_repr(plan)} is not a flatstep plan: it lacks {missing} (a "
                         "RestToRest from point_to_point, a PiecewisePlan from plan_waypoints or time_optimal, or any "
                         "object with the members of flatstep.plan.protocol.Plan)")


#: The members of :class:`Plan`, named in :func:`check_plan`'s message.
_MEMBERS = ("t0", "tf", "theta1", "theta2", "rho1", "rho2", "knots", "flag", "x0", "xf", "as_dict", "to_table",
            "c_plan")
