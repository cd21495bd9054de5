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

**Early stop.** From the second generation on, each trial candidate runs the plants in rounds (:data:`ROUNDS`),
the plants that were worst for the best candidate so far first, and goes on to the next round only if it can still
win. Differential evolution (deferred updating) keeps a trial only if its objective is no larger than that of the
population member it challenges; the worst over a subset of the plants is a lower bound of the worst over all
(every term of :math:`J` grows with the plants, while every plant run so far is ok), so a trial whose lower bound
already exceeds its challenger's objective, and which cannot be the answer either (it already breaks a cap, or its
error already exceeds the best feasible one's), is stopped: the search takes the same path, candidate for
candidate, as with every plant run, and the answer is the same. A stopped evaluation counts toward the budget; its
figures (:attr:`Evaluation.complete` false) are of the plants it ran and are never an answer. The plants are
independent runs, so the result does not depend on the number of threads.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping, Optional, Sequence

import numpy as np
from numpy.typing import NDArray

from ..validate import InputError, check_bool, check_integer, check_positive
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
#: The early stop's rounds (module docstring): after each of these shares of the plants (at least one plant), a
#: trial that can no longer win stops.
ROUNDS = (0.125, 0.5)
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
    """One candidate's gains and its worst over the plants [rad, V, J, s] (``settling`` ``None``: not settled).

    ``evaluated`` is the number of plants run (``None``: all ``plants``); fewer for an evaluation the search stopped
    early (module docstring), whose figures are those of the plants it ran.
    """

    gains: dict[str, float]
    move_max: float
    peak_voltage: float
    copper: float
    settling: Optional[float]
    bad_plants: int
    plants: int
    evaluated: Optional[int] = None

    @property
    def ok(self) -> bool:
        """Every plant run ran to its end, none lost or faulted."""
        return self.bad_plants == 0

    @property
    def complete(self) -> bool:
        """Every plant was run (the evaluation was not stopped early)."""
        return self.evaluated is None or self.evaluated == self.plants

    def as_dict(self) -> dict[str, Any]:
        """The evaluation by name, for JSON."""
        return {"gains": dict(self.gains), "move_max": self.move_max, "peak_voltage": self.peak_voltage,
                "copper": self.copper, "settling": self.settling, "bad_plants": self.bad_plants,
                "plants": self.plants, "evaluated": self.plants if self.evaluated is None else self.evaluated}


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


#: One plant's run of one candidate: ``(move_max, peak_voltage, copper, settling, bad)`` (NaN figures and
#: ``settling`` ``None`` for a run that failed).
PlantRun = tuple[float, float, float, Optional[float], bool]


def run_plants(runs: Sequence[Scenario], bands: Sequence[float], **batch_options: Any) -> list[PlantRun]:
    """Each run (a scenario on one plant, :func:`~flatstep.studies.robustness.perturbed`) and its figures, in one batch.

    ``bands`` are the runs' settling bands [rad]; ``batch_options`` go to
    :func:`~flatstep.studies.batch.run_batch`, its progress bar off.
    """
    rows = run_batch(runs, keep=KEEP, progress=False, **batch_options) if runs else []
    out: list[PlantRun] = []
    for row, run, band in zip(rows, runs, bands, strict=True):
        bad = row["error"] is not None or row.get("status") != "ok"
        if row["error"] is not None:
            out.append((math.nan, math.nan, math.nan, None, True))
            continue
        t, e, ia, ib, va, vb = (row[f"series_{k}"] for k in KEEP)
        m = metrics(t, e, ia, ib, va, vb, run.plan, band=band, R=run.simulated_plant.motor.R)
        out.append((float(m["move_max"] or 0.0), float(m["peak_voltage"] or 0.0), float(m["copper_loss"] or 0.0),
                    m["settling_time"], bad))
    return out


def combine(gains: Mapping[str, float], runs: Sequence[PlantRun], plants: int) -> Evaluation:
    """The worst over the plant runs ``runs`` of a candidate with ``gains``, of ``plants`` plants in all."""
    worst = [math.nan, math.nan, math.nan]
    settling: Optional[float] = 0.0
    bad = 0
    for move, peak, copper, settled, failed in runs:
        bad += failed
        if math.isnan(move):
            continue
        worst = [float(np.fmax(w, v)) for w, v in zip(worst, (move, peak, copper), strict=True)]  # fmax: NaN loses
        settling = None if settling is None or settled is None else max(settling, settled)
    if bad == len(runs):
        settling = None
    return Evaluation(dict(gains), worst[0], worst[1], worst[2], settling, bad, plants,
                      None if len(runs) == plants else len(runs))


