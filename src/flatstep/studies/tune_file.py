"""Tuned scenario files: the scenario file with its ``[controller]`` table holding a law's tuned gains.

:func:`tuned_toml` writes them (:mod:`tomlkit` keeps the rest of the file, its comments too); :func:`read_tuned`
reads one file or a directory of them back, one scenario per controller type, as ``flatstep compare --tuned``
does. Every tuned file starts with :data:`TUNED_MARK`, which makes it flatstep's own
(:func:`flatstep.validate.paths.check_output`).
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Mapping

import tomlkit
import tomlkit.exceptions

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..control.spec import LAW_GAINS, OPTION_LAWS, ControllerSpec
from ..validate import InputError
from .scenario_file import ScenarioFile, read_scenario_file
from .tune_laws import RULE_KEYS, law_gains

#: The first bytes of a tuned file.
TUNED_MARK = b"# flatstep tune:"
#: The ``[controller]`` keys a tuned table drops whatever its law: the law's name and options (given again as
#: ``type``) and the rule's scalings.
_DROPPED = {"type", "law", *OPTION_LAWS, *RULE_KEYS}
#: Every law's gain keys: a tuned table keeps those of its own law only.
_GAIN_KEYS = {k for keys in LAW_GAINS.values() for k in keys}


def tuned_toml(text: str, kind: str, gains: Mapping[str, float], note: str) -> str:
    """The scenario file ``text`` with ``[controller] type = kind`` and the tuned ``gains``; ``note`` heads it.

    The other ``[controller]`` keys stay (``design``: the observer the design gives, ``measurement``, ...), but for
    another law's gains; the gains given replace those the design (or the file) would give.

    Raises
    ------
    ValueError
        ``text`` is not TOML, or ``gains`` are not the keys of the law of ``kind``.
    """
    row = law_gains(kind)
    if set(gains) != set(row.keys):
        raise ValueError(f"gains {sorted(gains)} are not the tunable gains of {kind!r}: {list(row.keys)}")
    try:
        doc = tomlkit.parse(text)
    except tomlkit.exceptions.ParseError as exc:
        raise ValueError(f"the scenario file is not TOML: {exc}") from None
    old = tomllib.loads(text).get("controller", {})
    table = tomlkit.table()
    table.add("type", kind)
    own = LAW_GAINS[ControllerSpec.parse(kind).law]
    for key, value in old.items():
        if key not in _DROPPED and key not in row.keys and (key not in _GAIN_KEYS or key in own):
            table.add(key, value)
    for key in row.keys:
        table.add(key, float(gains[key]))
    if "controller" in doc:
        del doc["controller"]
    doc["controller"] = table
    lines = [f"{TUNED_MARK.decode()} {note}"] + [line for line in doc.as_string().splitlines()
                                                  if not line.startswith(TUNED_MARK.decode())]
    return "\n".join(lines).rstrip() + "\n"


def read_tuned(path: str | Path, source: str = "--tuned") -> dict[str, ScenarioFile]:
    """The tuned scenario files at ``path`` (a file, or a directory's ``*.toml`` that :func:`tuned_toml` wrote).

    Returns them by controller type. Raises an :class:`InputError` naming ``source`` for a path that is neither,
    a directory without a tuned file, or two files of one type.
    """
    where = Path(path)
    if where.is_dir():
        files = sorted(p for p in where.glob("*.toml") if p.read_bytes().startswith(TUNED_MARK))
        if not files:
            raise InputError(source, str(path), f"{source} {path}: the directory holds no tuned scenario file "
                             f"(a .toml starting with {TUNED_MARK.decode()!r}); write them with flatstep tune --out")
    elif where.is_file():
        files = [where]
    else:
        raise InputError(source, str(path), f"{source} {path}: no such file or directory; give a file or a "
                         "directory that flatstep tune --out wrote")
    out: dict[str, ScenarioFile] = {}
    for f in files:
        sf = read_scenario_file(f)
        kind = sf.scenario.controller_type
        if kind in out:
            raise InputError(source, str(path), f"{source} {path}: {out[kind].path} and {f} both tune {kind!r}; "
                             "keep one")
        out[kind] = sf
    return out
