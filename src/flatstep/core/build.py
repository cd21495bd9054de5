"""cffi API-mode build of the C core (csrc/) as ``flatstep._flatstep_core``; run by setuptools at install time.

setup.py names this file in ``cffi_modules`` (setuptools runs it by path); nothing imports it at run time and
nothing compiles at run time.

Every ``csrc/*.c`` is compiled in. The declarations Python sees are the headers' own: each header marks the
structs, enums and prototypes the binding needs between a ``// cffi:begin`` and a ``// cffi:end`` line, and
this script collects those blocks in include order. A new module (a controller, say) needs no line here.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from cffi import FFI

ROOT = Path(__file__).resolve().parents[3]
CSRC = ROOT / "csrc"
BLOCK = re.compile(r"^// cffi:begin\n(.*?)^// cffi:end$", re.S | re.M)
INCLUDE = re.compile(r'^#include "(\w+)\.h"', re.M)


def _header_order(headers: dict[str, str]) -> list[str]:
    """Header names with every header after the headers it includes (depth-first topological order)."""
    order: list[str] = []

    def visit(name: str, path: tuple[str, ...]) -> None:
        if name in order or name not in headers:
            return
        if name in path:
            raise RuntimeError(f"include cycle in csrc/: {' -> '.join(path + (name,))}")
        for dep in INCLUDE.findall(headers[name]):
            visit(dep, path + (name,))
        order.append(name)

    for name in sorted(headers):
        visit(name, ())
    return order


def collect_cdef(csrc: Path = CSRC) -> tuple[str, list[str]]:
    """The cdef text of every marked header block and the names of the headers that have one."""
    headers = {p.stem: p.read_text() for p in csrc.glob("*.h")}
    parts, names = ["typedef double fs_real;"], []
    for name in _header_order(headers):
        blocks = BLOCK.findall(headers[name])
        if blocks:
            names.append(name)
            parts += [f"// {name}.h"] + blocks
    return "\n".join(parts), names


def _relative(path: Path) -> str:
    """Source paths relative to the working directory (setuptools runs from the project root)."""
    try:
        return os.path.relpath(path)
    except ValueError:  # another drive on Windows
        return str(path)


CDEF, HEADERS = collect_cdef()
ffibuilder = FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "flatstep._flatstep_core",
    "\n".join(f'#include "{h}.h"' for h in HEADERS),
    sources=sorted(_relative(p) for p in CSRC.glob("*.c")),
    include_dirs=[_relative(CSRC)],
    # C99 also keeps GCC from contracting a*b+c into FMAs, so the core rounds like the NumPy reference.
    extra_compile_args=["-std=c99", "-O2"] if os.name != "nt" else [],
    libraries=["m"] if os.name != "nt" else [],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
