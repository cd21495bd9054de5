r"""A frontier, not a point: each law's best worst-of-plants error against its peak-voltage cap, and its copper.

:func:`frontier` tunes a controller type (:func:`flatstep.studies.tune.tune`, the same budget and seed) under a
sweep of peak-voltage caps, fractions of the drive's bus, and takes at each cap the best candidate any of those
searches evaluated on every plant that meets it (a search under a higher cap may have found a better one below the
lower cap; a candidate a search stopped early, :mod:`flatstep.studies.tune`, counts for no cap).
:func:`outside_layer` says how often a sliding law's :math:`|s|` is outside its boundary layer
(:math:`|s_1| > \epsilon_1` or :math:`|s_2| > \epsilon_2`): how much the law switches rather than running as a
linear high-gain law.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ..control.spec import ControllerSpec
from ..validate import InputError, check_positive
from .batch import run_batch
from .robustness import perturbed
from .scenario import Scenario
from .scenario_file import Robustness
from .tune import BUDGET, DEFAULT_CAPS, POPULATION, Caps, Evaluation, TuneResult, study_of, tune

#: The peak-voltage caps of a frontier, as fractions of the drive's bus.
FRACTIONS = (0.5, 0.75, 1.0)


@dataclass(frozen=True)
class FrontierPoint:
    """The best candidate under one peak-voltage cap [V] (``None``: none met it on every plant)."""

    cap: float
    best: Optional[Evaluation]

    def as_dict(self) -> dict[str, Any]:
        """The point for JSON."""
        return {"peak_voltage_cap": self.cap, "best": self.best.as_dict() if self.best is not None else None}


@dataclass
class Frontier:
    """One controller type's frontier: its points by increasing cap and the searches behind them."""

    kind: str
    points: list[FrontierPoint]
    results: list[TuneResult]

    @property
    def wall_time(self) -> float:
        """The searches' wall time [s]."""
        return sum(r.wall_time for r in self.results)

    def as_dict(self) -> dict[str, Any]:
        """The frontier for JSON (each search's summary, without its evaluations)."""
        return {"kind": self.kind, "points": [p.as_dict() for p in self.points],
                "searches": [r.as_dict() for r in self.results], "wall_time_s": self.wall_time}


def check_fractions(fractions: Sequence[float], source: str = "fractions") -> tuple[float, ...]:
    """The cap fractions, each in (0, 1], distinct, sorted."""
    try:
        values = sorted({check_positive(source, f) for f in fractions})
    except (TypeError, ValueError):
        raise InputError(source, fractions, f"{source} {fractions!r}: give fractions of the bus in (0, 1]") from None
    if not values or values[-1] > 1.0:
        raise InputError(source, fractions, f"{source} {list(fractions)!r}: give fractions of the bus in (0, 1] "
                         "(the drive cannot apply more than its bus)")
    return tuple(values)


def best_under(evaluations: Sequence[Evaluation], caps: Caps) -> Optional[Evaluation]:
    """The evaluation with the least worst-of-plants error among those run and ok on every plant and within ``caps``.

    An evaluation the search stopped early (:attr:`~flatstep.studies.tune.Evaluation.complete` false) is not one.
    """
    ok = [e for e in evaluations if e.complete and e.ok and caps.excess(e) == 0.0 and np.isfinite(e.move_max)]
    return min(ok, key=lambda e: e.move_max) if ok else None


def frontier(scenario: Scenario, kind: str, *, fractions: Sequence[float] = FRACTIONS, caps: Caps = DEFAULT_CAPS,
             budget: int = BUDGET, seed: int = 0, study: Optional[Robustness] = None, population: int = POPULATION,
             log: Optional[Callable[[str], None]] = None, **batch_options: Any) -> Frontier:
    """Tune ``kind`` under each peak-voltage cap ``fraction x caps.peak_voltage`` (default cap: the bus).

    Each cap gets its own search of ``budget`` evaluations (the same seed); each point is the best evaluation of
    any search that meets that cap and the other ``caps``.
    """
    fractions = check_fractions(fractions)
    full = caps.for_scenario(replace(scenario, controller_type=kind))
    if full.peak_voltage is None:
        raise InputError("scenario", scenario.name, f"scenario {scenario.name!r} has no drive bus: give a "
                         "peak-voltage cap")
    results = []
    for f in fractions:
        results.append(tune(scenario, kind, budget=budget, seed=seed, study=study, population=population, log=log,
                            caps=replace(full, peak_voltage=f * full.peak_voltage), **batch_options))
    archive = [e for r in results for e in r.evaluations]
    points = [FrontierPoint(r.caps.peak_voltage or 0.0, best_under(archive, r.caps)) for r in results]
    return Frontier(kind, points, results)


def outside_layer(scenario: Scenario, study: Optional[Robustness] = None,
                  **batch_options: Any) -> Optional[dict[str, float]]:
    r"""How often the sliding law's :math:`|s|` is outside its boundary layer, over every plant, from :math:`t_0` on.

    Returns the shares of control instants with :math:`|s_1| > \epsilon_1`, with :math:`|s_2| > \epsilon_2`, with
    either, and the largest :math:`|s_1|/\epsilon_1` and :math:`|s_2|/\epsilon_2`; ``None`` for a law that is not
    sliding (no ``s``).
    """
    if not ControllerSpec.parse(scenario.controller_type).sliding:
        return None
    g = scenario.gains
    rows = run_batch(perturbed(scenario, study_of(scenario, study), "/layer"), keep=("t", "s1", "s2"),
                     progress=False, **batch_options)
    r1, r2 = [], []
    for row in rows:
        if row["error"] is not None:
            continue
        t = np.asarray(row["series_t"])
        w = t >= scenario.plan.t0
        r1.append(np.abs(np.asarray(row["series_s1"]))[w] / g.eps1)
        r2.append(np.abs(np.asarray(row["series_s2"]))[w] / g.eps2)
    if not r1:
        return None
    a1, a2 = np.concatenate(r1), np.concatenate(r2)
    return {"s1": float(np.mean(a1 > 1.0)), "s2": float(np.mean(a2 > 1.0)),
            "either": float(np.mean((a1 > 1.0) | (a2 > 1.0))), "max_s1_over_eps1": float(np.max(a1)),
            "max_s2_over_eps2": float(np.max(a2))}
