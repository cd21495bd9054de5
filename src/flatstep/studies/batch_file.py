"""The JSON-lines file of a batch: a header, fingerprinted rows, one writer's lock, whole-line writes.

The file's first line is a header, ``{"flatstep_batch": 1, "version": ..., "engine": ..., "keep": [...],
"created": ..., "scenarios": n, "scenarios_hash": ...}``; every further line is one row, with its scenario's
``fingerprint`` after its ``index`` (:mod:`flatstep.studies.fingerprint`: a hash of the scenario's content,
the options that change a row and the package version), so that a row is reused only for the very run that
made it. docs/batch-files.md describes the format and the rules.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
import warnings
from contextlib import ExitStack
from pathlib import Path
from typing import Any, Optional, Sequence

from ..json_out import strict_json

#: The version of the file format, the value of the header's ``"flatstep_batch"`` key.
FORMAT = 1
#: The first bytes of a batch file (its header; a row, in the files of older versions, which had none): an existing
#: file that starts otherwise is not flatstep's, and is not replaced.
BATCH_MARK = (b'{"flatstep_batch"', b'{"index"')


class BatchWriteError(OSError):
    """Writing a batch file failed (e.g. a full disk); the rows are handed back instead.

    Parameters
    ----------
    path : Path
        The batch file.
    error : OSError
        The operating system's error.
    rows : list of dict or None
        One entry per scenario, in input order: its row, or ``None`` for a run not computed.
    action : str
        What failed: ``"writing"`` the rows, or ``"opening"`` the file.
    """

    def __init__(self, path: Path, error: OSError, rows: list[Optional[dict[str, Any]]],
                 action: str = "writing") -> None:
        done = sum(r is not None for r in rows)
        super().__init__(error.errno, f"{action} the batch file {path} failed ({error.strerror or error}); "
                                      f"{done} of {len(rows)} rows are on this exception's .rows, in input order")
        self.path, self.rows, self.error = path, rows, error


class BatchFileWarning(UserWarning):
    """A batch file was repaired, or a stale lock on it was taken over."""


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists (a process of another user counts; so does a zombie not yet reaped)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _lock_pid(lock: Path) -> Optional[int]:
    """The pid written in ``lock``, or ``None`` if it holds none (yet)."""
    try:
        text = lock.read_text().strip()
    except FileNotFoundError:
        return None
    return int(text) if text.isdigit() and int(text) > 0 else None


def acquire_lock(path: Path) -> Path:
    """Take ``<path>.lock``, created with ``O_CREAT | O_EXCL`` and holding this process's pid; return it.

    A lock whose pid no longer exists (its writer was killed) is taken over with a
    :class:`BatchFileWarning`; so is one that has held no pid for 10 s. Two processes taking over the same stale
    lock in the same instant is not guarded against.

    Raises
    ------
    ValueError
        When a live process holds the lock: it names the lock and the pid.
    """
    lock = path.with_name(path.name + ".lock")
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            pid = _lock_pid(lock)
            try:
                age, size = time.time() - lock.stat().st_mtime, lock.stat().st_size
            except FileNotFoundError:
                continue  # released in the meantime
            if pid is None and size > 0 and _lock_pid(lock) is None:  # text that is no pid: not a lock of ours
                raise ValueError(f"{path}: {lock} exists and is not a batch lock (it holds no process id); it is "
                                 "not removed: rename it, or write the batch to another file") from None
            if (pid is not None and pid_alive(pid)) or (pid is None and age < 10.0):
                holder = f"process {pid}" if pid is not None else "a process that has not written its pid yet"
                raise ValueError(f"{path} is being written by {holder} (lock {lock}); wait for that batch to "
                                 f"finish, or write to another file; if no batch is running, delete {lock}") from None
            if _lock_pid(lock) == pid:  # still the stale one
                warnings.warn(f"{lock}: taking over a stale lock (pid {pid} no longer runs)", BatchFileWarning,
                              stacklevel=4)
                lock.unlink(missing_ok=True)
            continue
        with os.fdopen(fd, "w") as f:
            f.write(f"{os.getpid()}\n")
        return lock
    raise ValueError(f"{path}: could not take the lock {lock}: other processes keep taking it")


def release_lock(lock: Path) -> None:
    """Remove ``lock`` if this process holds it."""
    if _lock_pid(lock) == os.getpid():
        lock.unlink(missing_ok=True)


def backup(path: Path) -> Path:
    """Rename ``path`` to ``<path>.bak`` (or ``.bak.2``, ``.bak.3``, ... if taken); return the new name."""
    bak = path.with_name(path.name + ".bak")
    n = 1
    while bak.exists():
        n += 1
        bak = path.with_name(f"{path.name}.bak.{n}")
    os.replace(path, bak)
    return bak


def header(engine: str, keep: Sequence[str], fingerprints: Sequence[str], version: str) -> dict[str, Any]:
    """The header line of a new batch file: format, package version, engine, keep, time, scenarios and hash."""
    return {"flatstep_batch": FORMAT, "version": version, "engine": engine, "keep": list(keep),
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "scenarios": len(fingerprints),
            "scenarios_hash": hashlib.sha256("".join(fingerprints).encode()).hexdigest()[:16]}


def _refuse(path: Path, what: str) -> ValueError:
    """The error for a file that holds another batch: the file, what differs and how to go on."""
    return ValueError(f"{path} holds another batch: {what}; pass fresh=True to move it to "
                      f"{path.name}.bak and start afresh, or write to another file")


def read_rows(path: Path, head: dict[str, Any], fingerprints: Sequence[str],
              names: Sequence[str]) -> dict[int, dict[str, Any]]:
    """The rows of the batch file ``path`` that belong to this batch, after checking and repairing the file.

    A missing or empty file is created with the header ``head``. A last line cut short (no newline, or not
    JSON) is truncated off with a :class:`BatchFileWarning` naming the byte count. A header that differs only
    in the scenarios (a grown list whose rows so far all match) is rewritten.

    Parameters
    ----------
    path : Path
        The batch file.
    head : dict
        The header of this batch (:func:`header`).
    fingerprints : sequence of str
        The fingerprint of each scenario, in input order.
    names : sequence of str
        The name of each scenario, for messages.

    Returns
    -------
    dict
        Index -> row (without its fingerprint) for every row the file holds.

    Raises
    ------
    ValueError
        If the file is not a batch file, or was written by another package version, engine or ``keep``, or has a
        row whose fingerprint is not that of the scenario at its index.
    """
    data = path.read_bytes() if path.exists() else b""
    end = data.rfind(b"\n") + 1  # the bytes of whole lines
    lines = data[:end].split(b"\n")[:-1]
    parsed: list[Any] = []
    for k, line in enumerate(lines):
        try:
            parsed.append(json.loads(line))
        except ValueError:
            if k < len(lines) - 1:
                raise ValueError(f"{path}: line {k + 1} is not JSON; it is not a flatstep batch file "
                                 "(pass fresh=True to move it aside and start afresh)") from None
            end -= len(line) + 1  # a last line cut short (then closed by a newline)
    if end < len(data):
        warnings.warn(f"{path}: dropping {len(data) - end} bytes of a last line cut short", BatchFileWarning,
                      stacklevel=4)
        os.truncate(path, end)
    if end == 0:
        _rewrite(path, head, b"")
        return {}
    first = parsed[0]
    if not isinstance(first, dict) or "flatstep_batch" not in first:
        raise _refuse(path, 'its first line is not a flatstep batch header (a JSON object with a "flatstep_batch" '
                            'key): it was written by an older flatstep or by something else')
    for key, what in (("flatstep_batch", "the file format"), ("version", "the flatstep version"),
                      ("engine", "the engine"), ("keep", "keep")):
        if first.get(key) != head[key]:
            raise _refuse(path, f"{what} differs: the file has {first.get(key)!r}, this batch {head[key]!r}")
    rows: dict[int, dict[str, Any]] = {}
    for k, row in enumerate(parsed[1:], start=2):
        if not isinstance(row, dict) or not isinstance(row.get("index"), int) or "fingerprint" not in row:
            raise _refuse(path, f"line {k} is not a batch row (an object with an index and a fingerprint)")
        i = row.pop("index")
        if not 0 <= i < len(fingerprints):
            raise _refuse(path, f"line {k} is the row of scenario {i}, and this batch has {len(fingerprints)}")
        if row.pop("fingerprint") != fingerprints[i]:
            raise _refuse(path, f"line {k}, the row of scenario {i} ({row.get('name')!r}), was computed for "
                                f"another scenario than this batch's scenario {i} ({names[i]!r})")
        rows[i] = {"index": i, **row}
    if (first.get("scenarios"), first.get("scenarios_hash")) != (head["scenarios"], head["scenarios_hash"]):
        _rewrite(path, {**head, "created": first.get("created")}, data[len(lines[0]) + 1:end])
    return rows


def _rewrite(path: Path, head: dict[str, Any], rest: bytes) -> None:
    """Replace ``path`` by ``head`` followed by ``rest``, atomically (a new file, synced, renamed over it)."""
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")  # a new file, never a user's
    tmp = Path(name)
    try:
        os.fchmod(fd, path.stat().st_mode & 0o7777 if path.exists() else 0o644)  # mkstemp's 0600 otherwise
        with os.fdopen(fd, "wb") as f:
            f.write(strict_json(head).encode() + b"\n" + rest)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


class RowWriter:
    """Appends rows to a batch file, each as one ``os.write`` of a whole line; syncs after each chunk.

    The first OSError stops the writing: it is kept in :attr:`error` (and announced by a
    :class:`BatchFileWarning`), a line written in part is truncated off if the file allows, and later rows are
    not written.

    Parameters
    ----------
    path : Path
        The batch file (checked by :func:`read_rows`).
    fingerprints : sequence of str
        The fingerprint of each scenario, written after each row's index.
    """

    def __init__(self, path: Path, fingerprints: Sequence[str]) -> None:
        self.path, self.fingerprints = path, fingerprints
        self.error: Optional[OSError] = None
        self.fd: Optional[int] = None
        self.size = 0  # the bytes of whole lines
        try:
            self.fd = os.open(path, os.O_WRONLY | os.O_APPEND)
            self.size = os.fstat(self.fd).st_size
        except OSError as exc:
            self.error = exc

    def _write(self, data: bytes) -> None:
        """Write ``data`` at the end of the file (``os.write`` until all of it is written)."""
        assert self.fd is not None
        view = memoryview(data)
        while view:
            view = view[os.write(self.fd, view):]

    def append(self, rows: Sequence[dict[str, Any]]) -> None:
        """Write ``rows`` (one line each, the fingerprint after the index), then ``os.fsync`` the file."""
        if self.error is not None or self.fd is None:
            return
        try:
            for row in rows:
                line = strict_json({"index": row["index"], "fingerprint": self.fingerprints[row["index"]], **row})
                data = line.encode() + b"\n"
                self._write(data)
                self.size += len(data)
            os.fsync(self.fd)
        except OSError as exc:
            self.error = exc
            try:
                os.ftruncate(self.fd, self.size)  # drop a line written in part (else the next run does)
            except OSError:
                pass
            warnings.warn(f"{self.path}: writing failed ({exc}); the batch goes on without writing, and its rows "
                          "come back on the BatchWriteError raised at its end", BatchFileWarning, stacklevel=4)
            self.close()

    def close(self) -> None:
        """Close the file."""
        if self.fd is not None:
            fd, self.fd = self.fd, None
            os.close(fd)


def open_batch_file(path: Path, fingerprints: Sequence[str], names: Sequence[str], engine: str, keep: Sequence[str],
                    version: str, fresh: bool, stack: ExitStack) -> tuple[RowWriter, dict[int, dict[str, Any]]]:
    """Lock the batch file ``path`` until ``stack`` closes, check and repair it; its writer and its rows.

    With ``fresh``, an existing file is first moved to ``<path>.bak`` (:func:`backup`).

    Parameters
    ----------
    path : Path
        The batch file.
    fingerprints : sequence of str
        The fingerprint of each scenario, in input order.
    names : sequence of str
        The name of each scenario, for messages.
    engine : str
        The batch's engine.
    keep : sequence of str
        The series its rows carry.
    version : str
        The package version.
    fresh : bool
        Start afresh.
    stack : ExitStack
        Releases the lock and closes the file when it closes.

    Returns
    -------
    tuple of (RowWriter, dict)
        The writer, and index -> row for the rows of this batch already in the file.

    Raises
    ------
    ValueError
        If ``path`` is a directory, holds another batch (:func:`read_rows`) or is locked (:func:`acquire_lock`).
    BatchWriteError
        If the file cannot be read, created or repaired (an OSError).
    """
    if path.is_dir():
        raise ValueError(f"out={str(path)!r} is a directory; give the name of a batch file (JSON lines)")
    if not path.parent.is_dir():
        raise ValueError(f"out={str(path)!r}: its folder {str(path.parent)!r} does not exist; create it first")
    lock = acquire_lock(path)
    stack.callback(release_lock, lock)
    try:
        if fresh and path.exists():
            backup(path)
        rows = read_rows(path, header(engine, keep, fingerprints, version), fingerprints, names)
    except OSError as exc:
        raise BatchWriteError(path, exc, [None] * len(fingerprints), action="opening") from exc
    sink = RowWriter(path, fingerprints)
    stack.callback(sink.close)
    return sink, rows
