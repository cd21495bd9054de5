r"""One tuner for every law: the worst-of-plants tracking error minimised under the same caps and budget.

:func:`tune` searches a controller type's gains (its law's row of :data:`flatstep.studies.tune_laws.TUNABLE`, in
decades around the scenario's own values) with SciPy's differential evolution, seeded, on a fixed budget of
evaluations. One evaluation runs the candidate on every plant of the scenario's ``[robustness]`` study (the +-10 %
corners of R, L, Km, J, B when the file has none) on the C engine, the plants in parallel
(:func:`~flatstep.studies.batch.run_batch`), and takes the worst over the plants of each metric of
:func:`flatstep.studies.compare.metrics`.

The objective and the caps (:class:`Caps`) are

.. math::

    J = \ln \max_p e_{move,p} + 10 \sum_c \max\left(0, \frac{g_c}{\bar g_c} - 1\right)
        + 20\,[\text{a plant lost, faulted or failed}]

with :math:`g_c` the worst-of-plants peak voltage, copper loss and settling time and :math:`\bar g_c` their caps:
the caps are penalties for the search, and constraints for the answer, which is the evaluated candidate with the
least error among those that meet every cap on every plant (:attr:`TuneResult.feasible` says whether any did).
The scenario's own gains are the search's first candidate, so the answer is never worse than them when they meet
the caps.

The budget is the same for every law: ``budget`` evaluations, a population of ``population`` candidates (a Latin
hypercube, seeded, with the scenario's gains in it) and ``budget // population - 1`` generations, whatever the
number of gains.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping, Optional, Sequence

import numpy as np
from numpy.typing import NDArray

from ..validate import InputError, check_integer, check_positive
from .batch import run_batch
from .compare import KEEP, default_band, metrics
from .robustness import perturbed, plant_errors
from .scenario import Scenario
from .scenario_file import Robustness
from .tune_laws import LawGains, law_gains

#: The default budget: evaluations (each on every plant) per law and scenario.
BUDGET = 120
#: The candidates of one generation.
POPULATION = 12
#: The objective's weight on the caps' relative excess, and its penalty for a plant lost, faulted or failed.
CAP_WEIGHT = 10.0
FAIL_PENALTY = 20.0


@dataclass(frozen=True)
class Caps:
    r"""The caps every law is tuned under, worst over the plants; ``None``: the default said for each.

    Parameters
    ----------
    peak_voltage : float, optional
        Peak phase voltage from the move's start on [V] (default: the drive's bus, which the drive enforces).
    copper : float, optional
        Copper loss :math:`R\int(i_a^2 + i_b^2)dt` from the move's start to the horizon [J] (default: none).
    settling : float, optional
        Settling time after the move's end into the settling band (one encoder count) [s] (default: settled
        before the horizon's end).
    """

    peak_voltage: Optional[float] = None
    copper: Optional[float] = None
    settling: Optional[float] = None

    def __post_init__(self) -> None:
        for name, unit in (("peak_voltage", " V"), ("copper", " J"), ("settling", " s")):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, check_positive(name, value, unit=unit))

    def for_scenario(self, scenario: Scenario) -> "Caps":
        """The caps with the scenario's defaults filled in: the bus for ``peak_voltage``, the horizon for settling."""
        loop = scenario.loop
        bus = loop.drive.v_bus if loop is not None and loop.drive is not None else None
        return replace(self, peak_voltage=self.peak_voltage if self.peak_voltage is not None else bus,
                       settling=self.settling if self.settling is not None
                       else scenario.t_end - scenario.plan.tf)

    def excess(self, ev: "Evaluation") -> float:
        """The sum of the relative excesses of ``ev`` over the caps (0: every cap met; infinite: not settled)."""
        total = 0.0
        for value, cap in ((ev.peak_voltage, self.peak_voltage), (ev.copper, self.copper),
                           (ev.settling, self.settling)):
            if cap is None:
                continue
            if value is None:
                return math.inf
            total += max(0.0, value / cap - 1.0)
        return total

    def as_dict(self) -> dict[str, Optional[float]]:
        """The caps by name, for JSON."""
        return {"peak_voltage": self.peak_voltage, "copper": self.copper, "settling": self.settling}


