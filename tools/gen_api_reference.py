"""Write docs/api/, the reference of flatstep's public Python API, from the code's numpydoc docstrings.

One page per layer (model, plan, control, loop, engine, studies, interop, validate), in the order a move flows
through them, and an index (docs/api/README.md) of the names ``import flatstep`` gives. A module is public when
:data:`PUBLIC` lists it; its public names are its ``__all__``, or else the classes and functions it defines whose
names do not start with ``_``. Every module of the package is either in :data:`PUBLIC` or in :data:`INTERNAL`, so
that a new module is a decision (tests/test_api_reference.py holds both, and that the pages match the code).

    python tools/gen_api_reference.py           # write the pages
    python tools/gen_api_reference.py --check   # exit 1 if a committed page differs from the code
"""
from __future__ import annotations

import argparse
import dataclasses
import enum
import importlib
import inspect
import pkgutil
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

from numpydoc.docscrape import NumpyDocString

DOCS = Path(__file__).resolve().parent.parent / "docs" / "api"

#: The public modules, per page (a layer of the package), in the order a move flows through them.
PUBLIC: dict[str, list[str]] = {
    "model": ["model.motor", "model.datasheet", "model.plant", "model.torque_model", "model.flat", "model.flat_dq",
              "model.equilibria", "model.psi", "model.pullout"],
    "plan": ["plan.protocol", "plan.rest_to_rest", "plan.waypoints", "plan.time_optimal", "plan.sequence",
             "plan.piecewise", "plan.limits", "plan.feasibility", "plan.d_current", "plan.loss_aware",
             "plan.copper", "plan.baselines", "plan.export", "plan.open_loop", "plan.time_optimal_dq"],
    "control": ["control", "control.feedforward", "control.build"],
    "loop": ["loop.drive", "loop.sensors", "loop.observers", "loop.reference", "loop.design"],
    "engine": ["engine.simulate", "engine.settings", "engine.result"],
    "studies": ["studies.scenario", "studies.scenario_file", "studies.batch", "studies.robustness", "studies.compare",
                "studies.verify", "studies.backoff", "studies.identify", "studies.identify_coverage",
                "studies.identify_result", "studies.excitation", "studies.record", "studies.calibrate",
                "studies.executors", "studies.pullout", "studies.open_loop", "studies.tune", "studies.tune_laws",
                "studies.frontier", "studies.held_out"],
    "interop": ["interop"],
    "validate": ["validate", "validate.limits", "validate.paths", "errors"],
}

#: The modules that are not public API: the parts the public modules are built from, the C binding, the command
#: line (documented by ``flatstep COMMAND --help``) and the benchmarks (docs/benchmarks.md).
INTERNAL = {
    "_version", "json_out", "__main__",
    "model.datasheet_math",
    "plan.arguments", "plan.time_optimal_c", "plan.envelope", "plan.margins", "plan.segments", "plan.smoothing",
    "plan.table_checks", "plan.time_optimal_dq_c", "plan.time_optimal_dq_envelope", "plan.time_optimal_dq_profile",
    "plan.time_optimal_dq_shoot", "plan.time_optimal_dq_policy", "plan.time_optimal_dq_phases",
    "plan.time_optimal_dq_ramp",
    "control.cascade", "control.dq_smc", "control.exact_linearization", "control.loops", "control.microstep",
    "control.protocol", "control.smc", "control.spec", "control.tuning",
    "studies.batch_file", "studies.calibrate_accuracy", "studies.file_values", "studies.fingerprint",
    "studies.identify_accuracy", "studies.identify_checks", "studies.identify_ls", "studies.plan_compare",
    "studies.scenario_keys", "studies.scenario_plan", "studies.workers", "studies.identify_detect",
    "studies.identify_quantization", "studies.tune_file", "studies.identify_separable", "studies.identify_terms",
    "interop.arguments", "interop.basis", "interop.controller_sys", "interop.dq", "interop.flat_sys",
    "interop.plant_sys",
    "validate.checks", "validate.ranges",
}

#: Package folders whose modules are internal as a whole.
INTERNAL_PACKAGES = ("cli", "bench", "core")

TITLES = {
    "model": "The motor model", "plan": "Planning", "control": "Controllers", "loop": "The drive loop",
    "engine": "Running a closed loop", "studies": "Studies of many runs", "interop": "python-control interop",
    "validate": "Validation and errors",
}


