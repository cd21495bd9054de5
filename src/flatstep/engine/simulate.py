"""One entry point for closed-loop runs: :func:`simulate`."""
from __future__ import annotations

from typing import Any, Optional

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from ..control.smc import FlatnessSMC
from ..model.flat import flat_to_state, polar
from ..validate import check_integer, check_positive
from ..model.motor import Load, MotorParams, acceleration, load_function, rhs
from ..plan.rest_to_rest import RestToRest
from ..loop.drive import Drive
from ..loop.observers import Observer
from ..model.plant import PlantEffects, plant_acceleration
from .result import SimResult
from ..loop.reference import DriveLoop, run_reference
from ..loop.sensors import Sensors

ENGINES = ("c", "scipy", "python")
CONTINUOUS_ENGINES = ("c", "scipy")
METHODS = ("LSODA", "Radau", "BDF", "DOP853", "RK45")


def _grid(t_end: float, knots: list[float], dt_out: float) -> list[np.ndarray]:
    """Output times split at the plan's knots so that no integration step straddles one."""
    edges = [0.0] + sorted(k for k in knots if 0.0 < k < t_end) + [t_end]
    return [np.linspace(a, b, max(2, int(round((b - a) / dt_out)) + 1)) for a, b in zip(edges[:-1], edges[1:])]