#: The caps' defaults: the bus, no copper cap, settled before the horizon's end.
DEFAULT_CAPS = Caps()


@dataclass(frozen=True)
class Evaluation:
    """One candidate's gains and its worst over the plants [rad, V, J, s] (``settling`` ``None``: not settled)."""

    gains: dict[str, float]
    move_max: float
    peak_voltage: float
    copper: float
    settling: Optional[float]
    bad_plants: int
    plants: int

    @property
    def ok(self) -> bool:
        """Every plant ran to its end, none lost or faulted."""
        return self.bad_plants == 0

    def as_dict(self) -> dict[str, Any]:
        """The evaluation by name, for JSON."""
        return {"gains": dict(self.gains), "move_max": self.move_max, "peak_voltage": self.peak_voltage,
                "copper": self.copper, "settling": self.settling, "bad_plants": self.bad_plants,
                "plants": self.plants}


@dataclass
class TuneResult:
    """What :func:`tune` found for one controller type on one scenario.

    ``best`` is the evaluated candidate with the least worst-of-plants error that meets every cap (``feasible``),
    or, if none did, the one with the least objective; ``start`` is the scenario's own gains; ``evaluations``
    every candidate evaluated, in order.
    """

    scenario: str
    kind: str
    caps: Caps
    budget: int
    seed: int
    best: Evaluation
    start: Evaluation
    feasible: bool
    evaluations: list[Evaluation] = field(repr=False)
    wall_time: float
    tuned: Scenario = field(repr=False)

    @property
    def gains(self) -> dict[str, float]:
        """The tuned gains by ``[controller]`` key."""
        return dict(self.best.gains)

    def as_dict(self) -> dict[str, Any]:
        """The result for JSON (the evaluations left out)."""
        return {"scenario": self.scenario, "kind": self.kind, "caps": self.caps.as_dict(), "budget": self.budget,
                "seed": self.seed, "evaluations": len(self.evaluations), "feasible": self.feasible,
                "wall_time_s": self.wall_time, "best": self.best.as_dict(), "start": self.start.as_dict()}


def study_of(scenario: Scenario, study: Optional[Robustness]) -> list[dict[str, float]]:
    """The plants' parameter errors: the study's, or the +-10 % corners of R, L, Km, J, B without one."""
    return plant_errors(study if study is not None else Robustness())


def evaluate(scenarios: Sequence[Scenario], errors: list[dict[str, float]], gains: Sequence[dict[str, float]],
             *, band: Optional[float] = None, **batch_options: Any) -> list[Evaluation]:
    """Each scenario (one per candidate, its ``gains``) on every plant of ``errors``, in one batch.

    ``batch_options`` go to :func:`~flatstep.studies.batch.run_batch` (``workers``, ``executor``, ...); its
    progress bar is off.
    """
    runs = [p for i, sc in enumerate(scenarios) for p in perturbed(sc, errors, f"/c{i}")]
    rows = run_batch(runs, keep=KEEP, progress=False, **batch_options) if runs else []
    n = len(errors)
    out = []
    for i, sc in enumerate(scenarios):
        b = default_band(sc) if band is None else band
        worst = {"move_max": math.nan, "peak_voltage": math.nan, "copper_loss": math.nan}
        settling: Optional[float] = 0.0
        bad = 0
        for row, run in zip(rows[i * n:(i + 1) * n], runs[i * n:(i + 1) * n], strict=True):
            if row["error"] is not None or row.get("status") != "ok":
                bad += 1
            if row["error"] is not None:
                continue
            t, e, ia, ib, va, vb = (row[f"series_{k}"] for k in KEEP)
            m = metrics(t, e, ia, ib, va, vb, sc.plan, band=b, R=run.simulated_plant.motor.R)
            worst = {k: float(np.fmax(v, m[k] or 0.0)) for k, v in worst.items()}  # fmax: NaN loses
            settled = m["settling_time"]
            settling = None if settling is None or settled is None else max(settling, settled)
        if bad == n:
            settling = None
        out.append(Evaluation(dict(gains[i]), worst["move_max"], worst["peak_voltage"], worst["copper_loss"],
                              settling, bad, n))
    return out


