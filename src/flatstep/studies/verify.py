r"""A plan the drive can follow: run it on the drive, on the nominal plant and on the corners of its uncertainty.

A plan within its limits (:func:`~flatstep.plan.margins.plan_margins`) can still be lost on a sampled drive: the
limits are a model, the drive samples, the encoder quantizes and the plant is not the model.
:func:`verify_scenario` runs a scenario as ``flatstep simulate`` runs it (:meth:`Scenario.run
<flatstep.studies.scenario.Scenario.run>`: its own controller, sensors, observer, plant effects, load and drive)
on its plant and on the :math:`2^4` corners of :math:`\pm\delta` on that plant's R, L, Km and J (the
controller's model nominal); :func:`verify_plan` does the same for a bare plan on a
:class:`~flatstep.loop.reference.DriveLoop` with :func:`drive_controller`. The plan is verified when every case
ends ``ok``; otherwise the first case lost or faulted names the limit that binds where it went wrong
(:func:`binding`).

:mod:`flatstep.studies.backoff` plans, checks and backs off: the binding limit is tightened and the plan re-planned;
then it refuses, naming the limit and what to change.

A scenario file is checked with its own controller (:func:`~flatstep.studies.backoff.check_on_drive`): the plan
``flatstep plan`` reports feasible is the plan ``flatstep simulate`` runs, with the same law, on the same drive. A
bare plan without a controller (:func:`verify_plan`) is checked with :func:`drive_controller`: the flatness +
sliding-mode law with the gains and the observer of :func:`~flatstep.loop.design.design_gains` for the drive.
"""
from __future__ import annotations

import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from itertools import product
from typing import Any, Callable, Optional

import numpy as np

from ..control.protocol import Controller
from ..control.smc import FlatnessSMC, SMCGains
from ..engine.simulate import simulate
from ..errors import RunError
from ..loop.design import design_gains
from ..loop.drive import Drive
from ..loop.reference import DriveLoop
from ..loop.sensors import Sensors
from ..model.motor import MotorParams
from ..plan.limits import COMMUTATION_ANGLE, MotorLimits
from ..plan.piecewise import PiecewisePlan
from ..validate import check_finite
from .scenario import Scenario

#: The parameters the uncertainty scales, as :mod:`flatstep.studies.robustness` names them.
PARAMETERS = ("R", "L", "Km", "J")
#: The time run after the plan's end [s], for the rotor to settle (a lost arrival shows there).
T_AFTER = 0.02
#: What to change when a limit binds.
ADVICE = {"commutation rate": "raise the drive's control rate, or lower speed_max",
          "voltage at speed": "raise v_bus, or lower v_use or speed_max",
          "torque angle": "lower torque_angle_max or accel_max, or raise i_max",
          "current": "raise i_max (a motor and drive rated for more current), or lower accel_max",
          "tracking on the drive": "raise the control rate, use a finer encoder, or lower speed_max"}
#: Added to the advice when the scenario's sliding law runs the default gains (the paper's, for its motor in
#: continuous time), not gains designed for this motor and drive.
DESIGN_ADVICE = "; the law runs the default gains: design them for this motor and drive ([controller] design = true)"


@dataclass(frozen=True)
class Case:
    """One run of the check: the plant's relative errors, its status and its worst angle error."""

    errors: dict[str, float]
    status: str
    max_abs_theta_error: float
    lost_at: Optional[float] = None
    controller_faults: int = 0
    #: when it went wrong: lost_at, the first fault, or when the run stopped [s]
    t_wrong: Optional[float] = None

    @property
    def label(self) -> str:
        """``nominal`` or the errors, e.g. ``R+0.1,L-0.1,Km+0.1,J+0.1``."""
        return ",".join(f"{k}{e:+.3g}" for k, e in self.errors.items()) or "nominal"

    def as_dict(self) -> dict[str, Any]:
        """The case for JSON."""
        return dict(plant=self.label, status=self.status, max_abs_theta_error=self.max_abs_theta_error,
                    lost_at=self.lost_at, controller_faults=self.controller_faults)