def simulate(motor: MotorParams, plan: RestToRest, controller: Optional[Any] = None, *,
             load: Load = 0.0, t_end: float = 0.06, x0: Optional[ArrayLike] = None, engine: Optional[str] = None,
             method: str = "LSODA", rtol: float = 1e-10, atol: float = 1e-12, dt_out: float = 1e-5,
             control_period: Optional[float] = None, substeps: int = 10, drive: Optional[Drive] = None,
             sensors: Optional[Sensors] = None, observer: Optional[Observer] = None,
             compute_delay: bool = False, effects: Optional[PlantEffects] = None) -> SimResult:
    """Simulate the closed loop: continuous-time control (the law evaluated inside the right-hand side) or,
    with ``control_period``, sampled control with a zero-order hold.

    Parameters
    ----------
    motor : the plant's parameters (the controller keeps its own model, ``controller.motor``).
    plan : the planned move; the run starts at t = 0 from ``x0`` (default: the plan's start equilibrium).
    controller : default :class:`~flatstep.control.smc.FlatnessSMC` with the paper's gains, ``ideal`` mode.
        The baselines of :mod:`flatstep.control` (microstepping, cascade, exact linearization) run on the
        sampled loop only (``engine="python"``, the default for them).
    load : load torque on the plant [N m], a constant or a function of time.
    t_end : horizon [s].
    engine : ``"c"``: the C core, adaptive Dormand-Prince 8(5,3) at ``rtol``/``atol`` (``method`` is not
        used); ``"scipy"``: :func:`scipy.integrate.solve_ivp` with ``method`` at ``rtol``/``atol``;
        ``"python"``: the readable sampled-loop reference (:mod:`flatstep.loop.reference`). Default (``None``): the C
        core, which runs the sampled drive loop too (sensors, observer, bus saturation, delays: C
        ``sampled_run``, held to the reference by ``tests/test_core_drive.py``), except for switched PWM,
        plant effects and the baseline controllers, which run on the Python reference loop.
    dt_out : spacing of the returned samples [s] (continuous control).
    control_period : ``None`` for continuous control; a period ``Ts`` [s] runs the controller at
        ``t = k Ts`` with the voltage held in between (C engine only), the plant integrated by ``substeps``
        RK4 steps per period, and returns the samples at the control instants (voltages as applied).
    drive, sensors, observer, compute_delay : a realistic drive around a sampled controller (they need
        ``control_period``): bus saturation and PWM (:class:`~flatstep.loop.drive.Drive`), quantized and noisy
        measurements (:class:`~flatstep.loop.sensors.Sensors`), estimated speed, acceleration and load
        (:class:`~flatstep.loop.observers.Observer`, with ``measurement="observer"``), one period of delay
        between measuring and applying.
    effects : detent torque, Coulomb friction, iron loss of the plant (:class:`~flatstep.model.plant.PlantEffects`);
        sampled loop only; the controller and observer do not know them.
    """
    if effects is not None and not effects.active:
        effects = None
    baseline = controller is not None and not isinstance(controller, FlatnessSMC)
    loop_parts = (drive is not None or sensors is not None or observer is not None or compute_delay
                  or effects is not None or baseline)
    why_not_c = _c_unsupported(controller, drive, sensors, effects) if loop_parts else None
    if engine is None:
        engine = "python" if why_not_c is not None and control_period is not None else "c"
    if engine not in ENGINES:
        raise ValueError(f"engine={engine!r} is not available; valid engines: {ENGINES}")
    if method not in METHODS:
        raise ValueError(f"method={method!r} is not a supported solve_ivp method; valid: {METHODS}")
    t_end = check_positive("t_end", t_end, unit=" s")
    dt_out = check_positive("dt_out", dt_out, unit=" s")
    for name, tol in (("rtol", rtol), ("atol", atol)):
        check_positive(name, tol)
    controller = controller if controller is not None else FlatnessSMC(motor, plan)
    tau = load_function(load)
    x0 = plan.x0(motor.Nr) if x0 is None else np.asarray(x0, dtype=float)
    if x0.shape != (4,) or not np.all(np.isfinite(x0)):
        raise ValueError(f"x0={x0!r} must be 4 finite numbers (ia, ib, omega, theta)")
    if loop_parts and control_period is None:
        raise ValueError("drive, sensors, observer, compute_delay, plant effects and the baseline controllers "
                         "run on the sampled drive loop: give control_period")
    if engine == "python":
        if control_period is None:
            raise ValueError("engine='python' is the sampled-loop reference: give control_period "
                             "(continuous control runs on engine='c' or 'scipy')")
        loop = DriveLoop(check_positive("control_period", control_period, unit=" s"), substeps, compute_delay,
                         drive, sensors, observer)
        return _simulate_python(motor, plan, controller, loop, load, t_end, x0, effects)
    if loop_parts and (engine != "c" or why_not_c is not None):
        what = why_not_c if engine == "c" else ("drive, sensors, observer, compute_delay, plant effects or "
                                                f"{type(controller).__name__}")
        raise ValueError(f"engine={engine!r} does not model {what}; use engine='python'")
    if loop_parts:
        loop = DriveLoop(check_positive("control_period", control_period, unit=" s"), substeps, compute_delay,
                         drive, sensors, observer)
        return _simulate_drive_c(motor, plan, controller, loop, load, t_end, x0)
    if engine == "c" or control_period is not None:
        return _simulate_c(motor, plan, controller, load, t_end, x0, engine, rtol, atol, dt_out,
                           control_period, substeps)

    def closed_loop(t, x):
        v = controller.voltages(t, x, acceleration(x, motor, tau(t)))
        return rhs(t, x, v, motor, load)

    ts, xs, x = [], [], x0
    for seg in _grid(t_end, [plan.t0, plan.tf], dt_out):
        sol = solve_ivp(closed_loop, (seg[0], seg[-1]), x, method=method, t_eval=seg, rtol=rtol, atol=atol)
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            raise RuntimeError(f"integration failed on [{seg[0]:.6g}, {seg[-1]:.6g}] s: {sol.message}")
        ts.append(sol.t if not ts else sol.t[1:])
        xs.append(sol.y if not xs else sol.y[:, 1:])
        x = sol.y[:, -1]
    t, X = np.concatenate(ts), np.concatenate(xs, axis=1)
    return collect(t, X, plan, controller, acceleration(X, motor, tau(t)), {"engine": engine, "method": method,
                   "rtol": rtol, "atol": atol})


