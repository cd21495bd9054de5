"""Open-loop plans checked on the drive: the microstepping driver on the +-10 % plants, and the best safe trapezoid.

A plan for a step/dir drive (:func:`flatstep.plan.open_loop.open_loop_plan`, or a trapezoid of
:func:`flatstep.plan.baselines.trapezoid_rows`) runs on :class:`~flatstep.control.microstep.Microstepping` (no position
feedback) over every sign combination of +-10 % on R, L, Km, J, B (the 32 plants of ``flatstep robustness``,
:func:`~flatstep.studies.robustness.plant_errors`); it is safe when no plant loses a step (status ``ok``,
docs/errors.md). :func:`best_trapezoid` searches the constant caps of the fastest safe trapezoid: speed caps on a
grid, the largest acceleration cap by bisection on the weakest plant, the winner confirmed on all 32, then a faster
cruise and more acceleration sought by bisection.
:func:`best_profile` starts from that trapezoid and searches a speed-dependent acceleration and braking
(:func:`flatstep.plan.open_loop.profile_plan`) and the cruise speed, screening as many candidates, each kept one
confirmed on all 32 plants.
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
from ..plan.open_loop import PulloutCurve, open_loop_plan, profile_plan, speed_profile, tabulated
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
    #: The plants (their index in the ``errors`` checked) that lost a step.
    lost_plants: tuple[int, ...] = ()

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
    failed = tuple(i for i, r in enumerate(rows) if r["error"] is not None or r["status"] != "ok")
    worst = max(float(r["max_abs_theta_error"]) for r in rows if r["error"] is None) \
        if len(failed) < len(rows) else np.inf
    return PlantCheck(len(rows), len(failed), worst, failed)


def trapezoid_plan(distance: float, v_max: float, a_max: float, current: float) -> PiecewisePlan:
    """The trapezoid (or triangle) from 0 over ``distance`` > 0 at the run current."""
    rows, h = trapezoid_rows(distance, v_max, a_max)
    rho = np.zeros((rows.shape[0], NCOEF))
    rho[:, -1] = current
    return PiecewisePlan(np.concatenate([[0.0], np.cumsum(h)]), rows, rho)


#: A candidate of a search: its duration [s], its plan at a scale of its acceleration, and its caps.
Candidate = tuple[float, Callable[[float], PiecewisePlan], dict[str, float]]


class _Counter:
    """The plant runs a search has used."""

    def __init__(self) -> None:
        self.runs = 0

    def check(self, motor: MotorParams, plan: PiecewisePlan, v_bus: float, control_rate: float,
              errors: Optional[list[dict[str, float]]] = None) -> PlantCheck:
        """:func:`check_on_plants`, counted."""
        check = check_on_plants(motor, plan, v_bus, control_rate=control_rate, errors=errors)
        self.runs += check.runs
        return check


def _confirmed(candidates: list[Candidate], motor: MotorParams, v_bus: float, control_rate: float,
               what: str, counter: _Counter) -> tuple[PiecewisePlan, float, PlantCheck, dict[str, float]]:
    """The fastest candidate safe on all 32 plants, each tried at 1, 0.95, 0.9, 0.85 of its acceleration scale."""
    for _, make, caps in sorted(candidates, key=lambda c: c[0]):
        for scale in (1.0, 0.95, 0.9, 0.85):
            plan = make(scale)
            check = counter.check(motor, plan, v_bus, control_rate)
            if check.safe:
                return plan, scale, check, caps
    raise ValueError(f"no {what} kept all 32 plants")


def best_trapezoid(motor: MotorParams, v_bus: float, current: float, distance: float, *, control_rate: float = 20e3,
                   speeds: int = 8, iterations: int = 7) -> tuple[PiecewisePlan, dict[str, float], PlantCheck]:
    """The fastest constant-acceleration trapezoid that loses no step on the 32 plants, and its caps.

    Speed caps on a grid from 0.2 to 1.2 x the chopper curve's top speed; at each, the largest acceleration cap
    kept by the weakest plant (:data:`WEAKEST`), by bisection up to twice the acceleration at rest; the
    candidates, fastest first, are confirmed on all 32 plants (at 1, 0.95, 0.9, 0.85 of their acceleration) until
    one loses no step. Then refined as :func:`best_profile` seeks its cruise: at 1 and each share of
    :data:`CRUISE_CUTS` of the acceleration, the fastest cruise up to :data:`CRUISE_REACH` x by
    :data:`CRUISE_ITERATIONS` bisection steps, and then the largest acceleration up to twice, each candidate
    screened on the weakest plant and confirmed on all 32, kept if shorter. Returns the plan, its caps ``v_max``,
    ``a_max`` and the plant runs of the search ``runs`` and the candidates it screened ``candidates``, and its check.
    """
    t0 = float(pullout_torque(motor, "chopper", v_bus, current, 0.0)[0])
    w_top = top_speed(motor, "chopper", v_bus, current, 0.0)
    counter = _Counter()
    candidates: list[Candidate] = []
    for v in np.linspace(0.2, 1.2, speeds) * w_top:
        lo, hi = 0.0, 2.0 * t0 / motor.J
        for _ in range(iterations):
            a = 0.5 * (lo + hi)
            ok = counter.check(motor, trapezoid_plan(distance, float(v), a, current), v_bus, control_rate,
                               [WEAKEST]).safe
            lo, hi = (a, hi) if ok else (lo, a)
        if lo > 0:
            def make(scale: float, v: float = float(v), a: float = lo) -> PiecewisePlan:
                return trapezoid_plan(distance, v, a * scale, current)
            candidates.append((make(1.0).tf, make, {"v_max": float(v), "a_max": lo}))
    plan, scale, check, caps = _confirmed(candidates, motor, v_bus, control_rate, f"trapezoid over {distance} rad",
                                          counter)
    v_max, a_max, screened = caps["v_max"], caps["a_max"] * scale, speeds * iterations

    def kept(v: float, a: float) -> Optional[tuple[PiecewisePlan, PlantCheck]]:
        """The trapezoid and its check if it is shorter than the best and all 32 plants keep it; screened."""
        nonlocal screened
        trial = trapezoid_plan(distance, v, a, current)
        if trial.tf >= plan.tf * (1 - 1e-6):
            return None
        screened += 1
        if not counter.check(motor, trial, v_bus, control_rate, [WEAKEST]).safe:
            return None
        full = counter.check(motor, trial, v_bus, control_rate)
        return (trial, full) if full.safe else None

    for cut in (1.0,) + CRUISE_CUTS:  # a faster cruise, after a gentler acceleration, as best_profile seeks it
        lo, hi, base = v_max, CRUISE_REACH * v_max, a_max
        for _ in range(CRUISE_ITERATIONS):
            mid = 0.5 * (lo + hi)
            result = kept(mid, cut * base)
            lo, hi = (mid, hi) if result is not None else (lo, mid)
            if result is not None:
                (plan, check), v_max, a_max = result, mid, cut * base
    lo, hi = a_max, 2.0 * a_max  # then more acceleration at that cruise
    for _ in range(CRUISE_ITERATIONS):
        mid = 0.5 * (lo + hi)
        result = kept(v_max, mid)
        lo, hi = (mid, hi) if result is not None else (lo, mid)
        if result is not None:
            (plan, check), a_max = result, mid
    return plan, {"v_max": v_max, "a_max": a_max, "runs": float(counter.runs), "candidates": float(screened)}, check


#: The knots of :func:`best_profile`'s acceleration profiles, as shares of the cruise speed.
KNOTS = (0.0, 0.4, 0.7, 0.9, 1.0)
#: The steps of :func:`best_profile`'s pattern search, as shares of the value changed.
PATTERN_STEPS = (0.2, 0.1, 0.05, 0.025)
#: The shares of the acceleration with which :func:`best_profile` first seeks a faster cruise.
CRUISE_CUTS = (0.3, 0.1, 0.04)
#: That cruise is sought up to this multiple of the seed's, by this many bisection steps per share.
CRUISE_REACH, CRUISE_ITERATIONS = 1.4, 3


@dataclass(frozen=True)
class Profile:
    """A point of :func:`best_profile`'s search: cruise speed [rad/s], acceleration and braking at the knots."""

    cruise: float
    accel: tuple[float, ...]
    brake: tuple[float, ...]

    def plan(self, distance: float, current: float) -> PiecewisePlan:
        """The move of :func:`~flatstep.plan.open_loop.profile_plan` with these profiles."""
        knots = [self.cruise * k for k in KNOTS]
        return profile_plan(distance, self.cruise, speed_profile(knots, self.accel, "accel"),
                            speed_profile(knots, self.brake, "brake"), current)

    def moves(self, s: float) -> list["Profile"]:
        """The neighbours at step ``s``.

        More acceleration or braking up to each knot (kept non-increasing in the speed); a faster cruise; a faster
        cruise approached with less acceleration (at the top one, two or three knots or at all, cut to 1 - s, 0.3
        0.1 or 0.04 of it: a taper, or a gentler start that lets the rotor's load angle settle), braking as before.
        """
        out = []
        for side in ("accel", "brake"):
            values = np.array(getattr(self, side))
            for j in range(len(values)):
                raised = values.copy()
                raised[:j + 1] = np.maximum(raised[:j + 1], values[j] * (1 + s))
                out.append(Profile(**{**self.__dict__, side: tuple(float(x) for x in raised)}))
        out.append(Profile(self.cruise * (1 + s), self.accel, self.brake))
        for top, cut in product((1, 2, 3, len(KNOTS)), (1 - s, 0.3, 0.1, 0.04)):
            a = np.array(self.accel)
            a[-top:] = a[-top:] * cut
            out.append(Profile(self.cruise * (1 + s), tuple(float(x) for x in a), self.brake))
        return out


