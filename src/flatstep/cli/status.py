"""The command line's exit codes and its warnings about runs that are not ``ok`` (docs/errors.md)."""
from __future__ import annotations

import sys
from typing import Any, Iterable, Mapping

#: Exit codes of every ``flatstep`` command (docs/errors.md).
EXIT_OK = 0            # every run ok
EXIT_INTERNAL = 1      # an unexpected error (one line; --debug prints the traceback)
EXIT_REFUSED = 2       # a bad value, file or flag, or an infeasible plan: nothing was run
EXIT_LOST = 3          # a run lost its move (status "lost")
EXIT_FAULT = 4         # no move lost, but a controller faulted (status "fault")
EXIT_STOPPED = 5       # a run stopped before its end (flatstep.errors.RunError: non-finite state, ...)
EXIT_INTERRUPTED = 130  # Ctrl-C


def exit_code(statuses: Iterable[str]) -> int:
    """The exit code of a command whose runs ended with these statuses: the worst of them."""
    seen = set(statuses)
    if "lost" in seen:
        return EXIT_LOST
    return EXIT_FAULT if "fault" in seen else EXIT_OK


def describe(summary: Mapping[str, Any]) -> str:
    """One line on a run that is not ok: when it lost its move, how many periods faulted."""
    parts = []
    if summary.get("status") == "lost":
        parts.append(f"lost its move at t = {summary['lost_at']:.6g} s (|theta - theta*| beyond one full step, or "
                     "half the last move if smaller)")
    if summary.get("controller_faults"):
        parts.append(f"the controller faulted in {summary['controller_faults']} periods (0 V applied)")
    return "; ".join(parts)


def warn(label: str, summary: Mapping[str, Any]) -> None:
    """Print a warning on stderr for a run whose status is not ``ok``."""
    if summary.get("status", "ok") != "ok":
        print(f"flatstep: warning: {label}: {describe(summary)}", file=sys.stderr)