def _simulate_c(motor: MotorParams, plan: RestToRest, controller: FlatnessSMC, load: Load, t_end: float,
                x0: np.ndarray, engine: str, rtol: float, atol: float, dt_out: float,
                control_period: Optional[float], substeps: int) -> SimResult:
    """The C engine: continuous (DOP853 on the output grid of :func:`_grid`) or sampled (ZOH + RK4)."""
    from .. import _core

    if engine != "c":
        raise ValueError(f"control_period={control_period!r} needs engine='c' (engine={engine!r} is continuous only)")
    if callable(load):
        raise ValueError(f"load={load!r}: engine='c' takes a constant load torque; use engine='scipy' for a function")
    tau = load_function(load)(0.0)[()]
    if control_period is None:
        segs = _grid(t_end, [plan.t0, plan.tf], dt_out)
        t = np.concatenate([segs[0]] + [s[1:] for s in segs[1:]])
        # The run, then voltages, references and sliding variables on the returned samples, in two C calls on
        # one controller struct; the status is the controller's on these samples (stats["stage_status"] also
        # counts trial stages).
        X, cols, status, stats = _core.continuous_result(controller, motor, tau, x0, t, rtol=rtol, atol=atol)
        stats = {**stats, "controller_status": _core.status_names(np.bitwise_or.reduce(status))}
        return _collect_columns(t, X, plan, controller, cols, {"engine": engine, "method": "DOP853", "rtol": rtol,
                                                                "atol": atol, **stats})
    Ts = check_positive("control_period", control_period, unit=" s")
    substeps = check_integer("substeps", substeps, why="RK4 steps per control period")
    n = max(1, math.ceil(t_end / Ts - 1e-9))
    X, V, stats = _core.run_sampled(controller, motor, tau, x0, 0.0, n, Ts=Ts, substeps=substeps)
    t = np.arange(n + 1) * Ts
    return collect(t, X, plan, controller, acceleration(X, motor, tau), {"engine": engine, "method": "RK4",
                   "control_period": Ts, "substeps": substeps, **stats}, v=V)


def _simulate_python(motor: MotorParams, plan: RestToRest, controller: Any, loop: DriveLoop, load: Load,
                     t_end: float, x0: np.ndarray, effects: Optional[PlantEffects] = None) -> SimResult:
    """The sampled drive loop reference of :mod:`flatstep.loop.reference`."""
    tau, n = _check_loop(controller, loop, load, t_end)
    r = run_reference(motor, controller, loop, x0, tau, n, effects)
    return _loop_result("python", motor, plan, controller, loop, tau, effects, r)


def _simulate_drive_c(motor: MotorParams, plan: RestToRest, controller: FlatnessSMC, loop: DriveLoop, load: Load,
                      t_end: float, x0: np.ndarray) -> SimResult:
    """The sampled drive loop on the C engine (``sampled_run``), returned as the reference returns it."""
    from .. import _core

    tau, n = _check_loop(controller, loop, load, t_end)
    substeps = check_integer("substeps", loop.substeps, why="RK4 steps per control period")
    X, V, Y, status, stats = _core.run_drive(controller, motor, tau, x0, n, Ts=loop.control_period,
                                             substeps=substeps, drive=loop.drive, sensors=loop.sensors,
                                             observer=loop.observer, compute_delay=loop.compute_delay)
    t = np.arange(n + 1) * loop.control_period
    r = {"t": t, "x": X, "v": V, "y": Y, "faults": t[(status & _core.FAULT_BITS) != 0]}
    return _loop_result("c", motor, plan, controller, loop, tau, None, r, stats)


def _c_unsupported(controller: Any, drive: Optional[Drive], sensors: Optional[Sensors],
                   effects: Optional[PlantEffects]) -> Optional[str]:
    """What of a sampled drive loop the C engine does not model (``None`` when it runs all of it)."""
    if controller is not None and not isinstance(controller, FlatnessSMC):
        return f"the {type(controller).__name__} controller"
    if effects is not None:
        return "plant effects (detent, Coulomb friction, iron loss)"
    from .. import _core

    return _core.drive_unsupported(drive, sensors)


