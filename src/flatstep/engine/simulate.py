"""One entry point for closed-loop runs: :func:`simulate`, dispatched through one table, one result assembler.

A run is a plant, a plan and a controller, and how time advances:

* ``loop=DriveLoop(...)``: the sampled drive loop (sensors -> observer -> controller -> drive -> plant, the
  controller fired every control period, its voltage held in between);
* ``solver=Continuous(...)`` (the default without a loop): the law evaluated inside the plant's right-hand
  side, solved adaptively.

``engine`` picks who computes it: ``"c"``, the C core (every controller, plant effect and loop part), or the
readable references: ``"python"`` for the sampled loop (:mod:`flatstep.loop.reference`), ``"scipy"`` for
the continuous loop (:func:`scipy.integrate.solve_ivp`). :data:`RUNNERS` lists the pairs.
"""
from __future__ import annotations

import math
import time
from typing import Any, Callable, NamedTuple, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import core
from ..control.protocol import Controller, SlidingController, StaticController, is_static
from ..control.smc import FlatnessSMC
from ..errors import RunError
from ..loop.reference import DriveLoop, run_reference
from ..model.flat import flat_to_state, polar
from ..model.motor import MotorParams, rhs
from ..model.plant import Plant
from ..plan.protocol import Plan, check_plan
from ..validate import check_quantity
from ..validate.limits import check_resources, check_timing, estimate
from .result import SimResult, rest_angles
from .settings import C_METHODS, SCIPY_METHODS, Continuous

Array = NDArray[np.float64]


class Run(NamedTuple):
    """What a runner hands the assembler: samples, the plant's states and what else the engine computed."""

    t: Array
    x: Array                                  # (4, n) plant states
    meta: dict[str, Any]                      # engine, method and the engine's own statistics
    v: Optional[Array] = None                 # (2, n) applied voltages (sampled runs)
    y: Optional[Array] = None                 # (5, n) what the controller saw (sampled runs)
    faults: Optional[Array] = None            # times at which the law faulted (0 V applied)
    columns: Optional[dict[str, Array]] = None  # series the C core computed (continuous FlatnessSMC runs)


#: A runner: ``(plant, plan, controller, settings, t_end, x0) -> Run``; ``settings`` is the
#: :class:`~flatstep.loop.reference.DriveLoop` of a sampled runner or the :class:`Continuous` of a continuous one.
Runner = Callable[[Plant, Plan, Controller, Any, float, Array], Run]


def simulate(plant: Union[Plant, MotorParams], plan: Plan, controller: Optional[Controller] = None, *,
             loop: Optional[DriveLoop] = None, solver: Optional[Continuous] = None, engine: str = "c",
             t_end: float = 0.06, x0: Optional[ArrayLike] = None) -> SimResult:
    """Simulate the closed loop from ``t = 0`` to ``t_end``.

    Parameters
    ----------
    plant : Plant or MotorParams
        The simulated plant (:class:`~flatstep.model.plant.Plant`: motor, effects, load); a bare
        :class:`~flatstep.model.motor.MotorParams` is a plant with no effects and no load.
    plan : Plan
        The planned move (the paper's, or a segment table such as a waypoint sequence); the run starts from
        ``x0``, by default the plan's start equilibrium.
    controller : Controller, optional
        Any controller of :mod:`flatstep.control` (:class:`~flatstep.control.protocol.Controller`); default
        :class:`~flatstep.control.smc.FlatnessSMC` with the paper's gains on the plant's motor, ``ideal``
        measurement.
    loop : DriveLoop, optional
        Run the sampled drive loop with these settings (control period, RK4 substeps, drive, sensors,
        observer, computation delay).
    solver : Continuous, optional
        Run continuous-time control with these settings (default ``Continuous()`` when there is no loop).
        Only laws without state (:func:`~flatstep.control.protocol.is_static`) run in continuous time: the
        PI integrators of the microstepping driver and of the cascade are updated once per control period.
    engine : {"c", "python", "scipy"}
        ``"c"``: the C core, for every controller and plant; ``"python"``: the readable sampled-loop
        reference; ``"scipy"``: the continuous loop on :func:`scipy.integrate.solve_ivp` (also for a load
        that is a function of time).
    t_end : float
        Horizon [s], > 0.
    x0 : array_like, optional
        Initial state ``(ia, ib, omega, theta)``.

    Returns
    -------
    SimResult
        The time series; ``meta["engine"]`` records who computed them.
    """
    plant = plant if isinstance(plant, Plant) else Plant(plant)
    check_plan(plan)
    controller = controller if controller is not None else FlatnessSMC(plant.motor, plan)
    if not isinstance(controller, Controller):
        raise ValueError(f"controller={controller!r} is not a flatstep controller (flatstep.control.protocol."
                         "Controller: FlatnessSMC, a baseline, ...)")
    for name, value, kind in (("loop", loop, DriveLoop), ("solver", solver, Continuous)):
        if value is not None and not isinstance(value, kind):
            raise ValueError(f"{name}={value!r} is not a {kind.__name__} (or None)")
    if not isinstance(engine, str):
        raise ValueError(f"engine={engine!r} must be a string: one of 'c', 'python', 'scipy'")
    if loop is not None and solver is not None:
        raise ValueError("give either loop= (sampled control) or solver= (continuous control), not both")
    timing = "sampled" if loop is not None else "continuous"
    runner = RUNNERS.get((timing, engine))
    if runner is None:
        valid = [e for (k, e) in RUNNERS if k == timing]
        raise ValueError(f"engine={engine!r} does not run {timing} control; valid: {valid}")
    t_end = check_quantity("t_end", t_end)
    x0 = plan.x0(plant.motor.Nr) if x0 is None else check_x0(x0)
    settings = loop if loop is not None else (solver or Continuous())
    check_run(plan, t_end, settings, engine)
    return assemble(runner(plant, plan, controller, settings, t_end, x0), plant, plan, controller, settings)


