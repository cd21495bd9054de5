r"""The one interface every controller satisfies, in Python and (through ``c_name``) in C.

A controller is a law on caller-owned state: the run loops call

.. math:: (v_k, s_{k+1}) = \mathrm{step}(s_k, y_k, t_k),\qquad y = (i_a, i_b, \omega, \theta, \ddot\theta)

once per control period, from ``s_0 = initial_state()``, and read ``motor`` (the controller's nominal model,
which the observer shares), ``plan`` (the move it tracks) and ``measurement`` (where its speed and
acceleration come from: ``"ideal"``, ``"model"`` or ``"observer"``) and ``gains``. A law whose voltages depend on
``(t, y)`` alone also offers ``voltages(t, x, ddtheta)`` vectorized over time, and may then run inside the
continuous loop (:class:`StaticController`).

The C twin of a controller is named by ``c_name``: ``csrc/<c_name>.h`` declares ``struct <c_name>_params``,
``<c_name>_init``, ``<c_name>_reset``, ``<c_name>_step`` and ``<c_name>_controller``, and ``c_params()`` returns
the fields of its params struct. The binding (:func:`flatstep.core.structs.controller_struct`) needs nothing
else, so adding a controller touches its Python file, its C file and nothing more.
"""
from __future__ import annotations

from typing import Any, Optional, Protocol, TypeGuard, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..plan.protocol import Plan, check_plan


@runtime_checkable
class Controller(Protocol):
    """What the sampled loops (Python reference and C) need of a controller."""

    motor: MotorParams
    gains: Any  # a frozen dataclass with ``as_dict()``, recorded in each result's metadata
    measurement: str

    @property
    def plan(self) -> Plan:
        """The move the law tracks."""
        ...

    @property
    def c_name(self) -> Optional[str]:
        """The C module of the law (``csrc/<c_name>.h``), ``None`` for a law with no C twin."""
        ...

    def initial_state(self) -> Any:
        """The controller's state at the start of a run (``None`` for a static law)."""
        ...

    def step(self, state: Any, measurement: ArrayLike, t: float) -> tuple[NDArray[np.float64], Any]:
        """One control period: the phase voltages ``(va, vb)`` and the next state."""
        ...

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct <c_name>_params``."""
        ...


@runtime_checkable
class StaticController(Controller, Protocol):
    """A controller whose voltages depend on ``(t, y)`` alone: it also runs in the continuous loop."""

    def voltages(self, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """Phase voltages ``(va, vb)`` at times ``t`` for states ``x`` (4, n), vectorized over time."""
        ...


@runtime_checkable
class SlidingController(StaticController, Protocol):
    """A static law with sliding variables (the paper's ``s1``, ``s2`` of eq. (12)), which results report."""

    def sliding_variables(self, t: ArrayLike, x: ArrayLike,
                          ddtheta: Optional[ArrayLike] = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The sliding variables at times ``t`` for states ``x`` (4, n), vectorized over time."""
        ...


def is_static(controller: Any) -> TypeGuard[StaticController]:
    """Whether ``controller`` can run in the continuous loop (it has no state between steps)."""
    return isinstance(controller, StaticController) and controller.initial_state() is None


def check_parts(motor: object, plan: object, gains: object, gains_type: type) -> None:
    """Raise a ValueError unless a controller's parts are a MotorParams, a plan and gains of ``gains_type``."""
    if not isinstance(motor, MotorParams):
        raise ValueError(f"motor={motor!r} is not a MotorParams (MotorParams.preset('paper'), say)")
    check_plan(plan)
    if not isinstance(gains, gains_type):
        raise ValueError(f"gains={gains!r} is not a {gains_type.__name__}")
