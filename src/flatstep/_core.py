"""Thin binding to the C core (csrc/), built at install time by cffi (see _build_core.py).

Every function takes and returns NumPy arrays and makes one C call per array: no Python loop over samples.
Arrays are float64, C-contiguous, row-major ``(n, k)`` on the C side and ``(k, n)`` (components first, as
in the Python reference) on this side.
"""
from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._flatstep_core import ffi, lib
from .control.smc import FlatnessSMC, SMCGains
from .flat import FlatFlag
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


def _shape(out: np.ndarray, like: tuple) -> np.ndarray:
    """(n, k) C rows -> (k, *like) components first."""
    return out.T.reshape((out.shape[1],) + like)


def motor_struct(m: MotorParams):
    """A ``struct motor_params`` holding ``m``."""
    return ffi.new("struct motor_params *", dict(R=m.R, L=m.L, Km=m.Km, J=m.J, B=m.B, Nr=m.Nr))


def plan_struct(p: RestToRest):
    """A ``struct plan`` holding ``p``."""
    return ffi.new("struct plan *", p.as_dict())


def smc_struct(controller: FlatnessSMC, v_limit: float = V_LIMIT, rho_min: float = RHO_MIN):
    """An initialised ``struct smc`` for ``controller`` (its motor model, plan, gains and measurement)."""
    check_positive("v_limit", v_limit, unit=" V")
    check_positive("rho_min", rho_min, unit=" A")
    m, g = controller.motor, controller.gains
    params = ffi.new("struct smc_params *")
    params.motor = dict(R=m.R, L=m.L, Km=m.Km, J=m.J, B=m.B, Nr=m.Nr)
    params.plan = controller.plan.as_dict()
    params.gains = dict(W1=g.W1, W2=g.W2, eps1=g.eps1, eps2=g.eps2, xi=g.xi, wn=g.wn)
    # "ideal" and "observer" both read theta'' from y[4]; only "model" computes it from the state
    params.measurement = lib.SMC_MODEL if controller.measurement == "model" else lib.SMC_IDEAL
    params.v_limit, params.rho_min = v_limit, rho_min
    s = ffi.new("struct smc *")
    err = lib.smc_init(s, params)
    if err != lib.SMC_PARAMS_OK:
        raise ValueError(f"smc_init rejected the controller's {_PARAM_ERRORS.get(err, err)} parameters")
    return s


def plan_flag(plan: RestToRest, t: ArrayLike) -> FlatFlag:
    """C ``plan_eval`` at times ``t``; the same values as :meth:`RestToRest.flag`."""
    t_arr = np.asarray(t, dtype=np.float64)
    tv = _vec(t_arr)
    out = np.empty((tv.size, 6))
    lib.batch_plan_eval(plan_struct(plan), _in(tv), tv.size, _out(out))
    return FlatFlag(*_shape(out, t_arr.shape))


def flat_voltages(motor: MotorParams, rho: ArrayLike, drho: ArrayLike, theta: ArrayLike, dtheta: ArrayLike,
                  ddtheta: ArrayLike, dddtheta: ArrayLike, phi: ArrayLike, torque_demand: ArrayLike) -> Array:
    """C ``flat_voltages``; (2, ...) voltages, NaN where the sample is outside the maps' domain."""
    args = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in
                                 (rho, drho, theta, dtheta, ddtheta, dddtheta, phi, torque_demand)))
    rows = np.ascontiguousarray(np.stack([a.ravel() for a in args], axis=1))
    out = np.empty((rows.shape[0], 2))
    lib.batch_flat_voltages(motor_struct(motor), _in(rows), rows.shape[0], _out(out))
    return _nan_outside(_shape(out, args[0].shape), rows, motor)