def all_modules() -> list[str]:
    """Every module of the flatstep package, relative to it (``"plan.limits"``), and the packages that export names."""
    import flatstep

    names = []
    for info in pkgutil.walk_packages(flatstep.__path__, "flatstep."):
        rel = info.name.removeprefix("flatstep.")
        if info.ispkg and not hasattr(importlib.import_module(info.name), "__all__"):
            continue  # a folder that exports nothing of its own: its modules are classified one by one
        names.append(rel)
    return sorted(n for n in names if n != "_flatstep_core")


def unclassified() -> list[str]:
    """The modules that are neither public nor internal."""
    public = {m for mods in PUBLIC.values() for m in mods}
    return [m for m in all_modules() if m not in public and m not in INTERNAL
            and m.split(".")[0] not in INTERNAL_PACKAGES and m not in INTERNAL_PACKAGES]


def public_names(module: ModuleType) -> list[str]:
    """The public names of a module: its ``__all__``, or the classes and functions it defines."""
    if hasattr(module, "__all__"):
        return list(module.__all__)
    return sorted(name for name, obj in vars(module).items()
                  if not name.startswith("_") and (inspect.isclass(obj) or inspect.isfunction(obj))
                  and getattr(obj, "__module__", None) == module.__name__)


_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")
_ADDRESS = re.compile(r" at 0x[0-9a-f]+")


def text(s: str) -> str:
    """The reST roles as code (``:class:`~a.b.C``` -> ```C```), in Markdown."""
    def short(m: re.Match[str]) -> str:
        whole = m.group(0)
        name = m.group(1)
        if ":math:" in whole:
            return f"`{name}`"
        return f"`{name.rsplit('.', 1)[-1]}`" if "~" in whole else f"`{name}`"
    return _ROLE.sub(short, s).replace("``", "`")


def cell(s: str) -> str:
    """A Markdown table cell: one line, pipes escaped."""
    return text(" ".join(s.split())).replace("|", "\\|")


def signature(name: str, obj: Callable[..., Any]) -> str:
    """``name(params)`` with the defaults as the code has them (addresses of objects left out)."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return name
    parts: list[str] = []
    star_done = False
    for p in sig.parameters.values():
        if p.kind is p.KEYWORD_ONLY and not star_done:
            parts.append("*")
            star_done = True
        prefix = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "")
        star_done = star_done or p.kind is p.VAR_POSITIONAL
        piece = prefix + p.name
        if p.annotation is not p.empty:
            piece += ": " + _annotation(p.annotation)
        if p.default is not p.empty:
            piece += (" = " if p.annotation is not p.empty else "=") + _ADDRESS.sub("", repr(p.default))
        parts.append(piece)
    tail = "" if sig.return_annotation is sig.empty else " -> " + _annotation(sig.return_annotation)
    return f"{name}({', '.join(parts)}){tail}"


def _annotation(a: Any) -> str:
    """An annotation as the code spells it (annotations are strings under ``from __future__ import annotations``)."""
    if isinstance(a, str):
        return a
    if hasattr(a, "__forward_arg__"):
        return str(a.__forward_arg__)
    if inspect.isclass(a):
        return a.__name__
    return str(a).replace("typing.", "")


def doc_sections(obj: Any) -> list[str]:
    """A docstring as Markdown: summary, extended summary, parameter/return/raise tables, notes, examples."""
    raw = inspect.getdoc(obj) or ""
    if not raw:
        return ["*(no docstring)*", ""]
    try:
        doc = NumpyDocString(raw)
    except Exception:  # a docstring numpydoc cannot parse: shown as it is
        return [text(raw), ""]
    out = []
    summary = " ".join(doc["Summary"])
    if summary:
        out += [text(summary), ""]
    if doc["Extended Summary"]:
        out += [text("\n".join(doc["Extended Summary"])), ""]
    for section in ("Parameters", "Attributes", "Returns", "Yields", "Raises"):
        items = doc[section]
        if not items:
            continue
        out += [f"**{section}**", "", "| name | type | description |", "|---|---|---|"]
        for p in items:
            out.append(f"| {cell(p.name) or '—'} | {cell(p.type)} | {cell(' '.join(p.desc))} |")
        out.append("")
    for section in ("Notes", "Examples"):
        if doc[section]:
            out += [f"**{section}**", "", text("\n".join(doc[section])), ""]
    return out


def _members(cls: type) -> list[tuple[str, Any]]:
    """The public methods and properties a class defines itself (not inherited, not dataclass fields)."""
    fields = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set()
    found = []
    for name, member in vars(cls).items():
        if name.startswith("_") or name in fields:
            continue
        if isinstance(member, (staticmethod, classmethod)):
            member = member.__func__
        if inspect.isfunction(member) or isinstance(member, property):
            found.append((name, member))
    return found


def render_object(qualname: str, obj: Any) -> list[str]:
    """One public name: its heading, signature and docstring; a class with its methods and properties."""
    short = qualname.rsplit(".", 1)[-1]
    out = [f"### `{qualname}`", ""]
    if inspect.isclass(obj):
        if issubclass(obj, enum.Enum):
            out += ["```python", f"class {short}(enum)", "```", ""]
        else:
            out += ["```python", "class " + signature(short, obj), "```", ""]
        out += doc_sections(obj)
        for name, member in _members(obj):
            if isinstance(member, property):
                out += [f"#### `{short}.{name}` (property)", ""] + doc_sections(member)
            else:
                out += [f"#### `{short}.{name}`", "", "```python", signature(name, member), "```", ""]
                out += doc_sections(member)
    elif callable(obj):
        out += ["```python", signature(short, obj), "```", ""] + doc_sections(obj)
    else:
        value = _ADDRESS.sub("", repr(obj))
        if len(value) > 200:
            value = value[:200] + " ..."
        out += ["```python", f"{short} = {value}", "```", ""]
    return out


def render_page(page: str) -> str:
    """The Markdown of one page: its modules in order, each with its docstring's summary and its public names."""
    out = [f"# {TITLES[page]}", "",
           "Generated from the code's docstrings by `python tools/gen_api_reference.py`; do not edit by hand.", ""]
    for rel in PUBLIC[page]:
        module = importlib.import_module(f"flatstep.{rel}")
        out += [f"## `flatstep.{rel}`", ""]
        mdoc = inspect.getdoc(module) or ""
        if mdoc:
            out += [text(mdoc.split("\n\n")[0]), ""]
        for name in public_names(module):
            out += render_object(f"flatstep.{rel}.{name}", getattr(module, name))
    return "\n".join(out).rstrip() + "\n"