def best_profile(motor: MotorParams, v_bus: float, current: float, distance: float,
                 seed: tuple[PiecewisePlan, dict[str, float], PlantCheck], *, budget: int,
                 control_rate: float = 20e3) -> tuple[PiecewisePlan, dict[str, Any], PlantCheck]:
    """The fastest speed-dependent acceleration found that loses no step on the 32 plants, from a safe trapezoid.

    A search over :class:`Profile` (cruise speed, acceleration and braking at the :data:`KNOTS`), started at the
    trapezoid ``seed`` (:func:`best_trapezoid`'s result: constant profiles give the same plan, and its check).
    Every candidate is screened as the trapezoid's caps are, on the screening plants (at first :data:`WEAKEST`),
    and one they keep is confirmed on all 32; a plant that loses a step joins the screening plants. A candidate
    kept by all 32 and shorter than the best becomes the best.

    First the cruise: for each share of :data:`CRUISE_CUTS`, the acceleration cut to it (a gentler start that lets
    the rotor's load angle settle) and the fastest cruise held up to :data:`CRUISE_REACH` x the seed's, by
    :data:`CRUISE_ITERATIONS` bisection steps. Then a pattern search: at each step of :data:`PATTERN_STEPS`, the
    neighbours (:meth:`Profile.moves`) shorter than the best are tried, shortest first; the first kept becomes the
    best and the step starts again; a move that lost a step is not tried again at that step size; when no
    neighbour is kept, the next step. Stops when ``budget`` candidates have been screened (the trapezoid's search
    screens ``speeds x iterations``). The family holds the trapezoid: the result is never longer than the seed.
    Returns the plan, the profile (``cruise``, ``accel``, ``brake`` at ``knots`` [rad/s]) with the plant runs
    ``runs`` and the candidates screened ``candidates``, and its check.
    """
    k = len(KNOTS)
    v, a = seed[1]["v_max"], seed[1]["a_max"]
    confirmed = (Profile(v, (a,) * k, (a,) * k), seed[0], seed[2])
    everyone = plant_errors(Robustness())
    screen = [WEAKEST]
    counter = _Counter()
    screened = 0

    def kept(prof: Profile) -> Optional[tuple[Profile, PiecewisePlan, PlantCheck]]:
        """The profile, its plan and check if the screening plants and then all 32 keep it; a screened candidate."""
        nonlocal screened, screen
        screened += 1
        cand = prof.plan(distance, current)
        if not counter.check(motor, cand, v_bus, control_rate, screen).safe:
            return None
        check = counter.check(motor, cand, v_bus, control_rate)
        screen += [everyone[i] for i in check.lost_plants if everyone[i] not in screen]
        return (prof, cand, check) if check.safe else None

    for cut in CRUISE_CUTS:  # the fastest cruise held after a gentler acceleration, by bisection
        lo, hi = confirmed[0].cruise, CRUISE_REACH * confirmed[0].cruise
        for _ in range(CRUISE_ITERATIONS):
            mid = 0.5 * (lo + hi)
            trial = Profile(mid, tuple(cut * x for x in confirmed[0].accel), confirmed[0].brake)
            if screened >= budget or trial.plan(distance, current).tf >= confirmed[1].tf * (1 - 1e-6):
                break
            result = kept(trial)
            lo, hi = (mid, hi) if result is not None else (lo, mid)
            if result is not None:
                confirmed = result
    for s in PATTERN_STEPS:
        improved, failed = True, set()  # the moves that lost a step at this step size are not tried again
        while improved and screened < budget:
            improved = False
            moves = [(p.plan(distance, current), j, p) for j, p in enumerate(confirmed[0].moves(s)) if j not in failed]
            for cand, j, prof in sorted(moves, key=lambda c: c[0].tf):
                if cand.tf >= confirmed[1].tf * (1 - 1e-6) or screened >= budget:
                    continue
                failed.add(j)
                result = kept(prof)
                if result is not None:
                    confirmed, improved = result, True
                    failed.discard(j)
                    break
    prof, plan, check = confirmed
    info = {"cruise": prof.cruise, "accel": prof.accel, "brake": prof.brake,
            "knots": tuple(prof.cruise * x for x in KNOTS), "runs": counter.runs, "candidates": screened}
    return plan, info, check


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
                                          f"open-loop plan over {distance} rad", _Counter())
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
