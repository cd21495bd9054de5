"""Many closed-loop runs in one call: :func:`run_batch`, on all cores or on any ``concurrent.futures`` executor.

Each worker receives a chunk of scenarios and returns one summary row per run (the keys of
:meth:`~flatstep.engine.result.SimResult.summary` plus ``index``, ``name`` and ``error``), so that only a few
numbers per run cross process boundaries. With ``out=`` the rows are appended to a batch file (JSON lines,
:mod:`flatstep.studies.batch_file`) as chunks finish; running the same batch again with the same file skips
the rows already there.
"""
from __future__ import annotations

import json
import math
import os
import sys
import time
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from contextlib import ExitStack
from dataclasses import replace
from itertools import product
from pathlib import Path
from typing import Any, Iterable, Optional, Sequence, TextIO

from ..engine.result import SimResult
from ..engine.simulate import RUNNERS
from ..validate import InputError, check_bool, check_integer
from ..validate.paths import check_output
from .batch_file import BATCH_MARK, BatchWriteError, open_batch_file
from .executors import as_executor, check_cancelled, default_chunk_size, executor_workers, run_chunks
from .fingerprint import fingerprint
from .scenario import Scenario
from .workers import die_with_parent


def _run_one(index: int, scenario: Scenario, engine: str, keep: Sequence[str]) -> dict[str, Any]:
    """One scenario's summary row (and the ``keep`` series), or its error row if the run is refused or fails."""
    row: dict[str, Any] = {"index": index, "name": scenario.name}
    try:
        result = scenario.run(engine=engine)
        row.update(result.summary())
        series = result.series()
        row.update({f"series_{k}": series[k].tolist() for k in keep})
        row["error"] = None
    except ValueError as exc:  # a refused or infeasible run is a result, not a crash
        row.update(status="refused", error=f"{type(exc).__name__}: {exc}")
    except RuntimeError as exc:  # so is a run that stopped early (RunError: non-finite state, step bound)
        row.update(status="failed", error=f"{type(exc).__name__}: {exc}")
    return row


def _run_chunk(chunk: list[tuple[int, Scenario]], engine: str, keep: Sequence[str]) -> list[dict[str, Any]]:
    """The rows of a chunk of ``(index, scenario)`` pairs, one :func:`_run_one` each.

    Between runs it stops if its batch was interrupted (:func:`~flatstep.studies.executors.check_cancelled`).
    """
    rows = []
    for i, s in chunk:
        check_cancelled()
        rows.append(_run_one(i, s, engine, keep))
    return rows


def summarised_in_c(scenario: Scenario) -> bool:
    """Whether C ``batch_sampled`` can run the scenario and summarise it.

    It can for a sampled run (any controller, plant effect, sensors, observer, averaged bridge) with a constant
    load.
    """
    from .. import core

    loop = scenario.loop
    return (loop is not None and core.drive_unsupported(loop.drive, loop.sensors) is None
            and scenario.simulated_plant.constant_load is not None)


def _run_chunk_c(chunk: list[tuple[int, Scenario]], engine: str, keep: Sequence[str]) -> list[dict[str, Any]]:
    """The rows of :func:`_run_chunk` for scenarios that :func:`summarised_in_c`, in one C call.

    All are simulated and summarised in C; an infeasible plan gives the same error row, and a run the C batch
    could not finish is run again by :func:`_run_one` for its error row.
    """
    from .. import core

    rows: dict[int, dict[str, Any]] = {}
    todo: list[tuple[int, Scenario]] = []
    runs: list[dict[str, Any]] = []
    for i, s in chunk:
        try:
            s.feasibility().raise_if_infeasible()
            ctrl = s.controller()
        except ValueError:
            rows[i] = _run_one(i, s, engine, keep)
            continue
        plant, loop = s.simulated_plant, s.loop
        assert loop is not None and plant.constant_load is not None  # summarised_in_c
        todo.append((i, s))
        runs.append(dict(controller=ctrl, motor=plant.motor, load=plant.constant_load, effects=plant.effects,
                         x0=s.plan.x0(plant.motor.Nr),
                         n_periods=max(1, math.ceil(s.t_end / loop.control_period - 1e-9)),
                         Ts=loop.control_period, substeps=loop.substeps, drive=loop.drive, sensors=loop.sensors,
                         observer=loop.observer, compute_delay=loop.compute_delay))
    summaries = core.run_sampled_summaries(runs)
    check_cancelled()  # an interrupted batch: the runs cut short are no results
    for (i, s), summary in zip(todo, summaries, strict=True):  # one summary per run
        rows[i] = {"index": i, "name": s.name, **summary, "error": None} if summary is not None \
            else _run_one(i, s, engine, keep)
    return [rows[i] for i, _ in chunk]


