r"""The held-out check of tuned gains: each law re-run on plants and moves its search did not see.

The tuner (:mod:`flatstep.studies.tune`) keeps the least of about a hundred evaluations of a rough objective: the
worst of the plants' max errors, in encoder counts, moves by several percent when a gain moves in its third digit,
so the least of many draws is partly the seed's luck and partly gains fit to those exact runs (docs/comparison.md:
other seeds, and the runs below). :func:`held_out` re-runs fixed gains,
unchanged, on runs none of them was chosen on, and takes each law's mean over those runs as its yardstick:

* ``32 random plants``: a seeded uniform sample of plants in the study's box (:data:`RANDOM_PLANTS`, the study's
  seed plus one) instead of its corners;
* ``move x s``: the same plants, the move's duration times ``s`` (:data:`STRETCHES`: 1 and 2 % shorter and longer),
  the start and the end states as they were.

The move's duration is the plan's ``tf - t0`` for a rest-to-rest plan (:class:`~flatstep.plan.rest_to_rest.RestToRest`,
the comparison scenarios' plans); other plans are refused by name.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Mapping, Optional, Sequence

from ..plan.rest_to_rest import RestToRest
from ..validate import InputError
from .scenario import Scenario
from .scenario_file import Robustness
from .tune import Evaluation, evaluate, study_of
from .tune_laws import law_gains

#: The random plants of the held-out check: as many as the study's corners of five parameters.
RANDOM_PLANTS = 32
#: The move's duration times these in the held-out check.
STRETCHES = (0.98, 0.99, 1.01, 1.02)


@dataclass(frozen=True)
class HeldOutRun:
    """One run of the held-out check: its label, the scenario and the plants' study."""

    label: str
    scenario: Scenario
    study: Robustness


def stretched(scenario: Scenario, factor: float) -> Scenario:
    """``scenario`` with its move ``factor`` times as long (the same start, end and horizon after the move).

    Raises
    ------
    InputError
        For a plan that is not rest-to-rest (its duration is not one number to scale).
    """
    plan = scenario.plan
    if not isinstance(plan, RestToRest):
        raise InputError("plan", type(plan).__name__, f"the held-out check stretches a rest-to-rest move; "
                         f"{scenario.name}'s plan is a {type(plan).__name__}: give a [plan] with t0 and tf")
    tf = plan.t0 + factor * (plan.tf - plan.t0)
    return replace(scenario, plan=replace(plan, tf=tf), t_end=scenario.t_end + (tf - plan.tf))


def held_out_runs(scenario: Scenario, study: Optional[Robustness]) -> list[HeldOutRun]:
    """The held-out check's runs of ``scenario`` (module docstring), the study's own plants first as ``as tuned``."""
    base = study if study is not None else Robustness()
    runs = [HeldOutRun("as tuned", scenario, base),
            HeldOutRun(f"{RANDOM_PLANTS} random plants", scenario,
                       replace(base, samples=RANDOM_PLANTS, seed=base.seed + 1))]
    runs += [HeldOutRun(f"move x {s:g}", stretched(scenario, s), base) for s in STRETCHES]
    return runs


def held_out(scenario: Scenario, study: Optional[Robustness],
             laws: Mapping[str, Optional[Mapping[str, float]]]) -> dict[str, list[Evaluation]]:
    """Each law of ``laws`` (controller type -> its gains, ``None``: the scenario's own) on every held-out run.

    Returns each law's evaluations in the order of :func:`held_out_runs` (the first: the study as tuned).
    """
    out: dict[str, list[Evaluation]] = {}
    runs = held_out_runs(scenario, study)
    for kind, gains in laws.items():
        table = law_gains(kind)
        evs = []
        for run in runs:
            sc = replace(run.scenario, controller_type=kind)
            given = dict(gains) if gains is not None else table.read(sc)
            sc = table.apply(sc, given)
            evs.append(evaluate([sc], study_of(sc, run.study), [given])[0])
        out[kind] = evs
    return out


def held_out_mean(evaluations: Sequence[Evaluation]) -> float:
    """The mean worst-of-plants max error [rad] over the held-out runs (all but the first); NaN if one failed."""
    rest = evaluations[1:]
    if not rest or any(not e.ok or e.settling is None or not math.isfinite(e.move_max) for e in rest):
        return math.nan
    return sum(e.move_max for e in rest) / len(rest)
