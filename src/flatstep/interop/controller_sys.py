"""A flatstep controller as a python-control ``NonlinearIOSystem``, to close loops with ``control.interconnect``."""
from __future__ import annotations

from typing import Any, Optional

import control
import numpy as np
from numpy.typing import NDArray

from ..control.protocol import is_static
from ..model.motor import INPUT_NAMES
from ..validate import InputError, short_repr
from .arguments import check_name
from .plant_sys import OUTPUT_NAMES


def controller_nlsys(controller: Any, *, name: Optional[str] = "controller",
                     **kwargs: Any) -> control.NonlinearIOSystem:
    r"""A static flatstep controller (:func:`~flatstep.control.protocol.is_static`) as a static I/O system.

    .. math:: v = k(t, y),\qquad y = (i_a, i_b, \omega, \theta, \ddot\theta)

    with :math:`k` the controller's ``voltages(t, x, ddtheta)`` (for
    :class:`~flatstep.control.smc.FlatnessSMC`, eqs. (12)-(14)); in ``model`` measurement the input
    ``ddtheta`` is not read. The inputs are named as the outputs of
    :func:`~flatstep.interop.plant_sys.nlsys` and the outputs as its inputs, so that
    ``control.interconnect([nlsys(plant), controller_nlsys(ctrl)], inplist=[], outlist=[...])`` closes the loop
    by name, in continuous time, as ``flatstep.simulate(..., solver=Continuous())`` does.

    Outside the law's domain (a measured current norm of 0, or a torque demand beyond :math:`K_m\rho`) the
    law has no finite voltages; the output is then 0 V, as the C step applies (csrc/controller.h), and the
    C engine counts such periods as faults. python-control evaluates every static system once on zero inputs
    while it solves an interconnection's signals, so a NaN there would spread to every signal of the loop.

    Parameters
    ----------
    controller : StaticController
        A controller whose voltages depend on ``(t, y)`` alone, e.g. :class:`~flatstep.control.smc.FlatnessSMC`.
    name : str, optional
        The system's name in an interconnection.
    **kwargs
        Passed to ``control.nlsys``.

    Returns
    -------
    control.NonlinearIOSystem
        No states; inputs ``ia, ib, omega, theta, ddtheta``; outputs ``va, vb``.
    """
    check_name(name)
    if not is_static(controller):
        raise InputError("controller", controller, f"controller={short_repr(controller)}: "
                         f"{type(controller).__name__} is not a static controller (it keeps state between control "
                         "periods, or has no voltages(t, x, ddtheta)); only static laws such as FlatnessSMC run in "
                         "continuous time")

    def output(t: float, x: NDArray[np.float64], u: NDArray[np.float64], params: Any) -> NDArray[np.float64]:
        y = np.asarray(u, dtype=float)
        ddtheta = None if getattr(controller, "measurement", None) == "model" else y[4]
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            v = np.asarray(controller.voltages(t, y[:4], ddtheta), dtype=float)
        return v if np.all(np.isfinite(v)) else np.zeros(2)  # outside the law's domain: 0 V, as the C step

    options: dict[str, Any] = dict(inputs=list(OUTPUT_NAMES), outputs=list(INPUT_NAMES), name=name)
    return control.nlsys(None, output, **{**options, **kwargs})
