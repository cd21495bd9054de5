"""Checks of the interop functions' arguments at entry that :mod:`flatstep.validate` does not already hold."""
from __future__ import annotations

from typing import Any, Optional

from ..validate import InputError, short_repr


def check_name(name: Any) -> Optional[str]:
    """``name``, or an InputError unless it is a non-empty string or None (a system's name in python-control)."""
    if name is not None and not (isinstance(name, str) and name):
        raise InputError("name", name, f"name={short_repr(name)} is not a system name ({type(name).__name__}); give "
                         "a non-empty string or None")
    return name
