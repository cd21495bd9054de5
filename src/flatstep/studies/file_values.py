"""Reading a scenario file's TOML and its values, each refusal naming ``file:table.key``, the value and why."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Callable, TypeVar

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..validate import InputError
from .scenario_keys import KEYS, RENAMED

T = TypeVar("T")

#: Where a value refused by a constructor was given in a scenario file, when its name is not its key.
SOURCES = {"control_period": "drive.control_rate", "t0": "plan.t0", "tf": "plan.tf", "t_end": "t_end",
           "substeps": "drive.substeps", "bandwidth_scale": "controller.bandwidth_scale",
           "measurement": "controller.measurement", "controller_type": "controller.type"}


def read_toml(path: Path) -> dict[str, Any]:
    """The TOML document at ``path``, or a ValueError naming the file and why it cannot be read."""
    where = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ValueError(f"{where}: no such scenario file") from None
    except IsADirectoryError:
        raise ValueError(f"{where}: is a directory, not a scenario file (give a .toml file)") from None
    except PermissionError:
        raise ValueError(f"{where}: cannot read the scenario file (permission denied)") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not a text file (UTF-8): {exc.reason} at byte {exc.start}") from None
    except OSError as exc:
        raise ValueError(f"{where}: cannot read the scenario file: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML: {exc}") from None


def check_keys(where: str, table: Any, section: str) -> dict[str, Any]:
    """``table`` if it is a table of known keys of ``section``; an old name is refused with its new one."""
    label = f"[{section}]" if section else "the top level"
    if not isinstance(table, dict):
        raise ValueError(f"{where}: {label} must be a table, got {table!r}")
    for key, value in table.items():
        advice = RENAMED.get((section, key)) or RENAMED.get(("*", key))
        if advice:
            raise InputError(key, value, f"{where}:{section + '.' if section else ''}{key}: {key} is an old name "
                                         f"(given {value!r}): {advice}")
    unknown = sorted(set(table) - set(KEYS[section]))
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown} in {label}; valid: {list(KEYS[section])}")
    return table


def source(where: str, section: str, name: str, keys: Any) -> str:
    """``file:table.key`` of the value ``name`` refused in ``[section]`` (whose keys are ``keys``)."""
    if section == "scenario" and name in SOURCES:  # the Scenario's fields come from several tables
        return f"{where}:{SOURCES[name]}"
    if name in keys:
        return f"{where}:{section + '.' if section else ''}{name}"
    if name in SOURCES:
        return f"{where}:{SOURCES[name]}"
    return f"{where}:{section}" if section else where


def wrap(where: str, section: str, build: Callable[..., T], **kwargs: Any) -> T:
    """``build(**kwargs)``, its errors raised again as a ValueError naming the file, table and key."""
    try:
        return build(**kwargs)
    except InputError as exc:
        raise exc.at(source(where, section, exc.name, kwargs)) from None
    except (TypeError, ValueError) as exc:
        named = [k for k in kwargs if str(exc).startswith(f"{k}=")]
        if named:  # a consistency check that names its key first ("i_hold=2.0 A must be below i_max ...")
            raise InputError(named[0], kwargs[named[0]], f"{source(where, section, named[0], kwargs)}: {exc}") from None
        raise ValueError(f"{where}: [{section}] {exc}") from None


def value(where: str, section: str, key: str, check: Callable[[Any], T], given: Any) -> T:
    """``check(given)`` for the value of ``key`` in ``[section]``, its error naming ``file:section.key``."""
    try:
        return check(given)
    except InputError as exc:
        raise exc.at(source(where, section, key, (key,))) from None
