"""Checks of user-given values.

Each returns the value as the type the caller keeps, or raises a ValueError that names the value, says why it
is wrong and what would be valid.
"""
from __future__ import annotations

import math

import numpy as np


def check_finite(name: str, value: float) -> float:
    """Return ``value`` as float, or raise a ValueError if it is not a finite real number."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}={value!r} is not a number; give a finite real value") from None
    if not math.isfinite(value):
        raise ValueError(f"{name}={value!r} is not finite; give a finite real value")
    return value


def check_positive(name: str, value: float, *, unit: str = "") -> float:
    """Return ``value`` as float, or raise a ValueError if it is not finite and > 0."""
    value = check_finite(name, value)
    if value <= 0.0:
        raise ValueError(f"{name}={value!r}{unit} must be > 0")
    return value


def check_nonnegative(name: str, value: float, *, unit: str = "", why: str = "") -> float:
    """Return ``value`` as float, or raise a ValueError if it is not finite and >= 0.

    ``why`` is added to the message in parentheses.
    """
    value = check_finite(name, value)
    if value < 0.0:
        raise ValueError(f"{name}={value!r}{unit} must be >= 0" + (f" ({why})" if why else ""))
    return value


def check_integer(name: str, value: object, *, low: int = 1, why: str = "") -> int:
    """Return ``value`` as int, or raise a ValueError if it is not an integer (``bool`` is not) >= ``low``.

    ``why`` is added to the message in parentheses.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        valid = "a positive integer" if low == 1 else f"an integer >= {low}"
        raise ValueError(f"{name}={value!r} must be {valid}" + (f" ({why})" if why else ""))
    return int(value)
