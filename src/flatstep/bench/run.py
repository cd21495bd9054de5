"""``flatstep bench``: run the chosen benchmarks and print each report, with the revision and machine load."""
from __future__ import annotations

import os
import subprocess
from typing import Callable, Optional

from .batch import bench_batch
from .closed_loop import bench_closed_loop
from .common import ROOT, Report
from .engine import bench_engine
from .plan import bench_plan
from .step import bench_step

WHICH = ("a", "b", "c", "d", "e")


BENCHMARKS: dict[str, Callable[..., Report]] = {"a": bench_plan, "b": bench_closed_loop, "c": bench_step,
                                                 "d": bench_batch, "e": bench_engine}


def main(which: str = "a,b,c,d,e", repeat: Optional[int] = None) -> int:
    """Run the chosen benchmarks, print each report; return 0 (targets missed are reported, not errors)."""
    keys = [k.strip() for k in which.split(",") if k.strip()]
    unknown = [k for k in keys if k not in BENCHMARKS]
    if unknown or not keys:
        raise ValueError(f"--which {which!r}: unknown benchmark(s) {unknown}; choose from {','.join(WHICH)}")
    try:
        import control  # noqa: F401
    except ImportError:
        if {"a", "b"} & set(keys):
            raise ValueError("benchmarks a and b compare with python-control: pip install 'flatstep[bench]'") from None
    print(f"flatstep bench: source {_revision()}, {os.cpu_count()} cores, load average {_load()} at start; "
          f"medians of {repeat or 'the default number of'} rounds; the ratios are the figures to quote\n")
    for key in keys:
        report = BENCHMARKS[key](**({} if repeat is None else {"repeat": repeat}))
        print(report.format(), flush=True)
        print()
    print(f"load average {_load()} at the end (a busy machine inflates times and deflates parallel speed-ups)")
    return 0


def _load() -> str:
    """The 1-minute load average, or 'unknown' where the platform has none."""
    return f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "unknown"


def _revision() -> str:
    """The git revision of the checkout (``-dirty`` with uncommitted changes), or 'installed package'."""
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True,
                             text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "installed package"
    return out.stdout.strip() if out.returncode == 0 else "installed package"
