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
import tempfile
from pathlib import Path
from typing import Iterable, Mapping, Optional, Union

from .checks import InputError

PathLike = Union[str, "os.PathLike[str]"]

#: First bytes of the files flatstep writes: a recording or a run's series (CSV, header ``t,...``), a batch file
#: or a JSON document whose first key starts with ``flatstep``, a figure (a PNG signed by Matplotlib, which draws
#: flatstep's figures: its ``Software`` text in the first 256 bytes). A file that starts otherwise is not flatstep's.
OWN_MARKS = (b"t,", b'{"flatstep', b"\x89PNG")
#: The first bytes of a CSV file of series or a recording (header ``t,...``).
CSV_MARK = (b"t,",)
#: The first bytes of a PNG figure.
PNG_MARK = (b"\x89PNG",)


def json_marks(*keys: str) -> tuple[bytes, ...]:
    """The first bytes of a JSON report flatstep writes whose first key is one of ``keys`` (indented or compact)."""
    return tuple(m for k in keys for m in (b'{\n  "' + k.encode() + b'"', b'{"' + k.encode() + b'"'))


def as_path(path: object, source: str) -> Path:
    """``path`` as a Path, or an InputError naming ``source`` if it is not a str or os.PathLike of str."""
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)) or not isinstance(os.fspath(path), str):
        raise InputError(source, path, f"{source}={path!r} is not a path; give a file name (a str or a pathlib.Path)")
    if not str(path):
        raise InputError(source, path, f"{source}={path!r}: give a file name (the path is empty)")
    return Path(path)


def writable_dir(folder: Path) -> bool:
    """Whether a file can be created in the directory ``folder``.

    The OS is asked, then a temporary file is created there and removed at once: root passes every access check,
    yet cannot write into /proc or onto a read-only mount.
    """
    if not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


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
    if head.startswith(PNG_MARK[0]):  # a figure: flatstep's are drawn by Matplotlib, which signs the file
        return PNG_MARK[0] in tuple(marks) and b"Software\x00Matplotlib" in head
    return head.strip() == b"" or head.startswith(tuple(marks))


def check_output(path: PathLike, source: str, *, inputs: Iterable[Optional[PathLike]] = (), force: bool = False,
                 marks: Iterable[bytes] = OWN_MARKS, force_hint: str = "--force (force=True) to replace it") -> Path:
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
    force_hint : str
        How the caller replaces a user's file, for the refusal (``"fresh=True to move it aside"``).

    Raises
    ------
    InputError
        ``path`` is one of the inputs, a directory, in a directory that does not exist or is not writable, or an
        existing file that flatstep did not write (without ``force``).
    """
    out = as_path(path, source)
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
    if not writable_dir(parent) or (out.exists() and not os.access(out, os.W_OK)):
        raise InputError(source, str(path), f"{source} {path}: cannot be written there (the directory {parent} or "
                         "the file is not writable)")
    if not force and not is_own_file(out, marks):
        raise InputError(source, str(path), f"{source} {path}: exists and is not a file flatstep wrote; give "
                         f"another name, or {force_hint}")
    return out


def check_output_dir(path: PathLike, source: str, files: Mapping[str, Iterable[bytes]], *,
                     inputs: Iterable[Optional[PathLike]] = (), force: bool = False) -> list[Path]:
    """The files ``files`` (name -> their first bytes) of the output directory ``path``, checked; nothing is created.

    The directory may be missing (it is created when the command writes, after its work), if its nearest existing
    ancestor is a writable directory; each file is checked by :func:`check_output` once the directory exists.

    Parameters
    ----------
    path : str or os.PathLike
        The output directory (``--out``).
    source : str
        Where the path was given (``"--out"``).
    files : dict of str to iterable of bytes
        The files the command writes there and the marks (:data:`OWN_MARKS`) of each.
    inputs : iterable of paths or None
        The run's inputs: none of the files may be one.
    force : bool
        Replace files that are not flatstep's (``--force``).

    Raises
    ------
    InputError
        ``path`` is a file, lies under a file, or cannot be created; or one of its files may not be written.
    """
    out, inputs = as_path(path, source), list(inputs)
    if out.exists() and not out.is_dir():
        raise InputError(source, str(path), f"{source} {path}: exists and is not a directory; give a directory "
                         "(it is created if missing)")
    if not out.exists():
        parent = out.absolute().parent
        while not parent.exists():
            parent = parent.parent
        if not parent.is_dir():
            raise InputError(source, str(path), f"{source} {path}: {parent} is a file, not a directory")
        if not writable_dir(parent):
            raise InputError(source, str(path), f"{source} {path}: cannot create it: the directory {parent} is "
                             "not writable")
        for name in files:  # new files; still, none may be an input (named through a path not yet there)
            for given in inputs:
                if given is not None and _same(out / name, Path(given)):
                    raise InputError(source, str(path), f"{source} {path}: its {name} is an input of this run "
                                     f"({given}); write to another directory")
        return [out / name for name in files]
    return [check_output(out / name, source, inputs=inputs, force=force, marks=marks)
            for name, marks in files.items()]


def check_distinct(outputs: Mapping[str, Optional[PathLike]]) -> None:
    """Raise an InputError if two of the outputs (where given -> path; ``None``: not written) are the same file."""
    seen: list[tuple[str, Path]] = []
    for source, path in outputs.items():
        if path is None:
            continue
        for other, earlier in seen:
            if _same(Path(path), earlier):
                raise InputError(source, str(path), f"{source} {path}: is also written by {other}; give another "
                                 "name (one of the two would overwrite the other)")
        seen.append((source, Path(path)))