def _check_loop(controller: Any, loop: DriveLoop, load: Load, t_end: float) -> tuple[float, int]:
    """Refuse a measurement the loop's sensors cannot provide; return the constant load and the periods."""
    if callable(load):
        raise ValueError(f"load={load!r}: the sampled loop takes a constant load torque")
    if loop.observer is not None and controller.measurement != "observer":
        raise ValueError(f"an observer needs measurement='observer' (got {controller.measurement!r})")
    if loop.observer is None and loop.sensors is not None and controller.measurement != "model":
        raise ValueError(f"with sensors and no observer no acceleration is measured: use measurement='model' "
                         f"(got {controller.measurement!r}) or add an observer")
    return float(load_function(load)(0.0)), max(1, math.ceil(t_end / loop.control_period - 1e-9))


def _loop_result(engine: str, motor: MotorParams, plan: RestToRest, controller: Any, loop: DriveLoop, tau: float,
                 effects: Optional[PlantEffects], r: dict, stats: Optional[dict] = None) -> SimResult:
    """The :class:`SimResult` of a sampled drive loop run ``r`` (``t``, ``x``, ``v``, ``y``, ``faults``)."""
    X, Y = r["x"], r["y"]
    meta = {"engine": engine, "method": "RK4", "control_period": loop.control_period, "substeps": loop.substeps,
            "compute_delay": loop.compute_delay,
            **{k: getattr(loop, k).as_dict() for k in ("drive", "sensors", "observer") if getattr(loop, k)},
            **({"effects": effects.as_dict()} if effects is not None else {}), **(stats or {})}
    result = collect(r["t"], X, plan, controller, plant_acceleration(X, motor, tau, effects), meta, v=r["v"])
    result.meta["measured"] = {"theta": Y[3], "omega": Y[2], "ddtheta": Y[4]}
    result.meta["controller_faults"] = int(r["faults"].size)
    if r["faults"].size:
        result.meta["first_fault_time"] = float(r["faults"][0])
    return result


def _collect_columns(t: np.ndarray, X: np.ndarray, plan: RestToRest, controller: FlatnessSMC, cols: dict,
                     meta: dict) -> SimResult:
    """The :class:`SimResult` of :func:`collect` from the series the C core computed (``_core.result_columns``)."""
    meta = {**meta, "controller": type(controller).__name__, "measurement": controller.measurement,
            "gains": controller.gains.as_dict(), "plan": plan.as_dict()}
    return SimResult(t=t, ia=X[0], ib=X[1], omega=X[2], theta=X[3], rho=cols["rho"], phi=cols["phi"], va=cols["va"],
                     vb=cols["vb"], theta_ref=cols["theta_ref"], omega_ref=cols["omega_ref"], rho_ref=cols["rho_ref"],
                     ia_ref=cols["ia_ref"], ib_ref=cols["ib_ref"], va_ref=cols["va_ref"], vb_ref=cols["vb_ref"],
                     s1=cols["s1"], s2=cols["s2"], meta=meta)


def collect(t: np.ndarray, X: np.ndarray, plan: RestToRest, controller: Any, acc: np.ndarray,
            meta: dict, v: Optional[np.ndarray] = None) -> SimResult:
    """Assemble a :class:`SimResult` from sampled states, recomputing voltages (unless the applied ``v``
    is given) and references vectorized; the sliding variables only for a controller that has them."""
    v = controller.voltages(t, X, acc) if v is None else v
    ref = plan.flag(t)
    x_ref, v_ref = flat_to_state(ref, controller.motor)
    rho, phi = polar(X[0], X[1])
    s1, s2 = controller.sliding_variables(t, X, acc) if hasattr(controller, "sliding_variables") else (None, None)
    meta = {**meta, "controller": type(controller).__name__, "measurement": controller.measurement,
            "gains": controller.gains.as_dict(), "plan": plan.as_dict()}
    return SimResult(t=t, ia=X[0], ib=X[1], omega=X[2], theta=X[3], rho=rho, phi=phi, va=v[0], vb=v[1],
                     theta_ref=ref.theta, omega_ref=ref.dtheta, rho_ref=ref.rho, ia_ref=x_ref[0], ib_ref=x_ref[1],
                     va_ref=v_ref[0], vb_ref=v_ref[1], s1=s1, s2=s2, meta=meta)
