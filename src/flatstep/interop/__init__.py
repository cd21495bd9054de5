"""python-control interop: the motor as ``NonlinearIOSystem`` and ``FlatSystem``, controllers as I/O systems.

Needs python-control >= 0.10 (``pip install 'flatstep[control]'``).

* :func:`nlsys`: the plant (motor, effects, load) as a ``control.NonlinearIOSystem``.
* :func:`flatsys`: the motor as a ``control.flatsys.FlatSystem`` on ``(rho, theta)`` or ``(theta, i_d)``.
* :class:`PsiFamily`: the paper's psi as a basis, so that ``point_to_point`` plans flatstep's moves.
* :func:`controller_nlsys`: a static flatstep controller as an I/O system, for ``control.interconnect``.

The paper's Fig. 2 run, closed in python-control (tests/test_interop.py holds it to ``flatstep.simulate``)::

    import control
    import flatstep as fs
    from flatstep.interop import controller_nlsys, nlsys

    motor, plan = fs.MotorParams.preset("paper"), fs.PAPER_PLAN
    ctrl = fs.FlatnessSMC(motor, plan, fs.SMCGains(W1=300, W2=300))
    loop = control.interconnect([nlsys(fs.Plant(motor, load=1e-5)), controller_nlsys(ctrl)], inplist=[],
                                outlist=["theta", "va", "vb"])
    resp = control.input_output_response(loop, [0.0, 0.06], 0, X0=plan.x0(motor.Nr), evaluation_times=None,
                                         solve_ivp_kwargs=dict(method="LSODA", rtol=1e-9, atol=1e-12))
"""
try:
    import control  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError("flatstep.interop needs python-control >= 0.10: pip install 'flatstep[control]'") from exc

from .basis import PsiFamily
from .controller_sys import controller_nlsys
from .dq import DQFlag, dq_flag_to_state, dq_state_to_flag, inverse_park, park
from .flat_sys import FLAG_LENGTHS, FLAT_OUTPUTS, flatsys
from .plant_sys import OUTPUT_NAMES, nlsys

__all__ = ["DQFlag", "FLAG_LENGTHS", "FLAT_OUTPUTS", "OUTPUT_NAMES", "PsiFamily", "controller_nlsys",
           "dq_flag_to_state", "dq_state_to_flag", "flatsys", "inverse_park", "nlsys", "park"]
