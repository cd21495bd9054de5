"""The cffi handle of the C core (csrc/), its status and error codes, the struct builders and the array
marshalling that :mod:`flatstep._core_maps` and :mod:`flatstep._core_runs` share.

Arrays are float64, C-contiguous, row-major ``(n, k)`` on the C side and ``(k, n)`` (components first, as
in the Python reference) on this side.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._flatstep_core import ffi, lib
from .control.smc import FlatnessSMC
from .motor import MotorParams, check_positive
from .plan import RestToRest

Array = NDArray[np.float64]
#: smc_step status bits by name; every bit but ``saturated`` is a fault (the step then outputs 0 V).
STATUS_BITS = {"nonfinite": lib.SMC_NONFINITE, "rho": lib.SMC_RHO, "sqrt": lib.SMC_SQRT,
               "overflow": lib.SMC_OVERFLOW, "saturated": lib.SMC_SATURATED}
#: The status bits that are faults (the step then outputs 0 V): all but ``saturated``.
FAULT_BITS = lib.SMC_NONFINITE | lib.SMC_RHO | lib.SMC_SQRT | lib.SMC_OVERFLOW
_SIM_ERRORS = {lib.SIM_EARGS: "invalid arguments", lib.SIM_ECONTROL: "the controller faulted",
               lib.SIM_EHMIN: "the step size fell below rounding level",
               lib.SIM_EMAXSTEPS: "more than max_steps steps", lib.SIM_ENONFINITE: "the state became non-finite"}
_PARAM_ERRORS = {lib.SMC_EMOTOR: "motor", lib.SMC_EPLAN: "plan", lib.SMC_EGAINS: "gains",
                 lib.SMC_EMEASUREMENT: "measurement", lib.SMC_ELIMITS: "v_limit/rho_min"}
#: Defaults of the guards in smc_step: bound on hypot(va, vb) [V] and smallest rho acted on [A].
V_LIMIT, RHO_MIN = 1e3, 1e-6


def status_names(status: int) -> list[str]:
    """The names of the smc_step status bits set in ``status``."""
    return [name for name, bit in STATUS_BITS.items() if int(status) & bit]


def _rows(a: ArrayLike, k: int, name: str) -> np.ndarray:
    """(k, n) or (k,) components-first input -> C-contiguous (n, k) float64 rows."""
    a = np.asarray(a, dtype=np.float64)
    if a.shape[:1] != (k,):
        raise ValueError(f"{name} has shape {a.shape}; expected ({k},) or ({k}, n)")
    return np.ascontiguousarray(a.reshape(k, -1).T)


def _vec(a: ArrayLike) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel())


def _in(a: np.ndarray):
    return ffi.from_buffer("double[]", a)


def _out(a: np.ndarray):
    return ffi.from_buffer("double[]", a, require_writable=True)


def _u32(a: np.ndarray):
    return ffi.from_buffer("uint32_t[]", a, require_writable=True)


def _shape(out: np.ndarray, like: tuple) -> np.ndarray:
    """(n, k) C rows -> (k, *like) components first."""
    return out.T.reshape((out.shape[1],) + like)


def _motor(m: MotorParams) -> dict:
    """The fields of a ``struct motor_params`` holding ``m``."""
    return dict(R=m.R, L=m.L, Km=m.Km, J=m.J, B=m.B, Nr=m.Nr)


def motor_struct(m: MotorParams):
    """A ``struct motor_params`` holding ``m``."""
    return ffi.new("struct motor_params *", _motor(m))


def plan_struct(p: RestToRest):
    """A ``struct plan`` holding ``p``."""
    return ffi.new("struct plan *", p.as_dict())


def _smc_params(controller: FlatnessSMC, v_limit: float, rho_min: float) -> dict:
    """The fields of a ``struct smc_params`` for ``controller`` (its motor model, plan, gains and measurement)."""
    g = controller.gains
    # "ideal" and "observer" both read theta'' from y[4]; only "model" computes it from the state
    return dict(motor=_motor(controller.motor), plan=controller.plan.as_dict(),
                gains=dict(W1=g.W1, W2=g.W2, eps1=g.eps1, eps2=g.eps2, xi=g.xi, wn=g.wn,
                           hold_damping=g.hold_damping or 0.0),
                measurement=lib.SMC_MODEL if controller.measurement == "model" else lib.SMC_IDEAL,
                v_limit=v_limit, rho_min=rho_min)


def smc_struct(controller: FlatnessSMC, v_limit: float = V_LIMIT, rho_min: float = RHO_MIN):
    """An initialised ``struct smc`` for ``controller`` (its motor model, plan, gains and measurement)."""
    check_positive("v_limit", v_limit, unit=" V")
    check_positive("rho_min", rho_min, unit=" A")
    s = ffi.new("struct smc *")
    err = lib.smc_init(s, ffi.new("struct smc_params *", _smc_params(controller, v_limit, rho_min)))
    if err != lib.SMC_PARAMS_OK:
        raise ValueError(f"smc_init rejected the controller's {_PARAM_ERRORS.get(err, err)} parameters")
    return s


def _plant(motor: MotorParams, load: float):
    return ffi.new("struct sim_plant *", dict(motor=_motor(motor), load=float(load)))


def _stats(st, key: str) -> dict:
    return {"steps": st.steps, "rejected": st.rejected, "rhs_evals": st.rhs_evals, key: status_names(st.smc_status)}


def _check(rc: int, st, what: str) -> None:
    if rc != lib.SIM_OK:
        raise RuntimeError(f"C {what} run failed at t = {st.t_fail:.6g} s: {_SIM_ERRORS.get(rc, rc)} "
                           f"(controller status {status_names(st.smc_status)})")