#: Largest |current| [A], |speed| [rad/s] and |angle| [rad] of a start state ``x0``.
X0_LIMITS = (1e3, 1e6, 1e6)


def check_x0(x0: ArrayLike) -> Array:
    """``x0`` as 4 floats, or a ValueError if it is not 4 finite numbers within :data:`X0_LIMITS`."""
    try:
        x = np.asarray(x0, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"x0={x0!r} must be 4 finite numbers (ia, ib, omega, theta)") from None
    if x.shape != (4,) or not np.all(np.isfinite(x)):
        raise ValueError(f"x0={x0!r} must be 4 finite numbers (ia, ib, omega, theta)")
    i_max, w_max, th_max = X0_LIMITS
    if max(abs(x[0]), abs(x[1])) > i_max or abs(x[2]) > w_max or abs(x[3]) > th_max:
        raise ValueError(f"x0={x.tolist()!r} is out of range: |ia|, |ib| <= {i_max:g} A, |omega| <= {w_max:g} rad/s, "
                         f"|theta| <= {th_max:g} rad")
    return x


def check_run(plan: Plan, t_end: float, settings: Union[DriveLoop, Continuous], engine: str,
              series: bool = True) -> None:
    """Refuse a run that is inconsistent, or above the resource limits of :mod:`flatstep.validate.limits`.

    Consistent: ``0 <= t0 < tf <= t_end``, and enough control periods over the move; ``series=False`` for a run
    that returns summaries only.
    """
    if isinstance(settings, DriveLoop):
        check_timing(plan.t0, plan.tf, t_end, settings.control_period)
        drive = settings.drive
        pwm = drive.pwm_periods(settings.control_period) if drive is not None and drive.pwm == "switched" else 0
        cost = estimate(t_end, control_period=settings.control_period, substeps=settings.substeps,
                        pwm_per_period=pwm)
    else:
        check_timing(plan.t0, plan.tf, t_end)
        cost = estimate(t_end, dt_out=settings.dt_out, extra_samples=2)
    check_resources(cost, engine=engine, series=series)


def _grid(t_end: float, knots: list[float], dt_out: float) -> list[Array]:
    """Output times split at the plan's knots so that no integration step straddles one."""
    tiny = 1e-12 * t_end  # a knot closer than this to an edge would make a segment below rounding level
    edges = [0.0] + sorted(k for k in knots if tiny < k < t_end - tiny) + [t_end]
    return [np.linspace(a, b, max(2, int(round((b - a) / dt_out)) + 1))
            for a, b in zip(edges[:-1], edges[1:], strict=True)]


def _constant_load(plant: Plant, engine: str) -> float:
    """The plant's load torque [N m] if it is a constant; a ValueError naming ``engine`` if it is a function."""
    load = plant.constant_load
    if load is None:
        raise ValueError(f"load={plant.load!r}: engine={engine!r} takes a constant load torque; a load that is a "
                         "function of time runs on the continuous scipy engine")
    return load


def _static(controller: Controller, engine: str) -> StaticController:
    """``controller`` as a static law, or a ValueError if it has state and so cannot run in continuous time."""
    if not is_static(controller):
        raise ValueError(f"{type(controller).__name__} has state updated once per control period: it runs on the "
                         f"sampled loop (give loop=DriveLoop(...)), not in continuous time (engine={engine!r})")
    return controller