def objective(ev: Evaluation, caps: Caps) -> float:
    """The search's objective of an evaluation (module docstring); infinite-free: a cap never met counts 10."""
    move = ev.move_max if math.isfinite(ev.move_max) and ev.move_max > 0 else 1e3
    excess = caps.excess(ev)
    return math.log(move) + CAP_WEIGHT * min(excess, 10.0) + (FAIL_PENALTY if not ev.ok else 0.0)


class _Search:
    """The candidates' evaluations, a generation at a time, for SciPy's ``workers`` map (deferred updating)."""

    def __init__(self, scenario: Scenario, table: LawGains, errors: list[dict[str, float]], caps: Caps,
                 batch_options: Mapping[str, Any], log: Optional[Callable[[str], None]], kind: str,
                 budget: int) -> None:
        self.scenario, self.table, self.errors, self.caps = scenario, table, errors, caps
        self.batch_options, self.log, self.kind, self.budget = dict(batch_options), log, kind, budget
        self.centre = table.read(scenario)
        self.evaluations: list[Evaluation] = []
        self.costs: dict[bytes, float] = {}
        self.start = time.perf_counter()

    def gains(self, x: NDArray[np.float64]) -> dict[str, float]:
        """The gains of a search vector (decades around the scenario's values)."""
        return {g.key: self.centre[g.key] * 10.0 ** float(v) for g, v in zip(self.table.gains, x, strict=True)}

    def run(self, xs: list[NDArray[np.float64]]) -> list[Evaluation]:
        """Evaluate the candidates ``xs`` (those not yet evaluated), in one batch."""
        todo = [x for x in xs if x.tobytes() not in self.costs]
        gains = [self.gains(x) for x in todo]
        scenarios = [self.table.apply(self.scenario, g) for g in gains]
        evs = evaluate(scenarios, self.errors, gains, **self.batch_options)
        for x, ev in zip(todo, evs, strict=True):
            self.costs[x.tobytes()] = objective(ev, self.caps)
            self.evaluations.append(ev)
        if self.log is not None and todo:
            best = self.best()
            self.log(f"{self.kind}: {len(self.evaluations)}/{self.budget} evaluations, best worst-of-plants error "
                     f"{best.move_max:.4g} rad at {best.peak_voltage:.3g} V"
                     + ("" if self.feasible(best) else " (no candidate meets the caps yet)")
                     + f", {time.perf_counter() - self.start:.1f} s")
        return evs

    def map(self, func: Callable[[Any], float], xs: Any) -> list[float]:
        """SciPy's map-like ``workers``: one batch for the generation, then the cached costs."""
        xs = [np.asarray(x, dtype=float) for x in xs]
        self.run(xs)
        return [func(x) for x in xs]

    def cost(self, x: NDArray[np.float64]) -> float:
        """The objective of ``x`` (evaluated by :meth:`map` before)."""
        key = np.asarray(x, dtype=float).tobytes()
        if key not in self.costs:
            self.run([np.asarray(x, dtype=float)])
        return self.costs[key]

    def feasible(self, ev: Evaluation) -> bool:
        """Every plant ok and every cap met."""
        return ev.ok and self.caps.excess(ev) == 0.0 and math.isfinite(ev.move_max)

    def best(self) -> Evaluation:
        """The feasible evaluation with the least error, else the one with the least objective."""
        feasible = [e for e in self.evaluations if self.feasible(e)]
        if feasible:
            return min(feasible, key=lambda e: e.move_max)
        return min(self.evaluations, key=lambda e: objective(e, self.caps))


