"""The package's import graph: cycles between modules and imports that run back up the layers.

The layers follow a move through the code (README, "How it fits together"); a module may import its own layer and
those below it. An import that names a higher layer runs back up; one inside a function (a lazy import) counts the
same, since it still ties the lower layer to the higher one. Imports under ``if TYPE_CHECKING:`` do not count: they
are for the type checker and never run.

    python tools/import_graph.py          # the upward imports and the cycles, one per line; exit 1 if any cycle

tests/test_layers.py holds the package to :data:`MAX_UPWARD` upward imports (none) and no cycle.
"""
from __future__ import annotations

import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "src" / "flatstep"

#: The layers, lowest first: a package folder (or a top-level module) and its rank.
LAYERS = {
    "validate": 0, "errors": 0, "json_out": 0, "_version": 0,
    "model": 1,
    "plan": 2,
    "control": 3,
    "loop": 4,
    "core": 5,  # the binding to the C core: it imports the parts above, and nothing below imports it
    "_flatstep_core": 0,  # the compiled C core itself: it imports no Python
    "engine": 6,
    "interop": 7,
    "studies": 7,
    "bench": 8,
    "cli": 9, "__main__": 9,
    "__init__": 10,
}

#: Most imports that may run back up the layers: none. A lower layer that needs a higher one's work takes it as
#: data (each part gives its own C fields to the binding) or moves the shared piece down.
MAX_UPWARD = 0


def module_name(path: Path) -> str:
    """The dotted name of a source file below ROOT (a package's __init__ is the package)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts = parts[:-1]
    return ".".join(["flatstep", *parts])


def layer(module: str) -> int:
    """The layer of a dotted flatstep module name."""
    parts = module.split(".")
    if len(parts) == 1:
        return LAYERS["__init__"]
    return LAYERS.get(parts[1], LAYERS["__init__"])


def imports(path: Path) -> list[str]:
    """The flatstep modules a source file imports (absolute names), lazy imports included."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: list[str] = []
    tree = ast.parse(path.read_text(), str(path))
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If) and _is_type_checking(block.test)
                   for stmt in block.body for n in ast.walk(stmt)}
    for node in ast.walk(tree):
        if id(node) in typing_only:  # under `if TYPE_CHECKING:`: for the type checker, never run
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("flatstep"):
                known = _known()
                subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in known]
                found.extend(subs or [target])
        elif isinstance(node, ast.Import):
            found.extend(a.name for a in node.names if a.name.startswith("flatstep"))
    return found


def _known() -> set[str]:
    """The dotted names of every flatstep module (cached)."""
    if not _KNOWN:
        _KNOWN.update(module_name(p) for p in ROOT.rglob("*.py"))
        _KNOWN.add("flatstep._flatstep_core")
    return _KNOWN


_KNOWN: set[str] = set()


def _is_type_checking(test: ast.expr) -> bool:
    """Whether an if-test is ``TYPE_CHECKING`` or ``typing.TYPE_CHECKING``."""
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def graph() -> dict[str, set[str]]:
    """Every module's flatstep imports."""
    g: dict[str, set[str]] = defaultdict(set)
    for path in sorted(ROOT.rglob("*.py")):
        g[module_name(path)].update(m for m in imports(path) if m != module_name(path))
    return g


def upward(g: dict[str, set[str]]) -> list[tuple[str, str]]:
    """The imports from a module to a higher layer (a package's __init__ re-exporting its own modules excepted)."""
    return sorted((a, b) for a, deps in g.items() for b in deps if layer(b) > layer(a) and not b.startswith(a + "."))


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), package __init__ files left out."""
    nodes = [n for n in g if not _is_package(n)]
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in g.get(v, ()):
            if _is_package(w) or w not in g:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for n in nodes:
        if n not in index:
            visit(n)
    return out


def _is_package(name: str) -> bool:
    """Whether a dotted name is a package (its __init__), which only re-exports."""
    return (ROOT.joinpath(*name.split(".")[1:]) / "__init__.py").exists() or name == "flatstep"


def main() -> int:
    """Print the upward imports and the cycles; 1 if there is a cycle or more than MAX_UPWARD upward imports."""
    g = graph()
    up, cyc = upward(g), cycles(g)
    for a, b in up:
        print(f"upward: {a} -> {b}")
    for c in cyc:
        print("cycle: " + " <-> ".join(c))
    print(f"{len(up)} upward import(s) (at most {MAX_UPWARD}), {len(cyc)} cycle(s)")
    return 1 if cyc or len(up) > MAX_UPWARD else 0


if __name__ == "__main__":
    sys.exit(main())
