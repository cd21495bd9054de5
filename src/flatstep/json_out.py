"""JSON text that is JSON: NaN and infinities written as ``null``, so no reader chokes on them and NaN never travels.

Python's ``json.dumps`` writes ``NaN`` and ``Infinity``, which are not JSON; every file and report flatstep writes
goes through :func:`strict_json`.
"""
from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def finite_or_none(obj: Any) -> Any:
    """``obj`` with every non-finite float (at any depth of dicts, lists and tuples) replaced by ``None``."""
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite_or_none(v) for v in obj]
    return obj


def strict_json(obj: Any, **kwargs: Any) -> str:
    """``json.dumps(obj, **kwargs)`` with non-finite numbers as ``null`` (and refused if any remain)."""
    return json.dumps(finite_or_none(obj), allow_nan=False, **kwargs)
