"""Parameter-error studies: one scenario, many plants, the controller's model unchanged."""
from __future__ import annotations

from dataclasses import replace
from itertools import product
from typing import Any, Optional

import numpy as np

from ..control.smc import SMCGains
from ..engine.result import STATUSES
from .batch import run_batch
from .scenario import Scenario
from .scenario_file import Robustness

#: Settling allowance after tf before the rotor counts as "at rest" [s].
REST_AFTER = 5e-3


def encoder_count(scenario: Scenario) -> Optional[float]:
    """One encoder count [rad] of the scenario's sensors, or ``None`` without an encoder."""
    sensors = scenario.loop.sensors if scenario.loop is not None else None
    return sensors.angle_step if sensors is not None and sensors.angle_step else None


def plant_errors(study: Robustness) -> list[dict[str, float]]:
    """Relative plant errors: every sign combination (``samples == 0``) or a seeded uniform sample."""
    names = study.parameters
    if study.samples == 0:
        return [dict(zip(names, (s * study.relative_error for s in signs), strict=True))
                for signs in product((1.0, -1.0), repeat=len(names))]
    rng = np.random.default_rng(study.seed)
    draws = rng.uniform(-study.relative_error, study.relative_error, (study.samples, len(names)))
    return [dict(zip(names, row, strict=True)) for row in draws]


def perturbed(scenario: Scenario, errors: list[dict[str, float]], label: str = "") -> list[Scenario]:
    """The scenario once per plant error set, the plant built from the controller's model ``motor``."""
    m, base = scenario.motor, scenario.simulated_plant
    out = []
    for err in errors:
        motor = m.replace(**{k: getattr(m, k) * (1.0 + e) for k, e in err.items()})
        tag = ",".join(f"{k}{e:+.3g}" for k, e in err.items())
        out.append(replace(scenario, name=f"{scenario.name}{label}[{tag}]", plant=replace(base, motor=motor)))
    return out


def run_study(scenario: Scenario, study: Robustness, *, with_paper_gains: bool = True,
              **batch_options: Any) -> dict[str, Any]:
    """Run the study for the scenario's gains (and the paper's gains on the same drive).

    Returns per-set summaries, the worst values in encoder counts, and the traces for
    :func:`flatstep.cli.plots.plot_robustness`.
    """
    errors = plant_errors(study)
    sets = {"scenario": scenario}
    if with_paper_gains:
        sets["paper gains"] = replace(scenario, gains=SMCGains())
    out: dict[str, Any] = {"errors": errors, "sets": {}}
    count = encoder_count(scenario)
    for label, sc in sets.items():
        rows = run_batch(perturbed(sc, errors, f"/{label}"), keep=("t", "theta_error", "va", "vb"), **batch_options)
        out["sets"][label] = _summarise(rows, sc, count)
    return out


def _summarise(rows: list[dict[str, Any]], scenario: Scenario, count: Optional[float]) -> dict[str, Any]:
    """One set's summary: runs, failures, statuses, worst errors [rad] and peak voltage, in counts too.

    The statuses count the rows that ran by their status (ok, fault, lost); the worst errors are those during
    the move, at rest and at the end.
    """
    plan = scenario.plan
    failed = [r for r in rows if r["error"] is not None]
    ok = [r for r in rows if r["error"] is None]
    worst: dict[str, float] = {}
    for r in ok:
        t, e = np.array(r["series_t"]), np.abs(np.array(r["series_theta_error"]))
        v = max(np.max(np.abs(r["series_va"])), np.max(np.abs(r["series_vb"])))
        during = float(np.max(e[(t >= plan.t0) & (t <= plan.tf)]))
        rest = e[t >= plan.tf + REST_AFTER]
        for key, val in (("move", during), ("rest", float(np.max(rest)) if rest.size else float("nan")),
                         ("final", float(e[-1])), ("peak_voltage", float(v))):
            worst[key] = max(worst.get(key, -np.inf), val)
    statuses = {s: sum(r.get("status") == s for r in ok) for s in STATUSES}
    summary: dict[str, Any] = {"runs": len(rows), "failed": len(failed), "failures": [r["error"] for r in failed],
                               "statuses": statuses, "worst_rad": worst, "rows": rows}
    if count:
        summary["worst_counts"] = {k: worst[k] / count for k in ("move", "rest", "final") if k in worst}
    return summary
