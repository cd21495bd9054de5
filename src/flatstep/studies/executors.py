"""The executor a batch runs on: how many tasks it runs at once, and its chunks run and stopped as one.

:func:`executor_workers` asks an executor how many workers it has (a Dask client's worker threads, a pool's
``max_workers``), so that a batch is cut into chunks for the cluster it runs on, not for the cores of the
machine that submits it. :func:`run_chunks` submits the chunks and records each as it finishes; on Ctrl-C
(or any exception while it waits) it cancels the chunks not started, and on threads it stops the running ones
within one control period: their C runs poll a cancel flag that the interrupted main thread sets.
"""
from __future__ import annotations

from concurrent.futures import Executor, Future, ThreadPoolExecutor, as_completed, wait
from typing import Any, Callable, Optional, Sequence, TypeVar, cast

#: Tasks per worker when the chunk size is not given: enough to even out runs of different lengths.
TASKS_PER_WORKER = 8

Chunk = TypeVar("Chunk")
Rows = list[dict[str, Any]]


class ChunkCancelled(Exception):
    """A chunk stopped because its batch was interrupted; its rows, if any, are not results."""


def as_executor(executor: Any) -> Executor:
    """The executor to submit a batch's chunks to: ``executor``, or a Dask client's executor.

    A Dask ``distributed.Client`` gives ``client.get_executor(pure=False)``, and a client's executor made
    without ``pure`` is made again with ``pure=False`` (its other options kept): a pure task is keyed by a hash
    of its arguments, which costs Dask time for every chunk of scenarios, and a batch never submits the same
    chunk twice. Raises a ValueError for anything else.
    """
    client, options = getattr(executor, "_client", None), getattr(executor, "_kwargs", None)
    if isinstance(executor, Executor):
        if client is not None and isinstance(options, dict) and "pure" not in options:
            return client.get_executor(pure=False, **options)
        return executor
    get = getattr(executor, "get_executor", None)
    if callable(get):
        return get(pure=False)
    raise ValueError(f"executor={executor!r} is not a concurrent.futures.Executor (nor a Dask Client, whose "
                     "get_executor() is one)")


def executor_workers(executor: Executor) -> Optional[int]:
    """How many tasks ``executor`` runs at once, or ``None`` if it does not tell.

    A Dask client's executor (``Client.get_executor()``) answers with its workers' threads
    (``Client.nthreads()``, over the workers it is restricted to, if any); a ``ThreadPoolExecutor`` or
    ``ProcessPoolExecutor`` with its ``max_workers``. A Dask cluster with no worker yet answers ``None``.
    """
    client = getattr(executor, "_client", None)
    if client is not None and callable(getattr(client, "nthreads", None)):
        restrict = getattr(executor, "_kwargs", {}).get("workers")
        total = sum(client.nthreads(restrict).values())
        return int(total) if total > 0 else None
    n = getattr(executor, "_max_workers", None)
    return n if isinstance(n, int) and n > 0 else None


def default_chunk_size(n_runs: int, n_workers: int) -> int:
    """Runs per task: enough for about :data:`TASKS_PER_WORKER` tasks per worker, at least one run."""
    return max(1, n_runs // (TASKS_PER_WORKER * n_workers))


def check_cancelled() -> None:
    """Raise :class:`ChunkCancelled` if this thread's batch was interrupted (its cancel flag is set)."""
    from ..core.structs import cancel_requested

    if cancel_requested():
        raise ChunkCancelled("the batch was interrupted")


def check_rows(executor: Any, chunk: Sequence[tuple[int, Any]], rows: Any) -> Rows:
    """``rows``, if they are a chunk's rows (a list of one dict per scenario, each with its ``index``).

    Raises
    ------
    InputError
        Naming the executor and the chunk's first row, when the executor handed back something else (``None``
        from a ``submit`` that does not run the function, rows of another chunk).
    """
    from ..validate import InputError

    want = sorted(i for i, _ in chunk)
    got = sorted(r.get("index", -1) for r in rows if isinstance(r, dict)) if isinstance(rows, list) else None
    if got != want or len(rows) != len(want):
        first = f"row {want[0]}" + (f" to {want[-1]}" if len(want) > 1 else "")
        name = getattr(chunk[0][1], "name", "?") if chunk else "?"
        shown = repr(rows) if len(repr(rows)) <= 80 else repr(rows)[:77] + "..."
        raise InputError("executor", executor, f"executor={executor!r} returned {shown} for the task of {first} "
                         f"(scenario {name!r}); a task must return what the submitted function returned: a list of "
                         f"{len(want)} summary row(s) with the indices {want[:5]}{'...' if len(want) > 5 else ''}; "
                         "check that the executor's submit() runs the function and hands back its result")
    return list(rows)


def _in_scope(flag: Any, run_chunk: Callable[..., Rows], chunk: Any, *args: Any) -> Rows:
    """``run_chunk(chunk, *args)`` with this thread's C runs polling ``flag``; its rows unless it was set."""
    from ..core.structs import cancel_scope

    with cancel_scope(flag):
        rows = run_chunk(chunk, *args)
    if flag[0]:
        raise ChunkCancelled("the batch was interrupted")
    return rows


def run_chunks(pool: Executor, run_chunk: Callable[..., Rows], chunks: Sequence[Chunk], args: tuple[Any, ...],
               record: Callable[[Rows], None]) -> None:
    """Submit ``run_chunk(chunk, *args)`` for every chunk on ``pool`` and ``record`` the rows as chunks finish.

    If waiting is interrupted (Ctrl-C's KeyboardInterrupt, or an exception raised by ``record``), the chunks
    not started are cancelled and the exception is raised again. On a ``ThreadPoolExecutor`` the running
    chunks are stopped first: their C runs poll a flag (:func:`flatstep.core.structs.cancel_scope`) that is
    set here, so they end within one control period or integrator step, and the exception is raised once
    they have. Chunks running in other processes (a process pool, a Dask cluster) are not stopped here.
    """
    from ..core.structs import cancel_flag

    flag = cancel_flag() if isinstance(pool, ThreadPoolExecutor) else None
    futures: list[Future[Rows]] = [pool.submit(run_chunk, chunk, *args) if flag is None
                                   else pool.submit(_in_scope, flag, run_chunk, chunk, *args) for chunk in chunks]
    bad = [k for k, fut in enumerate(futures) if not isinstance(fut, Future)]
    if bad:
        from ..validate import InputError

        for fut in futures:
            if isinstance(fut, Future):
                fut.cancel()
        raise InputError("executor", pool, f"executor={pool!r}: submit() returned {futures[bad[0]]!r} for the task of "
                         f"chunk {bad[0]}; an executor's submit() must return a concurrent.futures.Future")
    of = {id(fut): chunk for fut, chunk in zip(futures, chunks, strict=True)}
    try:
        for fut in as_completed(futures):
            record(check_rows(pool, cast(Sequence[tuple[int, Any]], of[id(fut)]), fut.result()))
    except BaseException:
        for fut in futures:
            fut.cancel()
        if flag is not None:
            flag[0] = 1
            wait(futures)
        raise