def _nan_outside(v: Array, rows: np.ndarray, motor: MotorParams) -> Array:
    """Mark samples outside the domain (rho <= 0 or |A| >= Km rho) with NaN instead of the C core's 0 V."""
    rho, A = rows[:, 0], rows[:, 7]
    bad = ~((rho > 0) & (motor.Km**2 * rho**2 - A**2 > 0))
    if np.any(bad):
        v = v.copy()
        v.reshape(2, -1)[:, bad] = np.nan
    return v


def flat_to_state(flag: FlatFlag, motor: MotorParams, load_torque: float = 0.0) -> tuple[Array, Array]:
    """C ``flat_to_state``; raises ValueError (naming the sample) outside the maps' domain."""
    arrays = np.broadcast_arrays(*(np.asarray(f, dtype=np.float64) for f in flag))
    rows = np.ascontiguousarray(np.stack([a.ravel() for a in arrays], axis=1))
    x, v = np.empty((rows.shape[0], 4)), np.empty((rows.shape[0], 2))
    bad = lib.batch_flat_to_state(motor_struct(motor), _in(rows), rows.shape[0], float(load_torque), _out(x), _out(v))
    if bad:
        raise ValueError(f"{bad} sample(s) of the flat flag are outside the domain of the flat maps "
                         "(rho <= 0 or |J theta'' + B theta' + tau| >= Km rho)")
    return _shape(x, arrays[0].shape), _shape(v, arrays[0].shape)


def state_to_flat(x: ArrayLike, v: ArrayLike, motor: MotorParams, load_torque: float = 0.0) -> FlatFlag:
    """C ``state_to_flat``; raises ValueError where ia = ib = 0."""
    x_arr = np.asarray(x, dtype=np.float64)
    xr, vr = _rows(x_arr, 4, "x"), _rows(v, 2, "v")
    if xr.shape[0] != vr.shape[0]:
        raise ValueError(f"x has {xr.shape[0]} samples but v has {vr.shape[0]}")
    out = np.empty((xr.shape[0], 6))
    bad = lib.batch_state_to_flat(motor_struct(motor), _in(xr), _in(vr), xr.shape[0], float(load_torque), _out(out))
    if bad:
        raise ValueError(f"{bad} sample(s) have ia = ib = 0 (rho = 0): the flat outputs' phase is undefined there")
    return FlatFlag(*_shape(out, x_arr.shape[1:]))


