"""Checks of user-given values: type, finiteness, range.

Each returns the value as the type the caller keeps, or raises an :class:`InputError` (a ``ValueError``) that names
the value, says why it is wrong and what would be valid. A ``bool`` is not a number and a string is not a number:
``R = true`` or ``v_bus = "24"`` in a scenario file is refused, not read as 1.0 or 24.0.
"""
from __future__ import annotations

import math
import reprlib
from typing import Any, Iterable, Optional, Union

import numpy as np

from .ranges import INTEGER_RANGES, QUANTITIES


class InputError(ValueError):
    """A refused value: ``name`` and ``value`` say which, the message says why and what is valid.

    Boundaries that know where the value came from (a command-line flag, ``file:table.key``) prefix the message
    with that source (:meth:`at`).
    """

    def __init__(self, name: str, value: object, message: str) -> None:
        super().__init__(message)
        self.name = name
        self.value = value

    def at(self, source: str) -> "InputError":
        """The same error with ``source`` (where the value was given) in front of its message."""
        return InputError(self.name, self.value, f"{source}: {self}")


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number of a numeric type (not a bool, not a string)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


_REPR = reprlib.Repr()
_REPR.maxstring, _REPR.maxother, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 80, 80, 6, 6, 4


def short_repr(value: object) -> str:
    """``repr(value)``, shortened for a message when it is long (a list of a million waypoints)."""
    if isinstance(value, (list, tuple, dict, set, np.ndarray)) and len(value) > 8:
        return _REPR.repr(value)
    text = repr(value)
    return text if len(text) <= 200 else _REPR.repr(value)


def check_instance(name: str, value: Any, kind: Union[type, tuple[type, ...]], what: str, hint: str = "") -> Any:
    """Return ``value``, or raise if it is not an instance of ``kind``.

    ``what`` says what is valid (``"a MotorLimits"``), ``hint`` how to make one.
    """
    if not isinstance(value, kind):
        raise InputError(name, value, f"{name}={short_repr(value)} is a {type(value).__name__}, not {what}; give "
                                      f"{what}" + (f" ({hint})" if hint else ""))
    return value


def check_sequence(name: str, value: Any, *, low: int, high: int, what: str, limit: str = "") -> int:
    """Return ``len(value)``, or raise unless ``value`` is a list, tuple or 1-D array of ``low`` to ``high`` items.

    ``what`` names the items (``"waypoints"``); ``limit`` names the constant that sets ``high``. A string, a
    mapping, a set or an iterator is refused: its items have no order or no length to check before any work.
    """
    ok = isinstance(value, (list, tuple)) or (isinstance(value, np.ndarray) and value.ndim == 1)
    if not ok:
        raise InputError(name, value, f"{name}={short_repr(value)} is not a sequence ({type(value).__name__}); "
                                      f"give a list of {low} to {high} {what}")
    n = len(value)
    if not low <= n <= high:
        where = f" (flatstep.validate.limits.{limit})" if limit else ""
        raise InputError(name, value, f"{name} has {n} {what}; give at least {low} and at most {high}{where}: "
                                      f"{name}={short_repr(value)}")
    return n


def check_finite(name: str, value: Any) -> float:
    """Return ``value`` as float, or raise if it is not a finite real number (a bool or a string is not)."""
    if not is_real(value):
        raise InputError(name, value, f"{name}={value!r} is not a number ({type(value).__name__}); "
                                      "give a finite real value")
    try:
        out = float(value)
    except OverflowError:
        raise InputError(name, value, f"{name}={value!r} is too large for a float; give a finite real value") from None
    if not math.isfinite(out):
        raise InputError(name, value, f"{name}={value!r} is not finite; give a finite real value")
    return out


def check_positive(name: str, value: Any, *, unit: str = "") -> float:
    """Return ``value`` as float, or raise if it is not finite and > 0."""
    out = check_finite(name, value)
    if out <= 0.0:
        raise InputError(name, value, f"{name}={out!r}{unit} must be > 0")
    return out


def check_nonnegative(name: str, value: Any, *, unit: str = "", why: str = "") -> float:
    """Return ``value`` as float, or raise if it is not finite and >= 0 (``why`` is added in parentheses)."""
    out = check_finite(name, value)
    if out < 0.0:
        raise InputError(name, value, f"{name}={out!r}{unit} must be >= 0" + (f" ({why})" if why else ""))
    return out


def check_integer(name: str, value: Any, *, low: int = 1, high: Optional[int] = None, why: str = "") -> int:
    """Return ``value`` as int, or raise if it is not an integer in ``[low, high]`` (a bool is not an integer).

    A float with an integral value (``50.0``, as TOML and JSON may give it) is taken as that integer; ``why`` is
    added to the message in parentheses.
    """
    given = value
    if isinstance(value, (float, np.floating)) and math.isfinite(value) and float(value).is_integer():
        value = int(value)
    ok = not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, np.integer))
    if not ok or value < low or (high is not None and value > high):
        valid = f"an integer in [{low}, {high}]" if high is not None else (
            "a positive integer" if low == 1 else f"an integer >= {low}")
        raise InputError(name, given, f"{name}={given!r} must be {valid}" + (f" ({why})" if why else ""))
    return int(value)


def check_bool(name: str, value: Any) -> bool:
    """Return ``value``, or raise if it is not ``True`` or ``False`` (1 and "yes" are not)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(name, value, f"{name}={value!r} must be true or false")
    return bool(value)


def check_choice(name: str, value: Any, valid: Iterable[str]) -> str:
    """Return ``value``, or raise if it is not one of the strings ``valid``."""
    options = tuple(valid)
    if not isinstance(value, str) or value not in options:
        raise InputError(name, value, f"{name}={value!r} is not one of {list(options)}")
    return value


def check_quantity(name: str, value: Any, *, as_name: Optional[str] = None) -> float:
    """Return ``value`` as float, or raise if it is not a finite number in the range of :data:`QUANTITIES` ``[name]``.

    ``as_name`` names the value in the message when it is known by another name (``rho1`` for a ``current``).
    """
    q = QUANTITIES[name]
    label = as_name or name
    out = check_finite(label, value)
    if not q.contains(out):
        raise InputError(label, value, f"{label}={out!r}{q.unit_suffix} is out of range: {q.why}; "
                                       f"valid: {q.describe()}")
    return out


def check_count(name: str, value: Any, *, kind: Optional[str] = None, why: str = "") -> int:
    """Return ``value`` as int, or raise if it is not an integer in the range :data:`INTEGER_RANGES` ``[kind]``."""
    low, high = INTEGER_RANGES[kind or name]
    return check_integer(name, value, low=low, high=high, why=why)
