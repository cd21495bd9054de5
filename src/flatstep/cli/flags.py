"""Typed command-line values, checked by the rules of :mod:`flatstep.validate`.

Each flag is checked as the Python constructors and scenario files check the same value; its error names the flag,
the value and what is valid.
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable

from ..validate import InputError, check_count, check_quantity


def _parse_float(flag: str, text: str) -> float:
    """``text`` as a float, or an ArgumentTypeError naming the flag."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{flag}={text!r} is not a number") from None


def quantity(kind: str, flag: str) -> Callable[[str], float]:
    """An argparse ``type``: a number in the range of ``kind`` (:data:`flatstep.validate.QUANTITIES`)."""
    name = flag.lstrip("-").replace("-", "_")

    def parse(text: str) -> float:
        try:
            return check_quantity(kind, _parse_float(flag, text), as_name=name)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = kind  # argparse names the type in its own messages
    return parse


def count(kind: str, flag: str) -> Callable[[str], int]:
    """An argparse ``type``: an integer in the range of ``kind`` (:data:`flatstep.validate.INTEGER_RANGES`)."""
    name = flag.lstrip("-").replace("-", "_")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{flag}={text!r} is not an integer") from None
        try:
            return check_count(name, value, kind=kind)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = kind
    return parse


def out_dir(path: str, flag: str = "--out") -> Path:
    """The output directory ``path``, created if needed; a ValueError naming the flag if it cannot be one."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{flag} {path}: exists and is not a directory; give a directory (it is created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"{flag} {path}: cannot create the directory: {exc.strerror or exc}") from None
    return out


def add_force(parser: argparse.ArgumentParser) -> None:
    """Add ``--force``: replace output files that flatstep did not write (an input is never replaced)."""
    parser.add_argument("--force", action="store_true", help="replace output files that flatstep did not write "
                        "(an input of the run is never replaced; docs/errors.md, 'Files flatstep writes')")