def evaluate(scenarios: Sequence[Scenario], errors: list[dict[str, float]], gains: Sequence[dict[str, float]],
             *, band: Optional[float] = None, **batch_options: Any) -> list[Evaluation]:
    """Each scenario (one per candidate, its ``gains``) on every plant of ``errors``, in one batch.

    ``band`` is the settling band [rad] (default: one encoder count, :func:`~flatstep.studies.compare.default_band`);
    ``batch_options`` go to :func:`~flatstep.studies.batch.run_batch` (``workers``, ``executor``, ...).
    """
    runs = [p for i, sc in enumerate(scenarios) for p in perturbed(sc, errors, f"/c{i}")]
    n = len(errors)
    bands = [default_band(sc) if band is None else band for sc in scenarios for _ in range(n)]
    done = run_plants(runs, bands, **batch_options)
    return [combine(gains[i], done[i * n:(i + 1) * n], n) for i in range(len(scenarios))]


def objective(ev: Evaluation, caps: Caps) -> float:
    """The search's objective of an evaluation (module docstring); infinite-free: a cap never met counts 10."""
    move = ev.move_max if math.isfinite(ev.move_max) and ev.move_max > 0 else 1e3
    excess = caps.excess(ev)
    return math.log(move) + CAP_WEIGHT * min(excess, 10.0) + (FAIL_PENALTY if not ev.ok else 0.0)