def _home(obj: Any) -> str:
    """The page and module where a top-level name is documented (its defining module, if public)."""
    module = getattr(obj, "__module__", "") or ""
    rel = module.removeprefix("flatstep.")
    for page, mods in PUBLIC.items():
        for m in mods:
            if rel == m or rel.startswith(m + "."):
                return page
    for page in PUBLIC:  # defined in an internal module, exported by a public package
        if rel.split(".")[0] == page:
            return page
    return ""


def render_index() -> str:
    """docs/api/README.md: the pages, and each name ``import flatstep`` gives with the page that documents it."""
    import flatstep

    out = ["# API reference", "",
           "Generated from the code's numpydoc docstrings by `python tools/gen_api_reference.py`; "
           "tests/test_api_reference.py fails when a page differs from the code.", "",
           "## Pages, in the order a move flows through the package", ""]
    for page in PUBLIC:
        out.append(f"- [{TITLES[page]}]({page}.md): " + ", ".join(f"`flatstep.{m}`" for m in PUBLIC[page]))
    out += ["", "## `import flatstep`", "", "| name | what it is | page |", "|---|---|---|"]
    for name in flatstep.__all__:
        obj = getattr(flatstep, name)
        doc = inspect.getdoc(obj) if (inspect.isclass(obj) or callable(obj)) else ""
        summary = cell((doc or "").split("\n\n")[0]) if doc else ""
        page = _home(obj)
        link = f"[{page}]({page}.md)" if page else ""
        out.append(f"| `{name}` | {summary} | {link} |")
    return "\n".join(out).rstrip() + "\n"


def pages() -> dict[Path, str]:
    """Every page's path and text."""
    found = {DOCS / "README.md": render_index()}
    for page in PUBLIC:
        found[DOCS / f"{page}.md"] = render_page(page)
    return found


def main() -> int:
    """Write the pages, or with ``--check`` compare them; returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare the committed pages instead of writing them")
    args = parser.parse_args()
    missing = unclassified()
    if missing:
        print(f"modules neither in PUBLIC nor in INTERNAL: {', '.join(missing)}", file=sys.stderr)
        return 1
    found = pages()
    if args.check:
        stale = [p for p, t in found.items() if not p.exists() or p.read_text() != t]
        for p in stale:
            print(f"{p}: differs from the code: run tools/gen_api_reference.py")
        return 1 if stale else 0
    DOCS.mkdir(parents=True, exist_ok=True)
    for p, t in found.items():
        p.write_text(t)
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
