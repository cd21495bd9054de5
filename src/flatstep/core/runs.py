"""Closed-loop runs on the C core, one C call each.

The continuous loop (``continuous_run``) and its result (``arrays_result``), the one sampled loop
(``sampled_run``) and many sampled runs at once (``batch_sampled``).

Every run takes any controller with a C twin (:func:`~flatstep.core.structs.controller_struct`) and the plant
as ``(motor, load, effects)``.
"""
from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..control.protocol import Controller
from ..control.smc import FlatnessSMC
from ..loop.drive import Drive
from ..loop.observers import Observer
from ..loop.sensors import Sensors
from ..model.motor import MotorParams, full_step
from ..model.plant import PlantEffects
from ..model.torque_model import TorqueModel
from .structs import (
    RHO_MIN,
    V_LIMIT,
    Array,
    CData,
    _check,
    _in,
    _out,
    _plant,
    _plant_fields,
    _rows,
    _stats,
    _u32,
    _vec,
    cancellable,
    controller_struct,
    ffi,
    lib,
    smc_struct,
)

#: Names of the columns of :func:`result_columns`, in the order of ``RES_*`` in csrc/arrays.h.
RESULT_COLUMNS = ("va", "vb", "acc", "rho", "phi", "theta_ref", "omega_ref", "rho_ref", "ia_ref", "ib_ref",
                  "va_ref", "vb_ref", "s1", "s2")


def result_columns(controller: FlatnessSMC, motor: MotorParams, load: float, t: ArrayLike, x: ArrayLike, *,
                   effects: Optional[PlantEffects] = None, v_limit: float = V_LIMIT,
                   rho_min: float = RHO_MIN) -> tuple[dict[str, Array], NDArray[np.uint32]]:
    """C ``arrays_result``: every series of a closed-loop result at the plant states ``x`` (4, n) and times ``t``.

    One C loop computes the controller's voltages on the plant's acceleration, polar currents, references and
    sliding variables (:data:`RESULT_COLUMNS`), and the controller's status bits per sample.
    """
    xr, tv = _rows(x, 4, "x"), _vec(t)
    if tv.size != xr.shape[0]:
        raise ValueError(f"t has {tv.size} samples but x has {xr.shape[0]}")
    return _result_rows(smc_struct(controller, v_limit, rho_min), _plant(motor, load, effects), tv, xr)


def _result_rows(ctrl: CData, plant: CData, tv: Array, xr: Array) -> tuple[dict[str, Array], NDArray[np.uint32]]:
    """``arrays_result`` on an initialised ``struct smc``, a ``struct plant``, the times and the (n, 4) states."""
    out, status = np.empty((tv.size, lib.RES_LEN)), np.empty(tv.size, dtype=np.uint32)
    bad = lib.arrays_result(ctrl, plant, _in(tv), _in(xr), tv.size, _out(out), _u32(status))
    if bad:
        raise ValueError(f"{bad} sample(s) of the plan are outside the domain of the flat maps "
                         "(|J theta'' + B theta' + tau| >= Km rho): no reference state there")
    cols = out.T
    return {name: cols[k] for k, name in enumerate(RESULT_COLUMNS)}, status


#: Integrators of ``continuous_run`` by name (``enum continuous_method``): DOP853 with cubic Hermite output
#: between steps (the default), DOPRI5 with its 4th-order dense output, DOP853 with its 7th-order dense output.
CONTINUOUS_METHODS = {"DOP853": lib.CONTINUOUS_DOP853, "DOPRI5": lib.CONTINUOUS_DOPRI5,
                      "DOP853-dense7": lib.CONTINUOUS_DOP853_DENSE}