def check_budget(budget: int, population: int, source: str = "budget") -> tuple[int, int]:
    """``(budget, population)`` checked: a population of 5 or more, a budget of at least two generations."""
    population = check_integer("population", population)
    budget = check_integer(source, budget)
    if population < 5:
        raise InputError("population", population, f"population={population!r} must be >= 5 (SciPy's differential "
                         "evolution needs five candidates)")
    if budget < 2 * population:
        raise InputError(source, budget, f"{source} {budget!r} evaluations: give at least {2 * population} (two "
                         f"generations of {population} candidates)")
    return budget, population


def tune(scenario: Scenario, kind: Optional[str] = None, *, budget: int = BUDGET, seed: int = 0,
         caps: Caps = DEFAULT_CAPS, study: Optional[Robustness] = None, population: int = POPULATION,
         log: Optional[Callable[[str], None]] = None, **batch_options: Any) -> TuneResult:
    """Tune the gains of controller type ``kind`` (default: the scenario's) on the scenario's plants.

    Parameters
    ----------
    scenario : Scenario
        The scenario (a sampled drive loop: the C engine's batch runs it); its gains are the search's centre.
    kind : str, optional
        A controller type or ``law+option+...`` name; its law's row of
        :data:`~flatstep.studies.tune_laws.TUNABLE` says what is searched.
    budget : int
        Evaluations, each on every plant (the same for every law).
    seed : int
        Seeds the initial population and the search: the same seed, the same result.
    caps : Caps
        The caps (module docstring); the defaults filled in by :meth:`Caps.for_scenario`.
    study : Robustness, optional
        The plants (default: the +-10 % corners of R, L, Km, J, B).
    population : int
        Candidates per generation (>= 5).
    log : callable, optional
        Told after each generation (the progress).
    **batch_options
        For :func:`~flatstep.studies.batch.run_batch` (``workers``, ``executor``).

    Returns
    -------
    TuneResult
        The tuned gains and their worst-of-plants figures; ``tuned`` is the scenario with them.

    Raises
    ------
    InputError
        A bad ``kind``, ``budget``, ``seed``, ``population`` or ``caps``, or a scenario without a drive loop.
    """
    from scipy.optimize import differential_evolution
    from scipy.stats import qmc

    if not isinstance(scenario, Scenario):
        raise InputError("scenario", scenario, f"scenario={scenario!r} is not a flatstep Scenario")
    kind = scenario.controller_type if kind is None else kind
    table = law_gains(kind)
    budget, population = check_budget(budget, population)
    seed = check_integer("seed", seed, low=0)
    if not isinstance(caps, Caps):
        raise InputError("caps", caps, f"caps={caps!r} is not a flatstep Caps")
    if scenario.loop is None:
        raise InputError("scenario", scenario.name, f"scenario {scenario.name!r} has no drive loop ([drive] "
                         "control_rate): the tuner runs the sampled loop on the C engine")
    base = replace(scenario, controller_type=kind)
    base.controller()  # refuse a type the scenario cannot build (a missing torque model) before any run
    caps = caps.for_scenario(base)
    search = _Search(base, table, study_of(base, study), caps, batch_options, log, kind, budget)
    bounds = [(g.low, g.high) for g in table.gains]
    sample = qmc.LatinHypercube(d=len(bounds), seed=seed).random(population)
    lows, highs = np.array(bounds).T
    init = lows + sample * (highs - lows)
    init[0] = 0.0  # the scenario's own gains
    generations = budget // population - 1
    differential_evolution(search.cost, bounds, init=init, maxiter=generations, popsize=population, seed=seed,
                           polish=False, tol=0.0, atol=0.0, updating="deferred", workers=search.map)
    start = search.evaluations[0]
    best = search.best()
    return TuneResult(scenario=scenario.name, kind=kind, caps=caps, budget=budget, seed=seed, best=best,
                      start=start, feasible=search.feasible(best), evaluations=search.evaluations,
                      wall_time=time.perf_counter() - search.start, tuned=table.apply(base, best.gains))
