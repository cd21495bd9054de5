"""The package's layers: imports run one way (tools/import_graph.py), and no new import cycle appears."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

import import_graph  # noqa: E402

#: The cycles still to break (lazy imports inside functions): none; a new one fails this test.
KNOWN_CYCLES: list[list[str]] = []


def test_no_import_runs_back_up_the_layers():
    up = import_graph.upward(import_graph.graph())
    assert import_graph.MAX_UPWARD == 0
    assert len(up) <= import_graph.MAX_UPWARD, up


def test_no_import_cycle():
    cycles = import_graph.cycles(import_graph.graph())
    assert all(c in KNOWN_CYCLES for c in cycles), [c for c in cycles if c not in KNOWN_CYCLES]


def test_nothing_below_the_binding_imports_it():
    g = import_graph.graph()
    below = [(a, b) for a, deps in g.items() for b in deps
             if b.startswith("flatstep.core") and import_graph.layer(a) < import_graph.LAYERS["core"]]
    assert below == [], below


def test_the_tool_sees_an_upward_import_and_a_cycle():
    g = {"flatstep.model.a": {"flatstep.cli.b"}, "flatstep.cli.b": {"flatstep.model.a"}}
    assert import_graph.upward(g) == [("flatstep.model.a", "flatstep.cli.b")]
    assert import_graph.cycles(g) == [["flatstep.cli.b", "flatstep.model.a"]]


def test_imports_for_the_type_checker_alone_do_not_count(tmp_path, monkeypatch):
    pkg = tmp_path / "flatstep"
    (pkg / "model").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "model" / "__init__.py").write_text("")
    (pkg / "model" / "a.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..cli import b\n"
                                        "def f():\n    from ..cli import c\n")
    monkeypatch.setattr(import_graph, "ROOT", pkg)
    monkeypatch.setattr(import_graph, "_KNOWN", set())
    assert import_graph.imports(pkg / "model" / "a.py") == ["flatstep.cli"]