def run_continuous(controller: Controller, motor: MotorParams, load: float, x0: ArrayLike, t_out: ArrayLike, *,
                   rtol: float, atol: float, effects: Optional[PlantEffects] = None,
                   knots: Optional[Sequence[float]] = None, h_max: float = np.inf, max_steps: int = 10_000_000,
                   method: str = "DOP853") -> tuple[Array, dict[str, Any]]:
    """C ``continuous_run``: the closed loop with ideal sensors, integrated with error control.

    Parameters
    ----------
    controller : Controller
        Any stateless controller with a C twin.
    motor : MotorParams
        The plant's motor.
    load : float
        The constant load torque [N m].
    x0 : array_like
        The start state (ia, ib, omega, theta) at ``t_out[0]``.
    t_out : array_like
        The nondecreasing output times [s].
    rtol, atol : float
        The error control's tolerances, > 0.
    effects : PlantEffects, optional
        Effects acting on the plant.
    knots : sequence of float, optional
        Where the reference's derivatives jump (default: the controller's ``plan.knots``);
        integration restarts there.
    h_max : float
        The largest step [s].
    max_steps : int
        Bound on the accepted steps over the whole run.
    method : str
        ``"DOP853"`` (Dormand-Prince 8(5,3); between steps the step's cubic Hermite interpolant), ``"DOPRI5"``
        (Dormand-Prince 5(4), 4th-order dense output) or ``"DOP853-dense7"`` (DOP853 with its 7th-order dense
        output, three more evaluations per step). docs/c-core.md compares their accuracy.

    Returns
    -------
    x : ndarray
        The (4, n) states at the times ``t_out``.
    stats : dict
        The run's stats (``stage_status``: the status bits of every controller call, trial stages of rejected
        steps included).
    """
    bound = controller_struct(controller)
    knots = controller.plan.knots if knots is None else knots
    X, st = _run_continuous(bound.iface, _plant(motor, load, effects), x0, _vec(t_out), rtol=rtol, atol=atol,
                            knots=knots, h_max=h_max, max_steps=max_steps, method=method)
    return np.ascontiguousarray(X.T), st


def _run_continuous(iface: CData, plant: CData, x0: ArrayLike, t_out: Array, *, rtol: float, atol: float,
                    knots: Sequence[float], h_max: float, max_steps: int,
                    method: str) -> tuple[Array, dict[str, Any]]:
    """``continuous_run`` on a bound controller and a ``struct plant``: the (n, 4) states and the stats."""
    if method not in CONTINUOUS_METHODS:
        raise ValueError(f"method={method!r} is not a C integrator; valid: {tuple(CONTINUOUS_METHODS)}")
    x0v = _vec(x0)
    k = _vec(sorted(float(t) for t in knots))
    X = np.empty((t_out.size, 4))
    st = ffi.new("struct sim_stats *")

    def run(cancel: CData) -> int:
        params = ffi.new("struct continuous_params *",
                         dict(rtol=rtol, atol=atol, h_max=min(h_max, 1e300), max_steps=max_steps,
                              method=CONTINUOUS_METHODS[method], knots=_in(k), n_knots=k.size, cancel=cancel))
        return int(lib.continuous_run(iface, plant, _in(x0v), _in(t_out), t_out.size, params, _out(X), st))

    rc = cancellable(run)
    _check(rc, st, "continuous")
    return X, _stats(st, "stage_status")


def continuous_result(controller: FlatnessSMC, motor: MotorParams, load: float, x0: ArrayLike, t_out: ArrayLike,
                      *, rtol: float, atol: float, effects: Optional[PlantEffects] = None, h_max: float = np.inf,
                      max_steps: int = 10_000_000,
                      method: str = "DOP853") -> tuple[Array, dict[str, Array], NDArray[np.uint32], dict[str, Any]]:
    """:func:`run_continuous` then :func:`result_columns` on its states, sharing one ``struct smc``.

    The two calls also share the C rows of the states (no copy between them). Returns the (4, n) states (a view
    of the (n, 4) rows), the result's series, the controller's status bits per sample and the run's stats.
    """
    tv = _vec(t_out)
    ctrl = smc_struct(controller, V_LIMIT, RHO_MIN)
    iface = ffi.new("struct controller *")
    lib.smc_controller(ctrl, iface)
    plant = _plant(motor, load, effects)
    X, st = _run_continuous(iface, plant, x0, tv, rtol=rtol, atol=atol,
                            knots=controller.plan.knots, h_max=h_max, max_steps=max_steps,
                            method=method)
    lib.smc_reset(ctrl)
    cols, status = _result_rows(ctrl, plant, tv, X)
    return X.T, cols, status, st