def _continuous_c(plant: Plant, plan: Plan, controller: Controller, solver: Continuous, t_end: float,
                  x0: Array) -> Run:
    """C ``continuous_run`` (DOP853 by default) on the output grid of :func:`_grid`."""
    method = solver.method or "DOP853"
    if method not in C_METHODS:
        raise ValueError(f"method={method!r} is not a C integrator; valid: {C_METHODS} "
                         f"(engine='scipy' takes {SCIPY_METHODS})")
    _static(controller, "c")
    load = _constant_load(plant, "c")
    segs = _grid(t_end, list(plan.knots), solver.dt_out)
    t = np.concatenate([segs[0]] + [s[1:] for s in segs[1:]])
    meta = {"engine": "c", "method": method, "rtol": solver.rtol, "atol": solver.atol}
    if isinstance(controller, FlatnessSMC):
        # The run and its series (voltages, references, sliding variables) in two C calls on one controller.
        X, cols, status, stats = core.continuous_result(controller, plant.motor, load, x0, t, rtol=solver.rtol,
                                                         atol=solver.atol, effects=plant.effects,
                                                         method=method, max_steps=solver.max_steps)
        stats = {**stats, "controller_status": core.status_names(np.bitwise_or.reduce(status))}
        return Run(t, X, {**meta, **stats}, columns=cols)
    X, stats = core.run_continuous(controller, plant.motor, load, x0, t, rtol=solver.rtol, atol=solver.atol,
                                    effects=plant.effects, method=method, max_steps=solver.max_steps)
    return Run(t, X, {**meta, **stats})


def _continuous_scipy(plant: Plant, plan: Plan, controller: Controller, solver: Continuous, t_end: float,
                      x0: Array) -> Run:
    """:func:`scipy.integrate.solve_ivp`, restarted at the plan's knots."""
    from scipy.integrate import solve_ivp  # here: only the scipy engine needs it
    method = solver.method or "LSODA"
    if method not in SCIPY_METHODS:
        raise ValueError(f"method={method!r} is not a solve_ivp method; valid: {SCIPY_METHODS}")
    law = _static(controller, "scipy")
    start, calls = time.monotonic(), [0]

    def closed_loop(t: float, x: Array) -> Array:
        calls[0] += 1
        if calls[0] > solver.max_steps:
            raise RunError("max_steps", t, f"scipy {method} run stopped at t = {t:.6g} s: more than max_steps="
                           f"{solver.max_steps} right-hand-side evaluations (a stiff or diverging state)")
        if calls[0] % 256 == 0 and time.monotonic() - start > solver.max_wall_time:
            raise RunError("wall_time", t, f"scipy {method} run stopped at t = {t:.6g} s: it took longer than "
                           f"max_wall_time={solver.max_wall_time:g} s")
        v = law.voltages(t, x, plant.acceleration(x, t))
        dx = rhs(t, x, v, plant.motor, plant.load)
        if plant.effects is not None:
            dx[2] = dx[2] + plant.effects.torque(x[2], x[3], plant.motor) / plant.motor.J
        return dx

    ts: list[Array] = []
    xs: list[Array] = []
    x = x0
    for seg in _grid(t_end, list(plan.knots), solver.dt_out):
        sol = solve_ivp(closed_loop, (seg[0], seg[-1]), x, method=method, t_eval=seg, rtol=solver.rtol,
                        atol=solver.atol)
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            reason = "nonfinite" if not np.all(np.isfinite(sol.y)) else "step_size"
            reached = np.asarray(sol.t, dtype=float)
            raise RunError(reason, float(reached[-1]) if reached.size else float(seg[0]),
                           f"scipy {method} integration failed on [{seg[0]:.6g}, {seg[-1]:.6g}] s: {sol.message}")
        ts.append(sol.t if not ts else sol.t[1:])
        xs.append(sol.y if not xs else sol.y[:, 1:])
        x = sol.y[:, -1]
    meta = {"engine": "scipy", "method": method, "rtol": solver.rtol, "atol": solver.atol}
    return Run(np.concatenate(ts), np.concatenate(xs, axis=1), meta)


def _check_measurement(controller: Controller, loop: DriveLoop) -> None:
    """Refuse a measurement the loop's sensors cannot provide."""
    if loop.observer is not None and controller.measurement != "observer":
        raise ValueError(f"an observer needs measurement='observer' (got {controller.measurement!r})")
    if loop.observer is None and loop.sensors is not None and controller.measurement != "model":
        raise ValueError(f"with sensors and no observer no acceleration is measured: use measurement='model' "
                         f"(got {controller.measurement!r}) or add an observer")


