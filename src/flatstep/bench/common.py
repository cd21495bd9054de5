"""What every benchmark shares: targets, reports with medians and ratios, and the side-by-side race.

The machine may be shared: the cases of a benchmark take turns in every round, medians are quoted, and the
ratios measured in the same run are the figures that mean something. Clocks are read here, never in the library.
"""
from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Optional

#: The source checkout (benchmarks/, csrc/) when flatstep runs from one.
ROOT = Path(__file__).resolve().parents[3]


@dataclass
class Target:
    """A goal of issue 3: ``value`` compared with ``limit`` (at least or at most)."""

    what: str
    value: float
    limit: float
    at_least: bool
    unit: str = ""

    @property
    def met(self) -> bool:
        """Whether the value is on the right side of the limit."""
        return self.value >= self.limit if self.at_least else self.value <= self.limit

    def describe(self) -> str:
        """The target on one line: the value, the limit, and met or by how much it is missed."""
        sign = ">=" if self.at_least else "<="
        head = f"{self.what} = {self.value:.4g}{self.unit} (target {sign} {self.limit:g}{self.unit})"
        if self.met:
            return f"{head}: met"
        factor = self.limit / self.value if self.at_least else self.value / self.limit
        return f"{head}: MISSED by a factor {factor:.2f}"


@dataclass
class Report:
    """One benchmark's medians (seconds per ``unit``), ratios against ``baseline``, checks and targets."""

    key: str
    title: str
    unit: str
    times: dict[str, float]
    baseline: str
    checks: list[tuple[str, float, str]] = field(default_factory=list)
    targets: list[Target] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def ratio(self, case: str) -> float:
        """How many times faster ``case`` is than the baseline."""
        return self.times[self.baseline] / self.times[case]

    def format(self) -> str:
        """The report as printed: one line per case (median, speed-up), then checks, targets and notes."""
        width = max(len(name) for name in self.times) + 2
        lines = [f"({self.key}) {self.title}",
                 f"  {'case':<{width}}{'median per ' + self.unit:>18}{'speed-up vs baseline':>24}"]
        for name, seconds in self.times.items():
            mark = "  (baseline)" if name == self.baseline else ""
            lines.append(f"  {name:<{width}}{_duration(seconds):>18}{self.ratio(name):>23.1f}x{mark}")
        lines += [f"  check: {what} = {value:.3g}{unit}" for what, value, unit in self.checks]
        lines += [f"  target: {t.describe()}" for t in self.targets]
        lines += [f"  note: {note}" for note in self.notes]
        return "\n".join(lines)


def _duration(seconds: float) -> str:
    """A duration with 4 significant digits in the largest unit (s, ms, us, ns) it is at least one of."""
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if seconds >= scale:
            return f"{seconds / scale:.4g} {unit}"
    return f"{seconds / 1e-9:.4g} ns"


def _clock(fn: Callable[[], Any], loops: int) -> float:
    """The wall time [s] of ``loops`` calls of ``fn``."""
    start = time.perf_counter()
    for _ in range(loops):
        fn()
    return time.perf_counter() - start


def median_ms(fn: Callable[[], Any], repeat: int = 7) -> float:
    """The median wall time [ms] of ``repeat`` calls of ``fn`` (one call a sample)."""
    return 1e3 * statistics.median(_clock(fn, 1) for _ in range(repeat))


def race(cases: dict[str, Callable[[], Any]], repeat: int, min_time: float = 0.02,
         per: Optional[dict[str, int]] = None) -> tuple[dict[str, float], dict[str, Any]]:
    """Median seconds per unit of work of each case, and each case's result (from its first, untimed call).

    The cases take turns in every one of ``repeat`` rounds, so a change of load on a shared machine hits them
    all alike; each sample loops its case until it lasts about ``min_time``. ``per[name]`` is the number of
    units one call does (e.g. samples), default 1.
    """
    if repeat < 1:
        raise ValueError(f"repeat={repeat!r} must be >= 1")
    results = {name: fn() for name, fn in cases.items()}
    loops = {name: max(1, math.ceil(min_time / max(_clock(fn, 1), 1e-9))) for name, fn in cases.items()}
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeat):
        for name, fn in cases.items():
            samples[name].append(_clock(fn, loops[name]) / loops[name])
    per = per or {}
    return {name: statistics.median(s) / per.get(name, 1) for name, s in samples.items()}, results


def core_module() -> Optional[ModuleType]:
    """The C binding, or None when it is not built."""
    try:
        from .. import core
    except ImportError:
        return None
    return core
