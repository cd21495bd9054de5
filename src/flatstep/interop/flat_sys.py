r"""The motor as a python-control ``FlatSystem``, on the paper's flat outputs or on the d-q pair.

``outputs="rho_theta"``: :math:`z = (\rho, \theta)`, flags :math:`(\rho, \dot\rho)` and
:math:`(\theta, \dot\theta, \ddot\theta, \theta^{(3)})`, through flatstep's own maps
(:func:`flatstep.model.flat.state_to_flat`, :func:`flatstep.model.flat.flat_to_state`, eqs. 7-10); singular
where :math:`|J\ddot\theta + B\dot\theta + \tau| \ge K_m\rho`.

``outputs="theta_id"``: :math:`z = (\theta, i_d)`, flags :math:`(\theta, \dot\theta, \ddot\theta,
\theta^{(3)})` and :math:`(i_d, \dot i_d)`, through the d-q maps of :mod:`flatstep.interop.dq`; regular
everywhere.
"""
from __future__ import annotations

from typing import Any, Callable, Optional

import control
import numpy as np
from control.flatsys import FlatSystem
from numpy.typing import NDArray

from ..model.flat import FlatFlag, flat_to_state, state_to_flat
from ..model.motor import INPUT_NAMES, STATE_NAMES, MotorParams, rhs
from ..validate import InputError, check_instance, check_quantity, short_repr
from .arguments import check_name
from .dq import DQFlag, dq_flag_to_state, dq_state_to_flag

Array = NDArray[np.float64]
Flag = list[Array]

#: The flat outputs of each choice, in the order of the flags.
FLAT_OUTPUTS = {"rho_theta": ("rho", "theta"), "theta_id": ("theta", "i_d")}
#: The flag lengths of each choice (the flat output and its derivatives).
FLAG_LENGTHS = {"rho_theta": (2, 4), "theta_id": (4, 2)}


def _forward_rho_theta(motor: MotorParams, tau: float, x: Array, u: Array) -> Flag:
    """Eqs. (7)-(8): the (rho, theta) flag of a state and input."""
    f = state_to_flat(x, u, motor, tau)
    return [np.array([f.rho, f.drho]), np.array([f.theta, f.dtheta, f.ddtheta, f.dddtheta])]


def _reverse_rho_theta(motor: MotorParams, tau: float, z: Flag) -> tuple[Array, Array]:
    """Eqs. (9)-(10), corrected: the state and input of a (rho, theta) flag."""
    (rho, drho), (theta, dtheta, ddtheta, dddtheta) = z[0][:2], z[1][:4]
    return flat_to_state(FlatFlag(rho, drho, theta, dtheta, ddtheta, dddtheta), motor, tau)


def _forward_theta_id(motor: MotorParams, tau: float, x: Array, u: Array) -> Flag:
    """The d-q maps: the (theta, i_d) flag of a state and input."""
    f = dq_state_to_flag(x, u, motor, tau)
    return [np.array([f.theta, f.dtheta, f.ddtheta, f.dddtheta]), np.array([f.i_d, f.di_d])]


def _reverse_theta_id(motor: MotorParams, tau: float, z: Flag) -> tuple[Array, Array]:
    """The d-q maps: the state and input of a (theta, i_d) flag."""
    (theta, dtheta, ddtheta, dddtheta), (i_d, di_d) = z[0][:4], z[1][:2]
    return dq_flag_to_state(DQFlag(theta, dtheta, ddtheta, dddtheta, i_d, di_d), motor, tau)


_MAPS: dict[str, tuple[Callable[..., Flag], Callable[..., tuple[Array, Array]]]] = {
    "rho_theta": (_forward_rho_theta, _reverse_rho_theta),
    "theta_id": (_forward_theta_id, _reverse_theta_id),
}


def flatsys(motor: MotorParams, outputs: str = "rho_theta", *, load_torque: float = 0.0,
            name: Optional[str] = "motor", **kwargs: Any) -> FlatSystem:
    """The nominal a-b model of eq. (1) as a ``control.flatsys.FlatSystem``.

    Parameters
    ----------
    motor : MotorParams
        The motor.
    outputs : {"rho_theta", "theta_id"}
        The flat outputs (module docstring; :data:`FLAT_OUTPUTS`).
    load_torque : float
        A constant load torque [N m] known to the maps; a ``params={"load_torque": ...}`` given to
        python-control (e.g. to ``point_to_point``) overrides it.
    name : str, optional
        The system's name.
    **kwargs
        Passed to ``FlatSystem``.

    Returns
    -------
    control.flatsys.FlatSystem
        States ``ia, ib, omega, theta``, inputs ``va, vb``, outputs the flat outputs; ``forward(x, u)``
        gives the flag as a list of arrays (:data:`FLAG_LENGTHS`), ``reverse(zflag)`` the state and input.
        Its update function is eq. (1), so it also simulates.
    """
    if not (isinstance(outputs, str) and outputs in _MAPS):
        raise InputError("outputs", outputs, f"outputs={short_repr(outputs)} is not a choice of flat outputs; valid: "
                         f"{sorted(_MAPS)}")
    check_instance("motor", motor, MotorParams, "a flatstep MotorParams")
    default = check_quantity("load", load_torque, as_name="load_torque")
    check_name(name)
    forward_map, reverse_map = _MAPS[outputs]

    def tau(params: Optional[dict[str, Any]]) -> float:
        value = (params or {}).get("load_torque", default)
        return check_quantity("load", value, as_name="params['load_torque']")

    def forward(x: Array, u: Array, params: Optional[dict[str, Any]] = None) -> Flag:
        return forward_map(motor, tau(params), np.asarray(x, dtype=float), np.asarray(u, dtype=float))

    def reverse(zflag: Flag, params: Optional[dict[str, Any]] = None) -> tuple[Array, Array]:
        return reverse_map(motor, tau(params), [np.asarray(z, dtype=float) for z in zflag])

    def update(t: float, x: Array, u: Array, params: Optional[dict[str, Any]] = None) -> Array:
        return rhs(t, x, u, motor, tau(params))

    def output(t: float, x: Array, u: Array, params: Optional[dict[str, Any]] = None) -> Array:
        return np.array([z[0] for z in forward(x, u, params)])

    options: dict[str, Any] = dict(states=list(STATE_NAMES), inputs=list(INPUT_NAMES),
                                   outputs=list(FLAT_OUTPUTS[outputs]), name=name,
                                   params={"load_torque": default})
    return control.flatsys.flatsys(forward, reverse, updfcn=update, outfcn=output, **{**options, **kwargs})