@dataclass(frozen=True)
class Verdict:
    """The check's result: every case, whether all ended ``ok``, and when not, what binds and what to change."""

    verified: bool
    cases: list[Case]
    seconds: float
    binds: Optional[str] = None
    advice: Optional[str] = None
    rounds: list[dict[str, Any]] = field(default_factory=list)
    #: the law the cases ran (a scenario's controller type, or ``drive_controller``'s)
    controller: str = "smc (gains and observer designed for the drive)"
    #: the relative error of R, L, Km and J of the corners
    uncertainty: float = 0.1

    @property
    def plants(self) -> str:
        """The plants the cases ran, in words: ``17 plants (nominal and +-10 % on R, L, Km, J)``."""
        if self.uncertainty == 0:
            return "1 plant (nominal)"
        return f"{len(self.cases)} plants (nominal and +-{100 * self.uncertainty:g} % on {', '.join(PARAMETERS)})"

    @property
    def worst_error(self) -> float:
        """The largest |theta - theta*| of any case [rad]."""
        return max(c.max_abs_theta_error for c in self.cases)

    @property
    def status(self) -> str:
        """``ok`` when verified, else the worst status of the cases (``failed`` > ``lost`` > ``fault``)."""
        for s in ("failed", "lost", "fault"):
            if any(c.status == s for c in self.cases):
                return s
        return "ok"

    def as_dict(self) -> dict[str, Any]:
        """The verdict for JSON (plan.json's ``verify``)."""
        return dict(verified=self.verified, status=self.status, controller=self.controller, plants=self.plants,
                    uncertainty=self.uncertainty, worst_error=self.worst_error if self.cases else None,
                    binds=self.binds, advice=self.advice, seconds=self.seconds,
                    cases=[c.as_dict() for c in self.cases], rounds=self.rounds)


def plant_corners(motor: MotorParams, uncertainty: float = 0.1) -> list[tuple[dict[str, float], MotorParams]]:
    """The nominal plant, then the :math:`2^4` corners of +-``uncertainty`` on R, L, Km and J."""
    delta = check_finite("uncertainty", uncertainty)
    if not 0 <= delta < 0.5:
        raise ValueError(f"uncertainty={delta!r} must be in [0, 0.5): the relative error of R, L, Km and J")
    out: list[tuple[dict[str, float], MotorParams]] = [({}, motor)]
    if delta == 0:
        return out
    for signs in product((1.0, -1.0), repeat=len(PARAMETERS)):
        err = {k: s * delta for k, s in zip(PARAMETERS, signs, strict=True)}
        out.append((err, motor.replace(**{k: getattr(motor, k) * (1 + e) for k, e in err.items()})))
    return out


def drive_loop(v_bus: float, control_rate: float, encoder_counts: Optional[int] = 4000,
               sensors: Optional[Sensors] = None) -> DriveLoop:
    """A sampled drive: the bus, the control rate, 4 RK4 substeps, an encoder (and a 12-bit current ADC)."""
    parts = sensors if sensors is not None else Sensors(encoder_counts=encoder_counts)
    return DriveLoop.at(control_rate, substeps=4, drive=Drive(v_bus=v_bus), sensors=parts)


def drive_controller(motor: MotorParams, plan: PiecewisePlan, loop: DriveLoop,
                     uncertainty: float = 0.1) -> tuple[Controller, DriveLoop]:
    """The flatness + sliding-mode law with gains and observer designed for this drive, and the loop with it.

    :func:`~flatstep.loop.design.design_gains` for the loop's control period, bus, encoder and ADC step and
    the uncertainty; the controller measures through the designed observer (the loop's own observer, if it has
    one, is kept).
    """
    v_bus = loop.drive.v_bus if loop.drive is not None else 24.0
    sensors = loop.sensors
    d = design_gains(motor, plan, control_period=loop.control_period, v_bus=v_bus,
                     encoder_counts=sensors.encoder_counts if sensors is not None else None,
                     current_step=sensors.current_step if sensors is not None and sensors.current_step else 4 / 4096,
                     uncertainty=uncertainty)
    loop = loop if loop.observer is not None else replace(loop, observer=d.observer)
    return FlatnessSMC(motor, plan, d.gains, "observer"), loop


