"""The cffi handle of the C core (csrc/), its status and error codes, struct builders and array marshalling.

:mod:`flatstep.core.maps` and :mod:`flatstep.core.runs` share them. Arrays are float64, C-contiguous,
row-major ``(n, k)`` on the C side and ``(k, n)`` (components first, as in the Python reference) on this side.
"""
from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Any, Callable, Iterator, NamedTuple, Optional, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._flatstep_core import ffi, lib
from ..control.protocol import Controller
from ..control.smc import FlatnessSMC
from ..errors import RunError
from ..model.motor import MotorParams
from ..model.plant import PlantEffects
from ..plan.protocol import Plan
from ..validate import check_positive

Array = NDArray[np.float64]
#: A cffi cdata object (a C pointer or buffer): cffi ships no type information, so it is ``Any`` to mypy.
CData = Any
#: Controller status bits by name (csrc/controller.h); every bit but ``saturated`` is a fault (the step then
#: outputs 0 V).
STATUS_BITS = {"nonfinite": lib.CTRL_NONFINITE, "rho": lib.CTRL_RHO, "sqrt": lib.CTRL_SQRT,
               "overflow": lib.CTRL_OVERFLOW, "saturated": lib.CTRL_SATURATED}
#: The status bits that are faults (the step then outputs 0 V): all but ``saturated``.
FAULT_BITS = lib.CTRL_FAULTS
_SIM_ERRORS = {lib.SIM_EARGS: "invalid arguments", lib.SIM_ECONTROL: "the controller faulted",
               lib.SIM_EHMIN: "the step size fell below rounding level",
               lib.SIM_EMAXSTEPS: "more than max_steps steps", lib.SIM_ENONFINITE: "the state became non-finite",
               lib.SIM_ECANCELLED: "cancelled"}
_SIM_REASONS = {lib.SIM_ECONTROL: "fault", lib.SIM_EHMIN: "step_size", lib.SIM_EMAXSTEPS: "max_steps",
                lib.SIM_ENONFINITE: "nonfinite"}
_PARAM_ERRORS = {lib.SMC_EMOTOR: "motor", lib.SMC_EPLAN: "plan", lib.SMC_EGAINS: "gains",
                 lib.SMC_EMEASUREMENT: "measurement", lib.SMC_ELIMITS: "v_limit/rho_min"}
#: Defaults of the guards in smc_step: bound on hypot(va, vb) [V] and smallest rho acted on [A].
V_LIMIT, RHO_MIN = FlatnessSMC.c_v_limit, FlatnessSMC.c_rho_min


def status_names(status: int) -> list[str]:
    """The names of the smc_step status bits set in ``status``."""
    return [name for name, bit in STATUS_BITS.items() if int(status) & bit]


def _rows(a: ArrayLike, k: int, name: str) -> Array:
    """(k, n) or (k,) components-first input -> C-contiguous (n, k) float64 rows."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.shape[:1] != (k,):
        raise ValueError(f"{name} has shape {arr.shape}; expected ({k},) or ({k}, n)")
    return np.ascontiguousarray(arr.reshape(k, -1).T)


def _vec(a: ArrayLike) -> Array:
    """Any input -> a C-contiguous 1-D float64 array."""
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel())


def _in(a: Array) -> CData:
    """A ``double *`` view of a C-contiguous float64 array, read by C."""
    return ffi.from_buffer("double[]", a)


def _out(a: Array) -> CData:
    """A ``double *`` view of a C-contiguous float64 array, written by C."""
    return ffi.from_buffer("double[]", a, require_writable=True)


def _u32(a: NDArray[np.uint32]) -> CData:
    """A ``uint32_t *`` view of a C-contiguous uint32 array, written by C."""
    return ffi.from_buffer("uint32_t[]", a, require_writable=True)


def _shape(out: Array, like: tuple[int, ...]) -> Array:
    """(n, k) C rows -> (k, *like) components first."""
    return out.T.reshape((out.shape[1],) + like)


def motor_struct(m: MotorParams) -> CData:
    """A ``struct motor_params`` holding ``m`` (its fields: ``m.c_params()``)."""
    return ffi.new("struct motor_params *", m.c_params())


def plan_struct(p: Plan) -> CData:
    """A ``struct plan`` holding ``p`` (its table, if any, kept alive by ``p``)."""
    return ffi.new("struct plan *", p.c_plan())


def _smc_params(controller: FlatnessSMC, v_limit: float, rho_min: float) -> dict[str, Any]:
    """The fields of a ``struct smc_params`` for ``controller`` with the guards ``v_limit`` and ``rho_min``."""
    return {**controller.c_params(), "v_limit": v_limit, "rho_min": rho_min}


def smc_struct(controller: FlatnessSMC, v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> CData:
    """An initialised ``struct smc`` for ``controller`` (its motor model, plan, gains and measurement)."""
    check_positive("v_limit", v_limit, unit=" V")
    check_positive("rho_min", rho_min, unit=" A")
    s = ffi.new("struct smc *")
    err = lib.smc_init(s, ffi.new("struct smc_params *", _smc_params(controller, v_limit, rho_min)))
    if err != lib.SMC_PARAMS_OK:
        raise ValueError(f"smc_init rejected the controller's {_PARAM_ERRORS.get(err, err)} parameters")
    return s


class BoundController(NamedTuple):
    """A controller's C state and the ``struct controller`` bound to it (the state must outlive the binding)."""

    state: CData
    iface: CData


