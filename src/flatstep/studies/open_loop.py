"""Open-loop plans checked on the drive: the microstepping driver on the +-10 % plants, and the best safe trapezoid.

A plan for a step/dir drive (:func:`flatstep.plan.open_loop.open_loop_plan`, or a trapezoid of
:func:`flatstep.plan.baselines.trapezoid_rows`) runs on :class:`~flatstep.control.microstep.Microstepping` (no position
feedback) over every sign combination of +-10 % on R, L, Km, J, B (the 32 plants of ``flatstep robustness``,
:func:`~flatstep.studies.robustness.plant_errors`); it is safe when no plant loses a step (status ``ok``,
docs/errors.md). :func:`best_trapezoid` searches the constant caps of the fastest safe trapezoid: speed caps on a
grid, the largest acceleration cap by bisection on the weakest plant, the winner confirmed on all 32.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import product
from typing import Any, Callable, Optional

import numpy as np

from ..loop.drive import Drive
from ..loop.reference import DriveLoop
from ..model.motor import MotorParams
from ..model.plant import Plant
from ..model.pullout import pullout_torque, top_speed
from ..plan.baselines import trapezoid_rows
from ..plan.open_loop import PulloutCurve, open_loop_plan, tabulated
from ..plan.piecewise import NCOEF, PiecewisePlan
from .batch import run_batch
from .robustness import plant_errors
from .scenario import Scenario
from .scenario_file import Robustness

#: The horizon after the plan's end [s]: the rotor must still be in step when it has settled.
SETTLE = 0.02
#: The plant errors under which the drive is weakest: less torque, more resistance, inductance, inertia, friction.
WEAKEST = {"R": 0.1, "L": 0.1, "Km": -0.1, "J": 0.1, "B": 0.1}


@dataclass(frozen=True)
class PlantCheck:
    """A plan on the plants: how many, how many lost a step, the worst angle error [rad] of any."""

    runs: int
    lost: int
    worst_error: float

    @property
    def safe(self) -> bool:
        """No plant lost a step and every run ended."""
        return self.lost == 0


def check_on_plants(motor: MotorParams, plan: PiecewisePlan, v_bus: float, *, control_rate: float = 20e3,
                    errors: Optional[list[dict[str, float]]] = None, load: float = 0.0, **batch: Any) -> PlantCheck:
    """The plan on the open-loop drive over the plants ``errors`` (default: the 32 corners of +-10 %)."""
    errors = plant_errors(Robustness()) if errors is None else errors
    loop = DriveLoop(control_period=1.0 / control_rate, substeps=4, drive=Drive(v_bus=v_bus))
    runs = [Scenario("open-loop", motor=motor, plan=plan, controller_type="microstep", measurement="model",
                     plant=Plant(motor.replace(**{k: getattr(motor, k) * (1 + e) for k, e in err.items()}),
                                 load=load), loop=loop, t_end=plan.tf + SETTLE) for err in errors]
    rows = run_batch(runs, progress=False, **batch)
    lost = sum(r["error"] is not None or r["status"] != "ok" for r in rows)
    worst = max(float(r["max_abs_theta_error"]) for r in rows if r["error"] is None) if lost < len(rows) else np.inf
    return PlantCheck(len(rows), lost, worst)


def trapezoid_plan(distance: float, v_max: float, a_max: float, current: float) -> PiecewisePlan:
    """The trapezoid (or triangle) from 0 over ``distance`` > 0 at the run current."""
    rows, h = trapezoid_rows(distance, v_max, a_max)
    rho = np.zeros((rows.shape[0], NCOEF))
    rho[:, -1] = current
    return PiecewisePlan(np.concatenate([[0.0], np.cumsum(h)]), rows, rho)


#: A candidate of a search: its duration [s], its plan at a scale of its acceleration, and its caps.
Candidate = tuple[float, Callable[[float], PiecewisePlan], dict[str, float]]


def _confirmed(candidates: list[Candidate], motor: MotorParams, v_bus: float, control_rate: float,
               what: str) -> tuple[PiecewisePlan, float, PlantCheck, dict[str, float]]:
    """The fastest candidate safe on all 32 plants, each tried at 1, 0.95, 0.9, 0.85 of its acceleration scale."""
    for _, make, caps in sorted(candidates, key=lambda c: c[0]):
        for scale in (1.0, 0.95, 0.9, 0.85):
            plan = make(scale)
            check = check_on_plants(motor, plan, v_bus, control_rate=control_rate)
            if check.safe:
                return plan, scale, check, caps
    raise ValueError(f"no {what} kept all 32 plants")


def best_trapezoid(motor: MotorParams, v_bus: float, current: float, distance: float, *, control_rate: float = 20e3,
                   speeds: int = 8, iterations: int = 7) -> tuple[PiecewisePlan, dict[str, float], PlantCheck]:
    """The fastest constant-acceleration trapezoid that loses no step on the 32 plants, and its caps.

    Speed caps on a grid up to the pull-out curve's top speed; at each, the largest acceleration cap kept by the
    weakest plant (:data:`WEAKEST`), by bisection up to twice the acceleration at rest; the candidates, fastest
    first, are confirmed on all 32 plants (at 1, 0.95, 0.9, 0.85 of their acceleration) until one loses no step.
    """
    t0 = float(pullout_torque(motor, "chopper", v_bus, current, 0.0)[0])
    w_top = top_speed(motor, "chopper", v_bus, current, 0.0)
    candidates: list[Candidate] = []
    for v in np.linspace(0.2, 1.2, speeds) * w_top:
        lo, hi = 0.0, 2.0 * t0 / motor.J
        for _ in range(iterations):
            a = 0.5 * (lo + hi)
            ok = check_on_plants(motor, trapezoid_plan(distance, float(v), a, current), v_bus,
                                 control_rate=control_rate, errors=[WEAKEST]).safe
            lo, hi = (a, hi) if ok else (lo, a)
        if lo > 0:
            def make(scale: float, v: float = float(v), a: float = lo) -> PiecewisePlan:
                return trapezoid_plan(distance, v, a * scale, current)
            candidates.append((make(1.0).tf, make, {"v_max": float(v), "a_max": lo}))
    plan, scale, check, caps = _confirmed(candidates, motor, v_bus, control_rate, f"trapezoid over {distance} rad")
    return plan, {"v_max": caps["v_max"], "a_max": caps["a_max"] * scale}, check


def best_open_loop(motor: MotorParams, v_bus: float, current: float, distance: float, *, control_rate: float = 20e3,
                   speeds: int = 8, iterations: int = 7,
                   pullout: Optional[PulloutCurve] = None) -> tuple[PiecewisePlan, dict[str, float], PlantCheck]:
    """The fastest plan along the pull-out curve that loses no step on the 32 plants, with its margin.

    The curve is ``pullout`` (default: the model's chopper curve). Searched as the trapezoid's caps are
    (:func:`best_trapezoid`): at each speed cap ``w_max`` of the same grid, with and without shaping, the largest
    share of the curve kept by the weakest plant, by bisection in (0, 1]; the candidates, fastest first, confirmed
    on all 32 plants (their share lowered by 5 % at a time if needed). Returns the plan, its share ``margin``, peak
    speed ``w_peak`` and ``shaping`` (1 or 0), and its check.
    """
    w_top = top_speed(motor, "chopper", v_bus, current, 0.0)
    candidates: list[Candidate] = []
    for v, shaping in product(np.linspace(0.2, 1.2, speeds) * w_top, (True, False)):
        def make(scale: float, v: float = float(v), shaping: bool = shaping) -> PiecewisePlan:
            return open_loop_plan(motor, v_bus, current, distance, margin=scale, w_max=v, pullout=pullout,
                                  shaping=shaping)
        lo, hi = 0.0, 1.0
        for _ in range(iterations):
            share = 0.5 * (lo + hi)
            try:
                ok = check_on_plants(motor, make(share), v_bus, control_rate=control_rate, errors=[WEAKEST]).safe
            except ValueError:  # the share leaves no acceleration at rest
                ok = False
            lo, hi = (share, hi) if ok else (lo, share)
        if lo > 0:
            def at(scale: float, make: Callable[[float], PiecewisePlan] = make, lo: float = lo) -> PiecewisePlan:
                return make(lo * scale)
            candidates.append((at(1.0).tf, at, {"margin": lo, "w_max": float(v), "shaping": float(shaping)}))
    plan, scale, check, caps = _confirmed(candidates, motor, v_bus, control_rate,
                                          f"open-loop plan over {distance} rad")
    peak = float(np.max(np.abs(plan.flag(np.linspace(plan.t0, plan.tf, 2001)).dtheta)))
    return plan, {"margin": caps["margin"] * scale, "w_peak": peak, "shaping": caps["shaping"]}, check


def measured_pullout(motor: MotorParams, v_bus: float, current: float, *, control_rate: float = 20e3,
                     points: int = 12) -> PulloutCurve:
    """The drive's own pull-out curve, measured on the C engine (:func:`flatstep.studies.pullout.engine_pullout`).

    At ``points`` speeds up to the field-weakening curve's top speed, on the nominal plant; :func:`tabulated`.
    """
    from .pullout import engine_pullout

    w_top = top_speed(motor, "foc_weakening", v_bus, current, 0.0)
    speeds = np.linspace(0.0, w_top, points + 1)[1:]
    torque = engine_pullout(motor, v_bus, current, speeds, control_rate=control_rate, progress=False)
    t_rest = float(pullout_torque(motor, "chopper", v_bus, current, 0.0)[0])
    return tabulated(np.concatenate([[0.0], speeds]), np.concatenate([[t_rest], torque]))
