"""Where flatstep may write: never over one of the run's inputs, never over a file it did not write without force.

Every command and every function that writes a file checks its path here *before* any work, so a bad path is
refused in the first second, not after a long run (docs/errors.md, "Files flatstep writes").

A file counts as flatstep's own when it is missing, empty, or of a kind flatstep writes and recognises by its
first line (:data:`OWN_MARKS`: the CSV headers, JSON and batch files it writes). Anything else is a user's file:
it is replaced only with ``force=True`` (``--force`` on the command line). An input (a scenario, a recording)
is never replaced, with or without force.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable, Optional, Union

from .checks import InputError

PathLike = Union[str, "os.PathLike[str]"]

#: First bytes of the files flatstep writes: a recording or a run's series (CSV, header ``t,...``), a batch file
#: or a JSON document whose first key starts with ``flatstep``, a figure (PNG). A file that starts otherwise is not
#: flatstep's.
OWN_MARKS = (b"t,", b'{"flatstep', b"\x89PNG")


def _same(a: Path, b: Path) -> bool:
    """Whether two paths name the same file (or would: resolved, for files not yet there)."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def is_own_file(path: Path, marks: Iterable[bytes] = OWN_MARKS) -> bool:
    """Whether ``path`` is missing, empty, or starts as a file flatstep writes (one of ``marks``)."""
    if not path.exists():
        return True
    if not path.is_file():
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(256)
    except OSError:
        return False
    return head.strip() == b"" or head.startswith(tuple(marks))


def check_output(path: PathLike, source: str, *, inputs: Iterable[Optional[PathLike]] = (), force: bool = False,
                 marks: Iterable[bytes] = OWN_MARKS) -> Path:
    """The output file ``path`` as a Path, or an InputError naming ``source`` if it may not be written.

    Parameters
    ----------
    path : str or os.PathLike
        The file to be written.
    source : str
        Where the path was given (``"--record"``, ``"run_batch(out=)"``): the refusal names it.
    inputs : iterable of paths or None
        The run's inputs (scenario, recording); ``path`` may be none of them, even with ``force``.
    force : bool
        Replace a file that is not flatstep's (``--force``).
    marks : iterable of bytes
        The first bytes that make an existing file flatstep's own (default :data:`OWN_MARKS`).

    Raises
    ------
    InputError
        ``path`` is one of the inputs, a directory, in a directory that does not exist or is not writable, or an
        existing file that flatstep did not write (without ``force``).
    """
    out = Path(path)
    for given in inputs:
        if given is not None and _same(out, Path(given)):
            raise InputError(source, str(path), f"{source} {path}: is an input of this run ({given}); write to "
                             "another file (an input is never replaced, even with --force)")
    if out.is_dir():
        raise InputError(source, str(path), f"{source} {path}: is a directory; give a file name")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.exists():
        raise InputError(source, str(path), f"{source} {path}: the directory {parent} does not exist; create it "
                         "first or give a path in an existing directory")
    if not parent.is_dir():
        raise InputError(source, str(path), f"{source} {path}: {parent} is not a directory")
    if not os.access(parent, os.W_OK):
        raise InputError(source, str(path), f"{source} {path}: the directory {parent} is not writable")
    if not force and not is_own_file(out, marks):
        raise InputError(source, str(path), f"{source} {path}: exists and is not a file flatstep wrote; give "
                         "another name, or --force (force=True) to replace it")
    return out