def _case(errors: dict[str, float], run: Callable[[], Any]) -> Case:
    """One case: ``run()`` on the C engine, its status, worst error and when it went wrong; a stop is ``failed``."""
    try:
        r = run()
    except RunError as exc:
        return Case(errors, "failed", math.inf, t_wrong=exc.t_fail)
    faults = int(r.meta.get("controller_faults", 0))
    first_fault = r.meta.get("first_fault_time")
    t_wrong = r.lost_at if r.lost_at is not None else first_fault
    return Case(errors, r.status, float(np.max(np.abs(r.theta_error))), r.lost_at, faults,
                None if t_wrong is None else float(t_wrong))


def _run(plant: MotorParams, plan: PiecewisePlan, controller: Controller, loop: DriveLoop,
         errors: dict[str, float]) -> Case:
    """One case of a bare plan on the drive ``loop``."""
    return _case(errors, lambda: simulate(plant, plan, controller, loop=loop, t_end=plan.tf + T_AFTER))


def _run_scenario(scenario: Scenario, errors: dict[str, float]) -> Case:
    """One case as ``flatstep simulate`` runs it (:meth:`Scenario.run`)."""
    return _case(errors, scenario.run)


def _run_all(run: Callable[[Any], Case], corners: list[Any], workers: Optional[int]) -> list[Case]:
    """``run`` of every corner, in their order, on ``workers`` threads (default: the CPUs, at most 2)."""
    with ThreadPoolExecutor(max_workers=workers or min(2, os.cpu_count() or 1)) as pool:
        return list(pool.map(run, corners))


def scenario_corners(scenario: Scenario, uncertainty: float = 0.1) -> list[tuple[dict[str, float], Scenario]]:
    """The scenario on its own plant, then on the :math:`2^4` corners of +-``uncertainty`` on that plant's R, L, Km, J.

    The plant keeps its effects and load; the controller keeps its model (``scenario.motor``) nominal.
    """
    plant = scenario.simulated_plant
    return [(err, scenario if not err else replace(scenario, plant=replace(plant, motor=m)))
            for err, m in plant_corners(plant.motor, uncertainty)]


def controller_label(scenario: Scenario) -> str:
    """The scenario's law in words: its controller type, measurement, and for the sliding laws whose gains."""
    if "smc" not in scenario.controller_type:
        return f"{scenario.controller_type} (tuned for the drive by rule, {scenario.measurement} measurement)"
    gains = "default gains" if scenario.gains == SMCGains() else "the file's gains"
    return f"{scenario.controller_type} ({gains}, {scenario.measurement} measurement)"


def verify_scenario(scenario: Scenario, uncertainty: float = 0.1, limits: Optional[MotorLimits] = None,
                    workers: Optional[int] = None) -> Verdict:
    """Run ``scenario`` as ``flatstep simulate`` runs it, on its plant and on the corners of ``uncertainty``.

    Parameters
    ----------
    scenario : Scenario
        The run: plan, controller (type, gains, measurement, known torques), drive loop, sensors, observer, plant
        (effects and load) and horizon, exactly as :meth:`Scenario.run` simulates it.
    uncertainty : float
        The relative error of the plant's R, L, Km and J (0.1: +-10 %; 0: the plant only).
    limits : MotorLimits, optional
        The limits the plan was made with, to name the one that binds.
    workers : int, optional
        Threads running the cases (the C runs release the GIL); default: the CPUs, at most 2.

    Returns
    -------
    Verdict
        Verified when every case ends ``ok``; otherwise what binds and what to change.
    """
    start = time.perf_counter()
    cases = _run_all(lambda c: _run_scenario(c[1], c[0]), scenario_corners(scenario, uncertainty), workers)
    verified = all(c.status == "ok" for c in cases)
    binds = advice = None
    if not verified:
        plan = scenario.plan.to_table()
        binds = binding(plan, scenario.motor, scenario.loop, limits, cases)
        advice = ADVICE[binds]
        if scenario.gains == SMCGains() and "smc" in scenario.controller_type:
            advice += DESIGN_ADVICE
    return Verdict(verified, cases, time.perf_counter() - start, binds, advice,
                   controller=controller_label(scenario), uncertainty=uncertainty)