def _periods(loop: DriveLoop, t_end: float) -> int:
    """The number of control periods that cover ``[0, t_end]`` (at least one)."""
    return max(1, math.ceil(t_end / loop.control_period - 1e-9))


def _sampled_c(plant: Plant, plan: Plan, controller: Controller, loop: DriveLoop, t_end: float,
               x0: Array) -> Run:
    """C ``sampled_run``: any controller, any plant effect, any loop part (switched PWM included)."""
    _check_measurement(controller, loop)
    n = _periods(loop, t_end)
    X, V, Y, status, stats = core.run_sampled(
        controller, plant.motor, _constant_load(plant, "c"), x0, n, Ts=loop.control_period,
        substeps=loop.substeps, effects=plant.effects, drive=loop.drive, sensors=loop.sensors,
        observer=loop.observer, compute_delay=loop.compute_delay)
    t = np.arange(n + 1, dtype=np.float64) * np.float64(loop.control_period)
    return Run(t, X, {"engine": "c", "method": "RK4", **stats}, v=V, y=Y,
               faults=t[(status & core.FAULT_BITS) != 0])


def _sampled_python(plant: Plant, plan: Plan, controller: Controller, loop: DriveLoop, t_end: float,
                    x0: Array) -> Run:
    """The readable reference of :mod:`flatstep.loop.reference`."""
    _check_measurement(controller, loop)
    n = _periods(loop, t_end)
    r = run_reference(plant.motor, controller, loop, x0, _constant_load(plant, "python"), n, plant.effects)
    return Run(r["t"], r["x"], {"engine": "python", "method": "RK4"}, v=r["v"], y=r["y"], faults=r["faults"])


#: Who runs what: ``(timing, engine) -> runner``.
RUNNERS: dict[tuple[str, str], Runner] = {
    ("continuous", "c"): _continuous_c,
    ("continuous", "scipy"): _continuous_scipy,
    ("sampled", "c"): _sampled_c,
    ("sampled", "python"): _sampled_python,
}


def assemble(run: Run, plant: Plant, plan: Plan, controller: Controller,
             settings: Union[DriveLoop, Continuous]) -> SimResult:
    """The one place a :class:`~flatstep.engine.result.SimResult` is built.

    It holds the run's samples, the plan's references through the flat maps (vectorized), the voltages
    (applied, or the law's on the samples), the sliding variables of a controller that has them, and the
    metadata.
    """
    t, X = run.t, run.x
    meta = {**settings.as_dict(), **run.meta, "controller": type(controller).__name__,
            "measurement": controller.measurement, "gains": controller.gains.as_dict(),
            "plan": {**plan.as_dict(), "rests": rest_angles(plan)}, "plant": plant.as_dict()}
    if run.y is not None:
        meta["measured"] = {"theta": run.y[3], "omega": run.y[2], "ddtheta": run.y[4]}
    if run.faults is not None:
        meta["controller_faults"] = int(run.faults.size)
        if run.faults.size:
            meta["first_fault_time"] = float(run.faults[0])
    cols = run.columns
    if cols is not None:
        return SimResult(t=t, ia=X[0], ib=X[1], omega=X[2], theta=X[3], rho=cols["rho"], phi=cols["phi"],
                         va=cols["va"], vb=cols["vb"], theta_ref=cols["theta_ref"], omega_ref=cols["omega_ref"],
                         rho_ref=cols["rho_ref"], ia_ref=cols["ia_ref"], ib_ref=cols["ib_ref"],
                         va_ref=cols["va_ref"], vb_ref=cols["vb_ref"], s1=cols["s1"], s2=cols["s2"], meta=meta)
    acc = plant.acceleration(X, t)
    if run.v is not None:
        v = run.v
    elif is_static(controller):  # a run without applied voltages is a continuous one: the runners take static laws
        v = controller.voltages(t, X, acc)
    else:
        raise ValueError(f"{type(controller).__name__} has state: a run without applied voltages needs a static law")
    ref = plan.flag(t)
    x_ref, v_ref = flat_to_state(ref, controller.motor)
    rho, phi = polar(X[0], X[1])
    s1, s2 = controller.sliding_variables(t, X, acc) if isinstance(controller, SlidingController) else (None, None)
    return SimResult(t=t, ia=X[0], ib=X[1], omega=X[2], theta=X[3], rho=rho, phi=phi, va=v[0], vb=v[1],
                     theta_ref=ref.theta, omega_ref=ref.dtheta, rho_ref=ref.rho, ia_ref=x_ref[0], ib_ref=x_ref[1],
                     va_ref=v_ref[0], vb_ref=v_ref[1], s1=s1, s2=s2, meta=meta)