def controller_struct(controller: Controller) -> BoundController:
    """The C twin of a Python controller, initialised and bound into the run loops' interface (controller.h).

    Any controller with ``c_name`` (its C module: ``struct <c_name>``, ``<c_name>_init``,
    ``<c_name>_controller``) and ``c_params()`` (the fields of ``struct <c_name>_params``, its plan as
    ``plan.c_plan()`` gives it) runs on the C engine, on any plan; the binding knows no controller by name.
    """
    name = getattr(controller, "c_name", None)
    if name is None or not hasattr(lib, f"{name}_init"):
        raise ValueError(f"{type(controller).__name__} has no C implementation (c_name={name!r}); "
                         "run it on engine='python'")
    params = controller.c_params()
    state = ffi.new(f"struct {name} *")
    err = getattr(lib, f"{name}_init")(state, ffi.new(f"struct {name}_params *", params))
    if err != 0:
        raise ValueError(f"{name}_init rejected the {type(controller).__name__} parameters (error {err}): "
                         f"{controller.c_params()!r}")
    iface = ffi.new("struct controller *")
    getattr(lib, f"{name}_controller")(state, iface)
    return BoundController(state, iface)


def _plant_fields(motor: MotorParams, load: float, effects: Optional[PlantEffects] = None) -> dict[str, Any]:
    """The fields of a ``struct plant``: the simulated motor, its constant load torque, its effects (none: zero)."""
    return dict(motor=motor.c_params(), load=float(load), effects=effects.c_effects() if effects is not None else {})


def _plant(motor: MotorParams, load: float, effects: Optional[PlantEffects] = None) -> CData:
    """A ``struct plant``."""
    return ffi.new("struct plant *", _plant_fields(motor, load, effects))


def _stats(st: CData, key: str = "controller_status") -> dict[str, Any]:
    """A run's statistics from its C ``struct sim_stats``, the controller status as bit names under ``key``."""
    return {"steps": st.steps, "rejected": st.rejected, "rhs_evals": st.rhs_evals,
            key: status_names(st.controller_status)}


def _check(rc: int, st: CData, what: str) -> None:
    """Raise a RuntimeError naming the failure and when it happened if a C run returned ``rc != SIM_OK``."""
    if rc != lib.SIM_OK:
        raise RunError(_SIM_REASONS.get(rc, "args"), float(st.t_fail),
                       f"C {what} run failed at t = {st.t_fail:.6g} s: {_SIM_ERRORS.get(rc, rc)} "
                       f"(controller status {status_names(st.controller_status)})")


Result = TypeVar("Result")


_scope = threading.local()


def cancel_flag() -> CData:
    """A new cancel flag (a ``uint32_t *`` set to 0) for :func:`cancel_scope`; set ``flag[0] = 1`` to cancel."""
    return ffi.new("uint32_t *")


@contextmanager
def cancel_scope(flag: CData) -> Iterator[None]:
    """Within this block, every C run this thread makes through :func:`cancellable` polls ``flag``.

    This is how a batch stops the runs of its worker threads: Python delivers Ctrl-C to the main thread only,
    which then sets the flag that the workers' C loops poll (:func:`flatstep.studies.batch.run_batch`).
    """
    previous = getattr(_scope, "flag", None)
    _scope.flag = flag
    try:
        yield
    finally:
        _scope.flag = previous


def cancel_requested() -> bool:
    """Whether the flag of this thread's :func:`cancel_scope` is set (``False`` outside a scope)."""
    flag = getattr(_scope, "flag", None)
    return flag is not None and bool(flag[0])


def cancellable(call: Callable[[CData], Result]) -> Result:
    """``call(cancel)`` so that Ctrl-C stops the C run it makes within milliseconds.

    ``cancel`` is a ``uint32_t *`` the call passes to the C loop (``sampled_params.cancel``,
    ``continuous_params.cancel``), which polls it once per control period or step. In the main thread the call
    runs in a helper thread (cffi releases the GIL), so that the main thread stays free to receive the
    KeyboardInterrupt, set the flag, wait for the run to stop and raise the KeyboardInterrupt again. In any
    other thread the call runs in place: Python delivers Ctrl-C to the main thread only, and the flag is the
    one of the thread's :func:`cancel_scope` (a new one outside a scope), which another thread may set.
    """
    scoped = getattr(_scope, "flag", None)
    cancel = scoped if scoped is not None else cancel_flag()
    if threading.current_thread() is not threading.main_thread():
        return call(cancel)
    box: dict[str, Any] = {}

    def target() -> None:
        try:
            box["value"] = call(cancel)
        except BaseException as exc:  # handed to the main thread below
            box["error"] = exc

    worker = threading.Thread(target=target, name="flatstep C run", daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.05)
    except KeyboardInterrupt:
        cancel[0] = 1
        worker.join()
        raise
    if "error" in box:
        raise box["error"]
    return box["value"]