def verify_plan(plan: PiecewisePlan, motor: MotorParams, loop: DriveLoop, controller: Optional[Controller] = None,
                uncertainty: float = 0.1, limits: Optional[MotorLimits] = None,
                workers: Optional[int] = None) -> Verdict:
    """Run ``plan`` on the drive ``loop`` on the nominal plant and the corners of ``uncertainty``.

    Parameters
    ----------
    plan : PiecewisePlan
        The plan to check.
    motor : MotorParams
        The nominal motor: the controller's model, and the plant the corners are taken around.
    loop : DriveLoop
        The drive: control period, bus, sensors (and observer).
    controller : Controller, optional
        The law; default :func:`drive_controller` (which also adds its observer to the loop).
    uncertainty : float
        The relative error of R, L, Km and J (0.1: +-10 %; 0: the nominal plant only).
    limits : MotorLimits, optional
        The limits the plan was made with, to name the one that binds (without them: the bus of the loop).
    workers : int, optional
        Threads running the cases (the C runs release the GIL); default: the CPUs, at most 2.

    Returns
    -------
    Verdict
        Verified when every case ends ``ok``; otherwise what binds and what to change.
    """
    start = time.perf_counter()
    ctrl, loop = drive_controller(motor, plan, loop, uncertainty) if controller is None else (controller, loop)
    cases = _run_all(lambda c: _run(c[1], plan, ctrl, loop, c[0]), plant_corners(motor, uncertainty), workers)
    verified = all(c.status == "ok" for c in cases)
    binds = advice = None
    if not verified:
        binds = binding(plan, motor, loop, limits, cases)
        advice = ADVICE[binds]
    label = "smc (gains and observer designed for the drive)" if controller is None else type(ctrl).__name__
    return Verdict(verified, cases, time.perf_counter() - start, binds, advice, controller=label,
                   uncertainty=uncertainty)


def binding(plan: PiecewisePlan, motor: MotorParams, loop: Optional[DriveLoop], limits: Optional[MotorLimits],
            cases: list[Case]) -> str:
    r"""The limit that binds where the first case went wrong (one of :data:`ADVICE`'s keys).

    The plan is looked at over the 2 ms before that instant: a torque demand near
    :math:`K_m\rho^*\sin\alpha_{max}` binds the torque angle; a speed near the commutation cap
    (:data:`~flatstep.plan.limits.COMMUTATION_ANGLE` electrical radians per period) the commutation rate; a
    feedforward near the bus the voltage; a current near ``i_max`` the current; none of these, tracking on the drive.
    """
    bad = [c for c in cases if c.status != "ok"]
    times = [c.t_wrong for c in bad if c.t_wrong is not None]
    tb = min(times) if times else plan.tf
    t = np.linspace(max(plan.t0, tb - 2e-3), min(max(tb, plan.t0 + 1e-6), plan.tf), 200)
    f = plan.flag(t)
    torque_ratio = float(np.max(np.abs(motor.J * f.ddtheta + motor.B * f.dtheta) / (motor.Km * f.rho)))
    alpha = limits.torque_angle_max if limits is not None else 1.2
    if torque_ratio >= 0.9 * math.sin(alpha):
        return "torque angle"
    speed = float(np.max(np.abs(f.dtheta)))
    if loop is not None and motor.Nr * speed * loop.control_period >= 0.9 * COMMUTATION_ANGLE:
        return "commutation rate"
    drive = loop.drive if loop is not None else None
    v_bus = limits.v_bus if limits is not None else (drive.v_bus if drive is not None else math.inf)
    emf = motor.Km * speed + motor.Nr * speed * motor.L * float(np.max(f.rho)) + motor.R * float(np.max(f.rho))
    if emf >= 0.75 * v_bus:
        return "voltage at speed"
    if limits is not None and float(np.max(f.rho)) >= 0.95 * limits.i_max:
        return "current"
    return "tracking on the drive"