def smc_voltages(controller: FlatnessSMC, t: ArrayLike, x: ArrayLike, ddtheta: Optional[ArrayLike] = None, *,
                 v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> tuple[Array, NDArray[np.uint32]]:
    """C ``smc_step`` at times ``t`` for states ``x`` (4, n) (and true theta'' in ideal mode).

    Returns the (2, n) voltages and the (n,) status bits (see :data:`STATUS_BITS`).
    """
    xr = _rows(x, 4, "x")
    n = xr.shape[0]
    if controller.measurement != "model" and ddtheta is None:
        raise ValueError(f"measurement={controller.measurement!r} needs the acceleration ddtheta; "
                         "use measurement='model' to compute it from the state")
    acc = np.zeros(n) if ddtheta is None else np.broadcast_to(np.asarray(ddtheta, dtype=np.float64).ravel(), (n,))
    y = np.ascontiguousarray(np.column_stack([xr, acc]))
    tv = np.ascontiguousarray(np.broadcast_to(_vec(t), (n,)))
    v, status = np.empty((n, 2)), np.empty(n, dtype=np.uint32)
    lib.batch_smc_step(smc_struct(controller, v_limit, rho_min), _in(tv), _in(y), n, _out(v),
                       ffi.from_buffer("uint32_t[]", status, require_writable=True))
    return np.ascontiguousarray(v.T), status


def plan_to_state(plan: RestToRest, motor: MotorParams, t: ArrayLike, load_torque: float = 0.0) -> tuple[Array, Array]:
    """C ``batch_plan_flat``: the planned state (4, n) and feedforward voltages (2, n) at the times ``t`` (1-D),
    plan and flat map in one C loop; the values of ``flat_to_state(plan_flag(plan, t), motor)``."""
    tv = _vec(t)
    flag, x, v = np.empty((tv.size, 6)), np.empty((tv.size, 4)), np.empty((tv.size, 2))
    bad = lib.batch_plan_flat(plan_struct(plan), motor_struct(motor), _in(tv), tv.size, float(load_torque),
                              _out(flag), _out(x), _out(v))
    if bad:
        raise ValueError(f"{bad} sample(s) of the plan are outside the domain of the flat maps "
                         "(|J theta'' + B theta' + tau| >= Km rho): the move is infeasible for this motor")
    return x.T, v.T


#: Names of the columns of :func:`result_columns`, in the order of ``RES_*`` in csrc/batch.h.
RESULT_COLUMNS = ("va", "vb", "acc", "rho", "phi", "theta_ref", "omega_ref", "rho_ref", "ia_ref", "ib_ref",
                  "va_ref", "vb_ref", "s1", "s2")


def result_columns(controller: FlatnessSMC, motor: MotorParams, load: float, t: ArrayLike, x: ArrayLike, *,
                   v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> tuple[dict[str, Array], NDArray[np.uint32]]:
    """C ``batch_result``: every series of a closed-loop result at the plant states ``x`` (4, n) and times ``t``
    in one C loop (the controller's voltages on the plant's acceleration, polar currents, references and
    sliding variables; :data:`RESULT_COLUMNS`), and the controller's status bits per sample."""
    xr, tv = _rows(x, 4, "x"), _vec(t)
    if tv.size != xr.shape[0]:
        raise ValueError(f"t has {tv.size} samples but x has {xr.shape[0]}")
    return _result_rows(smc_struct(controller, v_limit, rho_min), motor, load, tv, xr)


def _result_rows(ctrl, motor: MotorParams, load: float, tv: np.ndarray,
                 xr: np.ndarray) -> tuple[dict[str, Array], NDArray[np.uint32]]:
    """``batch_result`` on an initialised ``struct smc``, the times and the C rows (n, 4) of the states."""
    out, status = np.empty((tv.size, lib.RES_LEN)), np.empty(tv.size, dtype=np.uint32)
    bad = lib.batch_result(ctrl, motor_struct(motor), float(load), _in(tv), _in(xr), tv.size, _out(out),
                           ffi.from_buffer("uint32_t[]", status, require_writable=True))
    if bad:
        raise ValueError(f"{bad} sample(s) of the plan are outside the domain of the flat maps "
                         "(|J theta'' + B theta' + tau| >= Km rho): no reference state there")
    cols = out.T
    return {name: cols[k] for k, name in enumerate(RESULT_COLUMNS)}, status


#: Keys of :meth:`flatstep.result.SimResult.summary` that ``batch_sampled`` computes, in its order.
SUMMARY_KEYS = ("theta_final", "ia_final", "ib_final", "omega_final", "max_abs_theta_error", "max_abs_rho_error",
                "max_abs_va", "max_abs_vb", "final_theta_error")


def _smc_params(controller: FlatnessSMC, v_limit: float, rho_min: float) -> dict:
    m, g = controller.motor, controller.gains
    return dict(motor=dict(R=m.R, L=m.L, Km=m.Km, J=m.J, B=m.B, Nr=m.Nr), plan=controller.plan.as_dict(),
                gains=dict(W1=g.W1, W2=g.W2, eps1=g.eps1, eps2=g.eps2, xi=g.xi, wn=g.wn),
                measurement=lib.SMC_MODEL if controller.measurement == "model" else lib.SMC_IDEAL,
                v_limit=v_limit, rho_min=rho_min)


def run_sampled_summaries(runs: list[tuple[FlatnessSMC, MotorParams, float, ArrayLike, int, float, int]], *,
                          v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> list[Optional[dict]]:
    """C ``batch_sampled``: many sampled runs from t = 0 in one C call, each ``(controller, plant motor, load,
    x0, n_periods, Ts, substeps)``; returns per run the :meth:`~flatstep.result.SimResult.summary` values
    computed in C over the control instants, or None for a run that failed (controller refused, non-finite
    state). The C call releases the GIL, so threads run batches on separate cores."""
    n = len(runs)
    c_runs, out = ffi.new("struct batch_run[]", max(n, 1)), ffi.new("struct batch_summary[]", max(n, 1))
    for i, (ctrl, plant, load, x0, n_periods, Ts, substeps) in enumerate(runs):
        r = c_runs[i]
        r.ctrl = _smc_params(ctrl, v_limit, rho_min)
        r.plant = dict(motor=dict(R=plant.R, L=plant.L, Km=plant.Km, J=plant.J, B=plant.B, Nr=plant.Nr),
                       load=float(load))
        r.sp = dict(Ts=Ts, substeps=substeps)
        r.n_periods = n_periods
        r.x0 = [float(v) for v in x0]
    scratch = np.empty(6 * (max((r[4] for r in runs), default=0) + 1))
    lib.batch_sampled(c_runs, n, _out(scratch), scratch.size, out)
    rows: list[Optional[dict]] = []
    for i in range(n):
        o = out[i]
        if o.status != lib.SIM_OK:
            rows.append(None)
            continue
        row = {key: float(getattr(o, key)) for key in SUMMARY_KEYS}
        if o.n_move:
            row["max_abs_theta_error_move"] = float(o.max_abs_theta_error_move)
        if o.n_after:
            row["max_abs_theta_error_after"] = float(o.max_abs_theta_error_after)
        rows.append(row)
    return rows


def _plant(motor: MotorParams, load: float):
    return ffi.new("struct sim_plant *", dict(motor=dict(R=motor.R, L=motor.L, Km=motor.Km, J=motor.J, B=motor.B,
                                                         Nr=motor.Nr), load=float(load)))


def _stats(st, key: str) -> dict:
    return {"steps": st.steps, "rejected": st.rejected, "rhs_evals": st.rhs_evals, key: status_names(st.smc_status)}


def _check(rc: int, st, what: str) -> None:
    if rc != lib.SIM_OK:
        raise RuntimeError(f"C {what} run failed at t = {st.t_fail:.6g} s: {_SIM_ERRORS.get(rc, rc)} "
                           f"(controller status {status_names(st.smc_status)})")


#: Integrators of ``sim_continuous`` by name (``enum sim_method``): DOP853 with cubic Hermite output between
#: steps (the default), DOPRI5 with its 4th-order dense output, DOP853 with its 7th-order dense output.
CONTINUOUS_METHODS = {"DOP853": lib.SIM_DOP853, "DOPRI5": lib.SIM_DOPRI5, "DOP853-dense7": lib.SIM_DOP853_DENSE}


def run_continuous(controller: FlatnessSMC, motor: MotorParams, load: float, x0: ArrayLike, t_out: ArrayLike, *,
                   rtol: float, atol: float, h_max: float = np.inf, max_steps: int = 10_000_000,
                   method: str = "DOP853", v_limit: float = V_LIMIT, rho_min: float = RHO_MIN) -> tuple[Array, dict]:
    """C ``sim_continuous``: the (4, n) states at the nondecreasing times ``t_out`` and the run's stats
    (``stage_status``: the status bits of every controller call, trial stages of rejected steps included).

    ``method``: ``"DOP853"`` (Dormand-Prince 8(5,3); between steps the step's cubic Hermite interpolant),
    ``"DOPRI5"`` (Dormand-Prince 5(4), 4th-order dense output) or ``"DOP853-dense7"`` (DOP853 with its
    7th-order dense output, three more evaluations per step). docs/c-core.md compares their accuracy."""
    X, st = _run_continuous(smc_struct(controller, v_limit, rho_min), motor, load, x0, _vec(t_out), rtol=rtol,
                            atol=atol, h_max=h_max, max_steps=max_steps, method=method)
    return np.ascontiguousarray(X.T), st


def _run_continuous(ctrl, motor: MotorParams, load: float, x0: ArrayLike, t_out: np.ndarray, *, rtol: float,
                    atol: float, h_max: float, max_steps: int, method: str) -> tuple[np.ndarray, dict]:
    """``sim_continuous`` on an initialised ``struct smc``: the C rows (n, 4) of the states and the stats."""
    if method not in CONTINUOUS_METHODS:
        raise ValueError(f"method={method!r} is not a C integrator; valid: {tuple(CONTINUOUS_METHODS)}")
    x0 = _vec(x0)
    X = np.empty((t_out.size, 4))
    params = ffi.new("struct sim_continuous_params *", dict(rtol=rtol, atol=atol, h_max=min(h_max, 1e300),
                                                            max_steps=max_steps, method=CONTINUOUS_METHODS[method]))
    st = ffi.new("struct sim_stats *")
    rc = lib.sim_continuous(ctrl, _plant(motor, load), _in(x0), _in(t_out), t_out.size, params, _out(X), st)
    _check(rc, st, "continuous")
    return X, _stats(st, "stage_status")


def continuous_result(controller: FlatnessSMC, motor: MotorParams, load: float, x0: ArrayLike, t_out: ArrayLike,
                      *, rtol: float, atol: float, h_max: float = np.inf, max_steps: int = 10_000_000,
                      method: str = "DOP853", v_limit: float = V_LIMIT,
                      rho_min: float = RHO_MIN) -> tuple[Array, dict[str, Array], NDArray[np.uint32], dict]:
    """:func:`run_continuous` then :func:`result_columns` on its states, sharing one controller struct and the
    C rows of the states (no copy between the two calls): the (4, n) states (a view of the (n, 4) rows), the
    result's series, the controller's status bits per sample and the run's stats."""
    t_out = _vec(t_out)
    ctrl = smc_struct(controller, v_limit, rho_min)
    X, st = _run_continuous(ctrl, motor, load, x0, t_out, rtol=rtol, atol=atol, h_max=h_max, max_steps=max_steps,
                            method=method)
    lib.smc_reset(ctrl)
    cols, status = _result_rows(ctrl, motor, load, t_out, X)
    return X.T, cols, status, st


def run_sampled(controller: FlatnessSMC, motor: MotorParams, load: float, x0: ArrayLike, t_start: float,
                n_periods: int, *, Ts: float, substeps: int, v_limit: float = V_LIMIT,
                rho_min: float = RHO_MIN) -> tuple[Array, Array, dict]:
    """C ``sim_sampled``: the (4, n_periods + 1) states and (2, n_periods + 1) applied voltages at the
    control instants ``t_start + k Ts`` and the run's stats."""
    x0 = _vec(x0)
    X, V = np.empty((n_periods + 1, 4)), np.empty((n_periods + 1, 2))
    params = ffi.new("struct sim_sampled_params *", dict(Ts=Ts, substeps=substeps))
    st = ffi.new("struct sim_stats *")
    rc = lib.sim_sampled(smc_struct(controller, v_limit, rho_min), _plant(motor, load), _in(x0), float(t_start),
                         n_periods, params, _out(X), _out(V), st)
    _check(rc, st, "sampled")
    return np.ascontiguousarray(X.T), np.ascontiguousarray(V.T), _stats(st, "controller_status")


def drive_unsupported(drive=None, sensors=None) -> Optional[str]:
    """Why C ``sampled_run`` cannot run this drive (``None`` when it can): switched PWM, or a measurement
    delay beyond its ring."""
    if drive is not None and drive.pwm != "averaged":
        return f"pwm={drive.pwm!r} (switched PWM runs on the Python reference loop only)"
    if sensors is not None and sensors.delay > lib.SENSORS_MAX_DELAY:
        return f"sensors.delay={sensors.delay} periods (the C loop holds at most {lib.SENSORS_MAX_DELAY})"
    return None


def _sampled_params(controller: FlatnessSMC, Ts: float, substeps: int, drive, sensors, observer,
                    compute_delay: bool):
    """A ``struct sampled_params`` for the parts of :class:`flatstep.sampled.DriveLoop`."""
    p = ffi.new("struct sampled_params *")
    p.Ts, p.substeps = Ts, substeps
    p.sensed, p.observed = sensors is not None, observer is not None
    if sensors is not None:
        p.sensors = dict(angle_step=sensors.angle_step, encoder_offset=sensors.encoder_offset,
                         current_step=sensors.current_step, current_range=sensors.current_range,
                         current_offset=list(sensors.current_offset), delay=sensors.delay)
    if observer is not None:
        Ad, Bd, Lc = observer.matrices(controller.motor, Ts)
        n = observer.order
        p.observer.order = n
        for i in range(n):
            p.observer.Bd[i], p.observer.Lc[i] = Bd[i], Lc[i]
            for j in range(n):
                p.observer.Ad[i][j] = Ad[i, j]
    p.drive = dict(v_bus=drive.v_bus if drive is not None else np.inf, compute_delay=bool(compute_delay))
    return p


def run_drive(controller: FlatnessSMC, motor: MotorParams, load: float, x0: ArrayLike, n_periods: int, *,
              Ts: float, substeps: int, drive=None, sensors=None, observer=None, compute_delay: bool = False,
              noise: Optional[ArrayLike] = None, v_limit: float = V_LIMIT,
              rho_min: float = RHO_MIN) -> tuple[Array, Array, Array, NDArray[np.uint32], dict]:
    """C ``sampled_run``: the drive loop of :func:`flatstep.sampled.run_reference` (averaged bridge) with the
    :class:`~flatstep.drive.Drive`, :class:`~flatstep.sensors.Sensors` and :class:`~flatstep.observers.Observer`
    parts (``None``: ideal) and the (n_periods + 1, 2) current noise (default ``sensors.noise``).

    Returns the (4, n + 1) plant states, (2, n + 1) applied voltages and (5, n + 1) measurements the controller
    saw at the control instants ``k Ts``, the (n + 1,) smc_step status of each period, and the run's stats.
    """
    why = drive_unsupported(drive, sensors)
    if why is not None:
        raise ValueError(f"the C drive loop does not model {why}; use engine='python'")
    n1 = n_periods + 1
    if noise is None:
        noise = sensors.noise(n1) if sensors is not None else np.zeros((n1, 2))
    noise = np.ascontiguousarray(noise, dtype=np.float64)
    if noise.shape != (n1, 2):
        raise ValueError(f"noise has shape {noise.shape}; expected ({n1}, 2), one (ia, ib) sample per period")
    s = ffi.new("struct sampled *")
    if lib.sampled_init(s, _sampled_params(controller, Ts, substeps, drive, sensors, observer, compute_delay)):
        raise ValueError(f"sampled_init rejected the loop (control_period={Ts!r}, substeps={substeps!r}, "
                         f"sensors={sensors!r}, observer={observer!r}, drive={drive!r})")
    x0 = _vec(x0)
    X, V, Y = np.empty((n1, 4)), np.empty((n1, 2)), np.empty((n1, 5))
    status = np.empty(n1, dtype=np.uint32)
    st = ffi.new("struct sim_stats *")
    rc = lib.sampled_run(s, smc_struct(controller, v_limit, rho_min), _plant(motor, load), _in(x0), n_periods,
                         _in(noise), _out(X), _out(V), _out(Y),
                         ffi.from_buffer("uint32_t[]", status, require_writable=True), st)
    _check(rc, st, "drive loop")
    return (np.ascontiguousarray(X.T), np.ascontiguousarray(V.T), np.ascontiguousarray(Y.T), status,
            _stats(st, "controller_status"))