def drive_unsupported(drive: Optional[Drive] = None, sensors: Optional[Sensors] = None) -> Optional[str]:
    """Why C ``sampled_run`` cannot run this drive (``None`` when it can): a measurement delay beyond its ring."""
    if sensors is not None and sensors.delay > lib.SENSORS_MAX_DELAY:
        return f"sensors.delay={sensors.delay} periods (the C loop holds at most {lib.SENSORS_MAX_DELAY})"
    return None


def _loop_fields(model: MotorParams, Ts: float, substeps: int, drive: Optional[Drive], sensors: Optional[Sensors],
                 observer: Optional[Observer], compute_delay: bool,
                 torques: Optional[TorqueModel] = None) -> dict[str, Any]:
    """The fields of a ``struct sampled_params``: the parts of the drive loop (``None``: ideal).

    ``torques``: the controller's known torques, which the observer predicts with (``None``: none).
    """
    why = drive_unsupported(drive, sensors)
    if why is not None:
        raise ValueError(f"the C sampled loop does not model {why}; use engine='python'")
    return dict(Ts=Ts, substeps=substeps, sensed=sensors is not None, observed=observer is not None,
                model=model.c_params(), torques=torques.as_dict() if torques is not None else {},
                drive=drive.c_params(compute_delay) if drive is not None else Drive.c_ideal_params(compute_delay),
                sensors=sensors.c_params() if sensors is not None else {},
                observer=observer.c_params(model, Ts) if observer is not None else {})


def _noise(sensors: Optional[Sensors], n1: int, noise: Optional[ArrayLike]) -> Array:
    """The (n1, 2) current-noise samples of a run: given, the sensors' own, or zeros."""
    if noise is None:
        noise = sensors.noise(n1) if sensors is not None else np.zeros((n1, 2))
    out: Array = np.ascontiguousarray(noise, dtype=np.float64)
    if out.shape != (n1, 2):
        raise ValueError(f"noise has shape {out.shape}; expected ({n1}, 2), one (ia, ib) sample per period")
    return out


def run_sampled(controller: Controller, motor: MotorParams, load: float, x0: ArrayLike, n_periods: int, *,
                Ts: float, substeps: int, effects: Optional[PlantEffects] = None, drive: Optional[Drive] = None,
                sensors: Optional[Sensors] = None, observer: Optional[Observer] = None, compute_delay: bool = False,
                noise: Optional[ArrayLike] = None) -> tuple[Array, Array, Array, NDArray[np.uint32], dict[str, Any]]:
    """C ``sampled_run``: the drive loop of :func:`flatstep.loop.reference.run_reference` (averaged or switched).

    Parameters
    ----------
    controller : Controller
        Any controller with a C twin.
    motor : MotorParams
        The plant's motor.
    load : float
        The constant load torque [N m].
    x0 : array_like
        The start state (ia, ib, omega, theta) at t = 0.
    n_periods : int
        How many control periods to run.
    Ts : float
        The control period [s].
    substeps : int
        RK4 steps of the plant per period (averaged bridge).
    effects : PlantEffects, optional
        Effects acting on the plant.
    drive : Drive, optional
        Bus saturation and PWM (``None``: ideal).
    sensors : Sensors, optional
        Quantized and noisy measurements (``None``: ideal).
    observer : Observer, optional
        The speed and load observer (``None``: none).
    compute_delay : bool
        Apply each command one period after it is computed.
    noise : array_like, optional
        The (n_periods + 1, 2) current noise (default ``sensors.noise``).

    Returns
    -------
    x, v, y : ndarray
        The (4, n + 1) plant states, (2, n + 1) applied voltages and (5, n + 1) measurements the controller saw
        at the control instants ``k Ts``.
    status : ndarray
        The (n + 1,) controller status of each period.
    stats : dict
        The run's stats.
    """
    n1 = n_periods + 1
    noise_rows = _noise(sensors, n1, noise)
    fields = _loop_fields(controller.motor, Ts, substeps, drive, sensors, observer, compute_delay,
                          getattr(controller, "observer_torques", None))
    bound = controller_struct(controller)
    x0v = _vec(x0)
    X, V, Y = np.empty((n1, 4)), np.empty((n1, 2)), np.empty((n1, 5))
    status = np.empty(n1, dtype=np.uint32)
    st = ffi.new("struct sim_stats *")
    plant = _plant(motor, load, effects)

    def run(cancel: CData) -> int:
        s = ffi.new("struct sampled *")
        if lib.sampled_init(s, ffi.new("struct sampled_params *", {**fields, "cancel": cancel})):
            raise ValueError(f"sampled_init rejected the loop (control_period={Ts!r}, substeps={substeps!r}, "
                             f"sensors={sensors!r}, observer={observer!r}, drive={drive!r})")
        return int(lib.sampled_run(s, bound.iface, plant, _in(x0v), n_periods, _in(noise_rows), _out(X), _out(V),
                                   _out(Y), _u32(status), st))

    rc = cancellable(run)
    _check(rc, st, "sampled")
    return (np.ascontiguousarray(X.T), np.ascontiguousarray(V.T), np.ascontiguousarray(Y.T), status,
            _stats(st))


