"""How well :func:`~flatstep.studies.identify.identify` recovers a simulated plant: errors over seeds, targets."""
from __future__ import annotations

import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Iterable, Optional

import numpy as np

from .excitation import excite
from .identify import identify
from .identify_result import MOTOR_KEYS
from .record import write_recording
from .scenario import Scenario

#: The accuracy targets: the largest relative error accepted per parameter, and the time per identification [s].
TARGETS = {"R": 0.03, "L": 0.03, "Km": 0.03, "J": 0.10, "B": 0.20}
TIME_TARGET = 5.0


def preset_plant(scenario: Scenario) -> Scenario:
    """``scenario`` with its controller's model as the simulated motor (its load and plant effects kept)."""
    return replace(scenario, plant=replace(scenario.simulated_plant, motor=scenario.motor))


def accuracy(scenarios: Iterable[Scenario], seeds: Iterable[int], *, current_noise: Optional[float] = 0.005,
             duration: float = 1.0, **options: Any) -> list[dict[str, Any]]:
    """Excite, record and identify each scenario's plant once per seed.

    Parameters
    ----------
    scenarios : iterable of Scenario
        Sampled-drive scenarios; the truth is each one's simulated plant.
    seeds : iterable of int
        The excitation's seeds (moves and sensor noise).
    current_noise : float, optional
        The ADC noise [A rms] (``None``: the scenarios' own sensors).
    duration : float
        Length of each recording [s].
    **options
        Keywords of :func:`~flatstep.studies.identify.identify`.

    Returns
    -------
    list of dict
        One row per run: ``scenario``, ``seed``, ``errors`` (relative, by parameter), ``covered`` (whether each
        interval holds the truth), ``seconds`` (the identification from the CSV file, reading included).
    """
    rows = []
    seeds = list(seeds)
    for scenario in scenarios:
        truth = scenario.simulated_plant.motor
        for seed in seeds:
            rec = excite(scenario, seed=seed, duration=duration, current_noise=current_noise)
            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / "recording.csv"
                write_recording(path, rec)
                start = time.perf_counter()
                result = identify(path, **{"Nr": truth.Nr, **options})
                seconds = time.perf_counter() - start
            covered = {k: bool(result.interval(k)[0] <= getattr(truth, k) <= result.interval(k)[1])
                       for k in MOTOR_KEYS}
            rows.append({"scenario": scenario.name, "seed": seed, "errors": result.errors(truth),
                         "covered": covered, "seconds": seconds})
    return rows


def accuracy_table(rows: list[dict[str, Any]]) -> str:
    """Per scenario: the worst |error| of each parameter against its target, interval coverage, time."""
    head = (f"{'scenario':<24}{'runs':>5}" + "".join(f"{'max|' + k + '|':>11}" for k in MOTOR_KEYS)
            + f"{'covered':>9}{'max s':>8}")
    lines = [head]
    for name in dict.fromkeys(r["scenario"] for r in rows):
        own = [r for r in rows if r["scenario"] == name]
        worst = {k: max(abs(r["errors"][k]) for r in own) for k in MOTOR_KEYS}
        covered = sum(sum(r["covered"].values()) for r in own)
        lines.append(f"{name:<24}{len(own):>5}" + "".join(f"{worst[k]:>11.2%}" for k in MOTOR_KEYS)
                     + f"{covered:>5}/{len(own) * len(MOTOR_KEYS):<3}{max(r['seconds'] for r in own):>8.3f}")
    lines.append(f"{'target':<24}{'':>5}" + "".join(f"{TARGETS[k]:>11.0%}" for k in MOTOR_KEYS)
                 + f"{'':>9}{TIME_TARGET:>8.1f}")
    return "\n".join(lines)


def meets_targets(rows: list[dict[str, Any]]) -> bool:
    """Whether every run is within :data:`TARGETS` and :data:`TIME_TARGET`."""
    return all(abs(r["errors"][k]) <= TARGETS[k] for r in rows for k in MOTOR_KEYS) and \
        bool(np.all([r["seconds"] <= TIME_TARGET for r in rows]))