class _Progress:
    """A one-line progress bar on a stream (stderr), from ``after`` seconds on (short work stays quiet).

    It is redrawn at most 10 times a second on a terminal and every 2 s elsewhere (one line each).
    """

    def __init__(self, total: int, stream: TextIO, enabled: bool, after: float = 2.0) -> None:
        self.total, self.stream, self.enabled, self.after = total, stream, enabled, after
        self.done, self.start, self.last, self.shown = 0, time.perf_counter(), 0.0, False
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def update(self, n: int) -> None:
        """Count ``n`` more runs done and redraw the bar when it is due."""
        self.done += n
        now = time.perf_counter()
        if not self.enabled or (now - self.start < self.after and not self.shown):
            return
        if now - self.last > (0.1 if self.tty else 2.0) or self.done == self.total:
            self.shown = True
            self.last = now
            rate = self.done / max(now - self.start, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            bar = "#" * int(30 * self.done / max(self.total, 1))
            self.stream.write(f"{chr(13) if self.tty else ''}[{bar:<30}] {self.done}/{self.total} runs, "
                              f"{rate:.0f} runs/s, eta {eta:.1f} s")
            if self.done == self.total or not self.tty:
                self.stream.write("\n")
            self.stream.flush()


def _done_indices(out: Path) -> set[int]:
    """The indices of the rows in the batch file ``out`` (none if it does not exist), its header skipped.

    It reads the file as it is, checking no fingerprint; :func:`run_batch` checks them before reusing a row.
    """
    if not out.exists():
        return set()
    done = set()
    for line in out.read_text().splitlines():
        try:
            row = json.loads(line)
            if "flatstep_batch" not in row:
                done.add(int(row["index"]))
        except (ValueError, KeyError, TypeError):
            continue  # a line cut by an interruption
    return done


def run_batch(scenarios: Sequence[Scenario], *, engine: str = "c", executor: Optional[Any] = None,
              workers: Optional[int] = None, chunk_size: Optional[int] = None, progress: Optional[bool] = None,
              out: str | Path | None = None, keep: Sequence[str] = (), fresh: bool = False) -> list[dict[str, Any]]:
    """Run every scenario and return one summary row per scenario, in input order.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The runs; build grids with :func:`scenario_grid`.
    engine : str
        ``"c"`` (default) or a reference engine, as for :func:`flatstep.simulate`.
    executor : concurrent.futures.Executor or distributed.Client, optional
        Any executor, or a Dask ``distributed.Client`` (its ``get_executor()`` is used; docs/scaling.md);
        default: ``workers`` threads on the C engine (its runs release the GIL), a process pool of ``workers``
        processes on the reference engines, whose workers end when the calling process dies
        (:func:`die_with_parent`).
    workers : int, optional
        Without ``executor``: the threads or processes of the default executor (default: all cores). With
        one: how many tasks it runs at once, which sets the chunk size (default: asked of the executor by
        :func:`~flatstep.studies.executors.executor_workers`: a Dask cluster's worker threads, a pool's
        ``max_workers``; all cores of this machine if it does not tell).
    chunk_size : int, optional
        Scenarios per task (default: enough for about 8 tasks per worker).
    progress : bool, optional
        ``False`` draws no progress bar; otherwise one is drawn on stderr once the work has taken more than 2 s.
    out : str or Path, optional
        A batch file (JSON lines, docs/batch-files.md): a header, then one row per run, appended as chunks
        finish, each with its scenario's fingerprint. Run again with the same file, the batch reuses the rows
        already there, provided the file was written by this version of flatstep, for this engine and
        ``keep``, and each row's fingerprint is that of the scenario at its index (the list may have grown);
        otherwise it is refused with a ValueError. A lock file ``<out>.lock`` keeps a second writer out. A file
        that is not a batch file (nor empty) is refused before any run, unless ``fresh`` (it is then moved aside).
    keep : sequence of str
        Names of time series (see :meth:`~flatstep.engine.result.SimResult.series`) to return in each row as
        ``series_<name>`` lists, for figures.
    fresh : bool
        Start the file ``out`` afresh: an existing file is renamed to ``<out>.bak`` (``.bak.2``, ... if taken),
        never deleted.

    Returns
    -------
    list of dict
        One row per scenario, in input order.

    Raises
    ------
    ValueError
        For a bad argument (an InputError naming it: also an executor that hands back no rows, or rows of another
        task), a path ``out`` that cannot be written or is not a batch file (checked before any run), a file ``out``
        that holds another batch (naming what differs), or a file another live process is writing (naming the
        lock and its pid).
    BatchWriteError
        If writing ``out`` fails (an OSError, e.g. a full disk): the writing stops, the batch runs on to its
        end, and then this exception carries every row (``.rows``, input order) and the file (``.path``).

    Notes
    -----
    Summary rows of sampled runs on the C engine (:func:`summarised_in_c`, no ``keep``) are computed in C, one
    call per chunk (``core.run_sampled_summaries``: runs and summaries in C, threads instead of processes,
    since the C call releases the GIL); the rows equal those of one ``Scenario.run`` per scenario.

    Ctrl-C (KeyboardInterrupt) stops the batch and is raised again; the rows finished before it are in
    ``out``, and a run of the same batch resumes from them. On threads (the C engine's default) the running
    chunks stop within one control period or step (their C runs poll a cancel flag); chunks running in
    other processes are cancelled if not started; running ones are not stopped by the batch (a terminal's
    Ctrl-C also reaches a local process pool's workers, which then stop themselves).

    A row is written with one ``os.write`` of a whole line, and the file is synced (``os.fsync``) after each
    chunk, so a crash loses at most the chunks in flight; a last line cut short is truncated off on the next
    run, with a warning. The lock is an ``O_CREAT | O_EXCL`` file holding the writer's pid, removed when the
    batch ends (also on an exception); one left by a killed writer (its pid gone) is taken over with a warning.
    """
    if isinstance(scenarios, (Scenario, str)) or not isinstance(scenarios, Iterable):
        raise ValueError(f"scenarios={scenarios!r} must be a sequence of Scenario (a list, or scenario_grid(...))")
    scenarios = list(scenarios)
    bad = [i for i, s in enumerate(scenarios) if not isinstance(s, Scenario)]
    if bad:
        raise ValueError(f"scenarios[{bad[0]}]={scenarios[bad[0]]!r} is not a flatstep Scenario")
    for name, value in (("workers", workers), ("chunk_size", chunk_size)):
        if value is not None:
            check_integer(name, value)
    fresh = check_bool("fresh", fresh)
    engines = sorted({e for _, e in RUNNERS})
    if engine not in engines:
        raise ValueError(f"engine={engine!r} is not an engine; valid: {engines}")
    if progress is not None:
        progress = check_bool("progress", progress)
    if isinstance(keep, (str, bytes)) or not isinstance(keep, Iterable):
        raise InputError("keep", keep, f"keep={keep!r} must be a sequence of series names, e.g. ('t', 'theta')")
    keep = list(keep)
    if not all(isinstance(k, str) for k in keep):
        raise InputError("keep", keep, f"keep={keep!r} must hold series names (strings), e.g. ('t', 'theta')")
    valid = set(SimResult.__dataclass_fields__) - {"meta"} | {"theta_error", "rho_error"}
    if set(keep) - valid:
        raise ValueError(f"keep={list(keep)!r} names unknown series; valid: {sorted(valid)}")
    if out is not None:  # before any work: not over a file that is not a batch file (fresh=True moves it aside)
        out = check_output(out, "run_batch(out=)", force=fresh, marks=BATCH_MARK,
                           force_hint="fresh=True to move it aside (to <out>.bak) and start afresh")
    in_c = engine == "c" and not keep and all(summarised_in_c(s) for s in scenarios)
    keep = tuple(keep)
    rows: dict[int, dict[str, Any]] = {}
    with ExitStack() as stack:
        sink = None
        if out is not None:
            from .. import _version

            version = _version.__version__
            fingerprints = [fingerprint(s, engine, keep, version) for s in scenarios]
            sink, done = open_batch_file(Path(out), fingerprints, [s.name for s in scenarios], engine, keep,
                                         version, fresh, stack)
            rows.update(done)
        todo = [(i, s) for i, s in enumerate(scenarios) if i not in rows]
        given = as_executor(executor) if executor is not None else None
        told = executor_workers(given) if given is not None else None
        n_workers = workers or told or os.cpu_count() or 1
        size = chunk_size or default_chunk_size(len(todo), n_workers)
        chunks = [todo[k:k + size] for k in range(0, len(todo), size)]
        bar = _Progress(len(todo), sys.stderr, progress is not False)

        def record(batch: list[dict[str, Any]]) -> None:
            for row in batch:
                rows[row["index"]] = row
            if sink is not None:
                sink.append(batch)
            bar.update(len(batch))

        run_chunk = _run_chunk_c if in_c else _run_chunk
        if given is None and (n_workers == 1 or len(chunks) <= 1):
            for chunk in chunks:
                record(run_chunk(chunk, engine, keep))
        else:
            # C runs release the GIL: threads share the work without a process pool's start-up; the Python
            # reference engines hold it and need processes, which end with this process.
            pool: Executor = given if given is not None else (
                ThreadPoolExecutor(max_workers=n_workers) if engine == "c"
                else ProcessPoolExecutor(max_workers=n_workers, initializer=die_with_parent,
                                         initargs=(os.getpid(),)))
            try:
                run_chunks(pool, run_chunk, chunks, (engine, keep), record)
            finally:
                if given is None:
                    pool.shutdown(cancel_futures=True)
    if sink is not None and sink.error is not None:
        raise BatchWriteError(sink.path, sink.error, [rows.get(i) for i in range(len(scenarios))])
    return [rows[i] for i in range(len(scenarios))]


def scenario_grid(base: Scenario, **axes: Iterable[Any]) -> list[Scenario]:
    """Every combination of the given values of ``Scenario`` fields.

    For example ``scenario_grid(base, measurement=["ideal", "model"], t_end=[0.06, 0.08])``. Names are
    ``base.name`` followed by the field values.
    """
    unknown = set(axes) - set(Scenario.__dataclass_fields__)
    if unknown:
        raise ValueError(f"unknown scenario field(s) {sorted(unknown)}; valid: {list(Scenario.__dataclass_fields__)}")
    keys = list(axes)
    bad = [k for k in keys if isinstance(axes[k], (str, bytes)) or not isinstance(axes[k], Iterable)]
    if bad:
        raise ValueError(f"{bad[0]}={axes[bad[0]]!r}: give the values of an axis as a list, e.g. {bad[0]}=[...]")
    grid = []
    for values in product(*(list(axes[k]) for k in keys)):  # one value per key
        label = ",".join(f"{k}={v!r}" if not hasattr(v, "as_dict") else f"{k}={v.as_dict()}"
                         for k, v in zip(keys, values, strict=True))
        grid.append(replace(base, name=f"{base.name}[{label}]", **dict(zip(keys, values, strict=True))))
    return grid