#: Keys of :meth:`flatstep.engine.result.SimResult.summary` that ``batch_sampled`` computes, in its order.
SUMMARY_KEYS = ("theta_final", "ia_final", "ib_final", "omega_final", "max_abs_theta_error", "max_abs_rho_error",
                "max_abs_va", "max_abs_vb", "final_theta_error")


def run_sampled_summaries(runs: Sequence[dict[str, Any]]) -> list[Optional[dict[str, Any]]]:
    """C ``batch_sampled``: many sampled runs from t = 0 in one C call.

    The C call releases the GIL, so threads run batches on separate cores.

    Parameters
    ----------
    runs : sequence of dict
        Each run as a dict of :func:`run_sampled`'s arguments (``controller``, ``motor``, ``load``, ``x0``,
        ``n_periods``, ``Ts``, ``substeps`` and optionally ``effects``, ``drive``, ``sensors``, ``observer``,
        ``compute_delay``).

    Returns
    -------
    list of dict or None
        Per run the :meth:`~flatstep.engine.result.SimResult.summary` values computed in C over the control
        instants (the status and lost_at against one full step of the plant, the count of faulted periods),
        or None for a run that failed (non-finite state, refused loop).
    """
    n = len(runs)
    c_runs, out = ffi.new("struct batch_run[]", max(n, 1)), ffi.new("struct batch_summary[]", max(n, 1))
    keep: list[Any] = []  # the controllers' C states and the noise arrays must outlive the call
    for i, r in enumerate(runs):
        ctrl, n1 = r["controller"], r["n_periods"] + 1
        bound = controller_struct(ctrl)
        noise = _noise(r.get("sensors"), n1, None)
        keep += [bound, noise]
        c = c_runs[i]
        c.ctrl = bound.iface[0]
        c.plant = _plant_fields(r["motor"], r["load"], r.get("effects"))
        c.loop = _loop_fields(ctrl.motor, r["Ts"], r["substeps"], r.get("drive"), r.get("sensors"),
                              r.get("observer"), r.get("compute_delay", False), getattr(ctrl, "observer_torques", None))
        c.reference = ctrl.plan.c_plan()
        c.n_periods = r["n_periods"]
        c.x0 = [float(v) for v in r["x0"]]
        c.noise = _in(noise)
        c.lost_error = full_step(r["motor"].Nr)
    scratch = np.empty(6 * (max((r["n_periods"] for r in runs), default=0) + 1))

    def run(cancel: CData) -> int:
        for i in range(n):
            c_runs[i].loop.cancel = cancel
        return int(lib.batch_sampled(c_runs, n, _out(scratch), scratch.size, out))

    cancellable(run)
    rows: list[Optional[dict[str, Any]]] = []
    for i in range(n):
        o = out[i]
        if o.status != lib.SIM_OK:
            rows.append(None)
            continue
        faults = int(o.fault_periods)
        row: dict[str, Any] = {"status": "lost" if o.lost else "fault" if faults else "ok",
                               "lost_at": float(o.lost_at) if o.lost else None, "controller_faults": faults}
        row.update({key: float(getattr(o, key)) for key in SUMMARY_KEYS})
        if o.n_move:
            row["max_abs_theta_error_move"] = float(o.max_abs_theta_error_move)
        if o.n_after:
            row["max_abs_theta_error_after"] = float(o.max_abs_theta_error_after)
        rows.append(row)
    return rows
