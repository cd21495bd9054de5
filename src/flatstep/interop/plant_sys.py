"""The motor, or a whole :class:`~flatstep.model.plant.Plant`, as a python-control ``NonlinearIOSystem``."""
from __future__ import annotations

from typing import Any, Optional, Union

import control
import numpy as np
from numpy.typing import NDArray

from ..model.motor import INPUT_NAMES, STATE_NAMES, MotorParams, load_function
from ..model.plant import Plant, plant_rhs
from ..validate import check_bool, check_instance
from .arguments import check_name

#: The outputs of :func:`nlsys`: the state and the rotor's acceleration, the measurement ``y`` a flatstep
#: controller reads (:mod:`flatstep.control.protocol`).
OUTPUT_NAMES = (*STATE_NAMES, "ddtheta")
#: The name of the load-torque input of ``nlsys(..., load_input=True)``.
LOAD_INPUT = "tau"


def nlsys(plant: Union[Plant, MotorParams], *, load_input: bool = False, name: Optional[str] = "motor",
          **kwargs: Any) -> control.NonlinearIOSystem:
    r"""The a-b model of eq. (1), with the plant's effects and load, as a ``control.NonlinearIOSystem``.

    .. math::
        \dot x = f(x, v, \tau),\quad x = (i_a, i_b, \omega, \theta),\quad v = (v_a, v_b),\qquad
        y = (i_a, i_b, \omega, \theta, \ddot\theta)

    with :math:`f` the right-hand side of :func:`flatstep.model.plant.plant_rhs` (detent torque, Coulomb
    friction and iron loss included when the plant has them).

    Parameters
    ----------
    plant : Plant or MotorParams
        The simulated plant; a bare motor is a plant with no effects and no load.
    load_input : bool
        Add a third input ``tau``, a load torque [N m] added to the plant's own load.
    name : str, optional
        The system's name in an interconnection.
    **kwargs
        Passed to ``control.nlsys`` (e.g. ``outputs`` to rename the outputs).

    Returns
    -------
    control.NonlinearIOSystem
        States ``ia, ib, omega, theta``; inputs ``va, vb`` (and ``tau``); outputs ``ia, ib, omega, theta,
        ddtheta`` (:data:`OUTPUT_NAMES`), the measurement vector of a flatstep controller, so that
        :func:`~flatstep.interop.controller_sys.controller_nlsys` connects to it by name.
    """
    if isinstance(plant, MotorParams):
        plant = Plant(plant)
    check_instance("plant", plant, Plant, "a flatstep Plant or MotorParams")
    load_input = check_bool("load_input", load_input)
    check_name(name)
    motor, effects, tau = plant.motor, plant.effects, load_function(plant.load)

    def load(t: float, u: NDArray[np.float64]) -> float:
        return float(tau(np.asarray(t, dtype=float))) + (float(u[2]) if load_input else 0.0)

    def update(t: float, x: NDArray[np.float64], u: NDArray[np.float64], params: Any) -> NDArray[np.float64]:
        return plant_rhs(x, u[:2], motor, load(t, u), effects)

    def output(t: float, x: NDArray[np.float64], u: NDArray[np.float64], params: Any) -> NDArray[np.float64]:
        acc = plant_rhs(x, np.zeros(2), motor, load(t, u), effects)[2]
        return np.array([*x, acc])

    inputs = (*INPUT_NAMES, LOAD_INPUT) if load_input else INPUT_NAMES
    options: dict[str, Any] = dict(states=list(STATE_NAMES), inputs=list(inputs), outputs=list(OUTPUT_NAMES),
                                   name=name)
    return control.nlsys(update, output, **{**options, **kwargs})