class _Search:
    """The candidates' evaluations, a generation at a time, for SciPy's ``workers`` map (deferred updating).

    It keeps a copy of the population's objectives as differential evolution updates them (deferred: a trial
    replaces the member of its index if its objective is no larger; then the best member is swapped to the front),
    so that it knows which objective each trial challenges (the early stop, module docstring).
    """

    def __init__(self, scenario: Scenario, table: LawGains, errors: list[dict[str, float]], caps: Caps,
                 batch_options: Mapping[str, Any], log: Optional[Callable[[str], None]], kind: str,
                 budget: int, early_stop: bool) -> None:
        self.scenario, self.table, self.errors, self.caps = scenario, table, errors, caps
        self.batch_options, self.log, self.kind, self.budget = dict(batch_options), log, kind, budget
        self.early_stop = early_stop
        self.centre = table.read(scenario)
        self.evaluations: list[Evaluation] = []
        self.plant_moves: dict[int, list[float]] = {}  # id of a complete evaluation -> its error on each plant
        self.costs: dict[bytes, float] = {}
        self.population: Optional[NDArray[np.float64]] = None  # the population's objectives, as SciPy holds them
        self.start = time.perf_counter()

    def gains(self, x: NDArray[np.float64]) -> dict[str, float]:
        """The gains of a search vector (decades around the scenario's values)."""
        return {g.key: self.centre[g.key] * 10.0 ** float(v) for g, v in zip(self.table.gains, x, strict=True)}

    def _runs(self, todo: Sequence[tuple[int, dict[str, float]]], plants: Sequence[int]) -> list[list[PlantRun]]:
        """The runs of candidates ``(index, gains)`` on the plants ``plants`` (indices into the errors), one batch."""
        errors = [self.errors[p] for p in plants]
        scenarios = [self.table.apply(self.scenario, g) for _, g in todo]
        runs = [r for i, sc in enumerate(scenarios) for r in perturbed(sc, errors, f"/c{i}")]
        bands = [default_band(sc) for sc in scenarios for _ in plants]
        done = run_plants(runs, bands, **self.batch_options)
        n = len(plants)
        return [done[i * n:(i + 1) * n] for i in range(len(todo))]

    def plant_order(self) -> list[int]:
        """The order a trial runs the plants in: worst first for the best complete evaluation so far."""
        moves = self.plant_moves[id(self.best())]
        return sorted(range(len(moves)), key=lambda p: (-moves[p] if math.isfinite(moves[p]) else -math.inf, p))

    def stops(self, partial: Evaluation, challenged: float, best: Optional[Evaluation]) -> bool:
        """Whether a trial whose first round gave ``partial`` can neither replace its member nor be the answer."""
        if not (partial.ok and math.isfinite(partial.move_max)) or not objective(partial, self.caps) > challenged:
            return False
        return self.caps.excess(partial) > 0.0 or (best is not None and partial.move_max > best.move_max)

    def run(self, xs: list[NDArray[np.float64]], challenged: Optional[NDArray[np.float64]] = None) -> None:
        """Evaluate the candidates ``xs`` not yet evaluated; ``challenged``: the objectives they challenge, if any."""
        todo: list[tuple[int, dict[str, float]]] = []
        seen = set()
        for j, x in enumerate(xs):
            key = x.tobytes()
            if key not in self.costs and key not in seen:
                seen.add(key)
                todo.append((j, self.gains(x)))
        if not todo:
            return
        n = len(self.errors)
        results: dict[int, list[PlantRun]] = {}
        order: list[int] = list(range(n))
        if self.early_stop and challenged is not None and n > 1 and any(e.complete for e in self.evaluations):
            order = self.plant_order()
            top = self.best()
            best = top if self.feasible(top) else None
            results = {j: [] for j, _ in todo}
            going, done = list(todo), 0
            for end in sorted({max(1, int(f * n)) for f in ROUNDS} | {n}):
                for (j, _), runs in zip(going, self._runs(going, order[done:end]), strict=True):
                    results[j] += runs
                done = end
                going = [(j, g) for j, g in going
                         if end == n or not self.stops(combine(g, results[j], n), float(challenged[j]), best)]
                if not going:
                    break
        else:
            results = {j: runs for (j, _), runs in zip(todo, self._runs(todo, order), strict=True)}
        for j, g in todo:
            ev = combine(g, results[j], n)
            self.costs[xs[j].tobytes()] = objective(ev, self.caps)
            self.evaluations.append(ev)
            if ev.complete:
                moves = [math.nan] * n
                for p, r in zip(order, results[j], strict=False):
                    moves[p] = r[0]
                self.plant_moves[id(ev)] = moves
        if self.log is not None:
            best = self.best()
            stopped = sum(not e.complete for e in self.evaluations)
            self.log(f"{self.kind}: {len(self.evaluations)}/{self.budget} evaluations"
                     + (f" ({stopped} stopped early)" if stopped else "")
                     + f", best worst-of-plants error {best.move_max:.4g} rad at {best.peak_voltage:.3g} V"
                     + ("" if self.feasible(best) else " (no candidate meets the caps yet)")
                     + f", {time.perf_counter() - self.start:.1f} s")

    def map(self, func: Callable[[Any], float], xs: Any) -> list[float]:
        """SciPy's map-like ``workers``: one generation's candidates evaluated, their costs, the population updated.

        The first call is the initial population; every later one holds one trial per population member, in the
        members' order (deferred updating).
        """
        xs = [np.asarray(x, dtype=float) for x in xs]
        challenged = self.population if self.population is not None and len(self.population) == len(xs) else None
        self.run(xs, challenged)
        costs = np.array([func(x) for x in xs], dtype=float)
        if challenged is None:
            self.population = costs.copy()
        else:
            self.population = np.where(costs <= challenged, costs, challenged)
        lowest = int(np.argmin(self.population))  # SciPy's _promote_lowest_energy: the best member to the front
        self.population[[0, lowest]] = self.population[[lowest, 0]]
        return [float(c) for c in costs]

    def cost(self, x: NDArray[np.float64]) -> float:
        """The objective of ``x`` (evaluated by :meth:`map` before)."""
        key = np.asarray(x, dtype=float).tobytes()
        if key not in self.costs:
            self.run([np.asarray(x, dtype=float)])
        return self.costs[key]

    def feasible(self, ev: Evaluation) -> bool:
        """Every plant run and ok, and every cap met."""
        return ev.complete and ev.ok and self.caps.excess(ev) == 0.0 and math.isfinite(ev.move_max)

    def best(self) -> Evaluation:
        """The feasible evaluation with the least error, else the complete one with the least objective."""
        feasible = [e for e in self.evaluations if self.feasible(e)]
        if feasible:
            return min(feasible, key=lambda e: e.move_max)
        return min((e for e in self.evaluations if e.complete), key=lambda e: objective(e, self.caps))


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
         log: Optional[Callable[[str], None]] = None, early_stop: bool = True,
         **batch_options: Any) -> TuneResult:
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
    early_stop : bool
        Stop a trial once its first plants show it can neither enter the population nor be the answer (module
        docstring: the same search and answer as without, in less time).
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
    early_stop = check_bool("early_stop", early_stop)
    search = _Search(base, table, study_of(base, study), caps, batch_options, log, kind, budget, early_stop)
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
