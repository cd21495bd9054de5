"""Fingerprints of batch rows: a stable hash of a scenario's content, its engine options and the package version.

Equal contents give equal fingerprints in any process and session (no memory address, no hash seed enters),
so a batch file's row can be matched to the run that made it (:mod:`flatstep.studies.batch_file`).
"""
from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
import json
import re
import types
from typing import Sequence

import numpy as np


def _canonical(value: object, depth: int = 0) -> object:
    """A JSON-ready form of ``value`` that equal contents share, across processes and sessions.

    Floats are spelled by ``repr`` (so equal values give the same text), dataclasses by their type and fields,
    functions by their name, bytecode, constants, defaults and closure; tags keep kinds apart (a float from a
    string, a tuple from a list). Anything else falls back to its ``repr`` without memory addresses.
    """
    if depth > 40:
        raise ValueError("a scenario nests values more than 40 deep; it cannot be fingerprinted")
    d = depth + 1
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return {"float": repr(float(value))}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        kind = type(value)
        return {"dataclass": [f"{kind.__module__}.{kind.__qualname__}",
                              [[f.name, _canonical(getattr(value, f.name), d)] for f in dataclasses.fields(value)]]}
    if isinstance(value, enum.Enum):
        return {"enum": [type(value).__qualname__, value.name]}
    if isinstance(value, (list, tuple)):
        return {type(value).__name__ if type(value) in (list, tuple) else "sequence": [_canonical(v, d) for v in value]}
    if isinstance(value, dict):
        items = [[_canonical(k, d), _canonical(v, d)] for k, v in value.items()]
        return {"dict": sorted(items, key=lambda kv: json.dumps(kv, sort_keys=True))}
    if isinstance(value, np.ndarray):
        return {"array": [str(value.dtype), list(value.shape), _canonical(value.tolist(), d)]}
    if isinstance(value, functools.partial):
        return {"partial": [_canonical(value.func, d), _canonical(value.args, d), _canonical(value.keywords, d)]}
    if isinstance(value, types.CodeType):  # not its file name nor its line numbers: moving a function keeps it
        return {"code": [value.co_code.hex(), _canonical(value.co_consts, d), list(value.co_names)]}
    if isinstance(value, types.FunctionType):
        cells = [c.cell_contents for c in value.__closure__ or ()]
        return {"function": [f"{value.__module__}.{value.__qualname__}", _canonical(value.__code__, d),
                             _canonical(value.__defaults__, d), _canonical(value.__kwdefaults__, d),
                             _canonical(cells, d)]}
    if isinstance(value, (types.BuiltinFunctionType, np.ufunc)):
        return {"callable": f"{getattr(value, '__module__', '')}.{getattr(value, '__qualname__', value.__name__)}"}
    if hasattr(value, "__dict__") and not isinstance(value, (type, types.ModuleType)):
        return {"object": [f"{type(value).__module__}.{type(value).__qualname__}", _canonical(vars(value), d)]}
    return {"repr": re.sub(r" at 0x[0-9a-fA-F]+", "", repr(value))}


def fingerprint(scenario: object, engine: str, keep: Sequence[str], version: str) -> str:
    """The fingerprint of one batch row: a hash of the scenario, the engine, ``keep`` and the package version.

    Parameters
    ----------
    scenario : Scenario
        The run (every field, the name included: a row carries its scenario's name).
    engine : str
        The engine the row is computed on.
    keep : sequence of str
        The series the row carries.
    version : str
        The package version (``flatstep.__version__``).

    Returns
    -------
    str
        16 hexadecimal digits of SHA-256 over the canonical JSON of all four.
    """
    text = json.dumps([version, engine, list(keep), _canonical(scenario)], sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]
