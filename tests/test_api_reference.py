"""docs/api/ is the code's: generated from the public modules' numpydoc docstrings, every module classified.

``python tools/gen_api_reference.py`` writes the pages; these tests fail when a page differs from the code, when a
new module is neither public nor internal, or when a public docstring's Parameters section names a parameter the
signature does not have (or leaves one out).
"""
from __future__ import annotations

import importlib
import importlib.util
import inspect
from pathlib import Path
from types import ModuleType

import pytest

pytest.importorskip("numpydoc")
from numpydoc.docscrape import NumpyDocString  # noqa: E402

TOOL = Path(__file__).resolve().parent.parent / "tools" / "gen_api_reference.py"


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_api_reference", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gen = _tool()


def test_every_module_is_public_or_internal():
    assert gen.unclassified() == [], "add the module to PUBLIC or INTERNAL in tools/gen_api_reference.py"


def test_classified_modules_exist():
    known = set(gen.all_modules())
    listed = {m for mods in gen.PUBLIC.values() for m in mods}
    assert sorted(listed - known) == []


@pytest.mark.parametrize("path", sorted(gen.pages()), ids=lambda p: p.name)
def test_page_matches_the_code(path):
    assert path.exists() and path.read_text() == gen.pages()[path], "run python tools/gen_api_reference.py"


def _documented(obj) -> list[str]:
    doc = NumpyDocString(inspect.getdoc(obj) or "")
    names = []
    for p in doc["Parameters"]:
        names += [n.strip().lstrip("*") for n in p.name.split(",") if n.strip()]
    return names


def _callables():
    for mods in gen.PUBLIC.values():
        for rel in mods:
            module = importlib.import_module(f"flatstep.{rel}")
            for name in gen.public_names(module):
                obj = getattr(module, name)
                if inspect.isclass(obj):
                    yield f"{rel}.{name}", obj
                    for member_name, member in gen._members(obj):
                        if not isinstance(member, property):
                            yield f"{rel}.{name}.{member_name}", member
                elif callable(obj):
                    yield f"{rel}.{name}", obj


def test_parameters_sections_match_signatures():
    wrong = []
    for qualname, obj in _callables():
        documented = _documented(obj)
        if not documented:
            continue
        try:
            params = [p for p in inspect.signature(obj).parameters if p not in ("self", "cls")]
        except (TypeError, ValueError):
            continue
        extra = [n for n in documented if n not in params]
        missing = [n for n in params if n not in documented and not n.startswith("_")]
        if extra or missing:
            wrong.append(f"{qualname}: documents {extra} not in the signature, leaves out {missing}")
    assert wrong == []


def test_the_index_lists_every_top_level_name():
    import flatstep

    index = gen.render_index()
    for name in flatstep.__all__:
        assert f"| `{name}` |" in index
