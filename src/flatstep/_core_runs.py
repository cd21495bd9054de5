"""Closed-loop runs on the C core: continuous (``sim_continuous``) and its result (``batch_result``), sampled
(``sim_sampled``, ``batch_sampled`` for many runs) and the sampled drive loop (``sampled_run``)."""
from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._core_structs import (RHO_MIN, V_LIMIT, Array, _check, _in, _motor, _out, _plant, _rows, _smc_params, _stats,
                            _u32, _vec, ffi, lib, motor_struct, smc_struct)
from .control.smc import FlatnessSMC
from .motor import MotorParams

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
                           _u32(status))
    if bad:
        raise ValueError(f"{bad} sample(s) of the plan are outside the domain of the flat maps "
                         "(|J theta'' + B theta' + tau| >= Km rho): no reference state there")
    cols = out.T
    return {name: cols[k] for k, name in enumerate(RESULT_COLUMNS)}, status


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


#: Keys of :meth:`flatstep.result.SimResult.summary` that ``batch_sampled`` computes, in its order.
SUMMARY_KEYS = ("theta_final", "ia_final", "ib_final", "omega_final", "max_abs_theta_error", "max_abs_rho_error",
                "max_abs_va", "max_abs_vb", "final_theta_error")


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
        r.plant = dict(motor=_motor(plant), load=float(load))
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
                         _u32(status), st)
    _check(rc, st, "drive loop")
    return (np.ascontiguousarray(X.T), np.ascontiguousarray(V.T), np.ascontiguousarray(Y.T), status,
            _stats(st, "controller_status"))
