"""Run a batch: every task of a manifest on local processes or a Dask cluster, resumably.

The coordinating process submits the tasks not yet done, writes each result as it arrives
(:class:`~rczone.batch.store.ResultStore`), and consolidates the table at the end. The same
code path serves a laptop (a ``dask.distributed.LocalCluster`` with one single-threaded
worker process per core, or ``concurrent.futures`` processes when Dask is not installed) and
a cluster (``scheduler="tcp://host:port"``).

References
----------
.. [1] Dask Development Team, *Dask: Library for dynamic task scheduling*, 2016,
   https://dask.org (``distributed.Client.map``, ``as_completed``).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as futures_completed
from dataclasses import dataclass
from pathlib import Path

from rczone.batch.manifest import Manifest, Task
from rczone.batch.store import ResultStore
from rczone.batch.task import run_tasks
from rczone.errors import RczoneError


@dataclass(frozen=True)
class BatchRun:
    """What one run did.

    Attributes
    ----------
    total : int
        Tasks in the manifest.
    skipped : int
        Already done by an earlier run (resumed).
    computed : int
        Finished in this run (ok or failed).
    failed : int
        Of the computed, how many failed.
    seconds : float
        Wall time of this run.
    results : Path
        The consolidated table.
    """

    total: int
    skipped: int
    computed: int
    failed: int
    seconds: float
    results: Path


def _by_zone(tasks: list[Task]) -> list[list[Task]]:
    groups: dict[str, list[Task]] = {}
    for t in tasks:
        groups.setdefault(t.zone, []).append(t)
    return list(groups.values())


def _dask_results(tasks: list[Task], scheduler: str | None, workers: int) -> Iterator[dict]:
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler:
        client, cluster = Client(scheduler), None
    else:
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    try:
        groups = _by_zone(tasks)
        futures = client.map(run_tasks, groups, pure=False)
        index = {f.key: g for f, g in zip(futures, groups)}
        for fut in as_completed(futures):
            try:
                yield from fut.result()
            except Exception as exc:  # the worker itself died (e.g. out of memory)
                for t in index[fut.key]:
                    yield _failed(t, f"{type(exc).__name__}: {exc}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _process_results(tasks: list[Task], workers: int) -> Iterator[dict]:
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futs = {pool.submit(run_tasks, g): g for g in _by_zone(tasks)}
        for fut in futures_completed(futs):
            try:
                yield from fut.result()
            except Exception as exc:  # the worker process died
                for t in futs[fut]:
                    yield _failed(t, f"{type(exc).__name__}: {exc}")


def _failed(task: Task, error: str) -> dict:
    return {
        "key": task.key,
        "zone": task.zone,
        "method": task.method,
        "model": task.model,
        "status": "failed",
        "error": error,
        "seconds": float("nan"),
    }


def have_dask() -> bool:
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        return False
    return True


def run_batch(
    manifest: Manifest,
    out: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    backend: str = "auto",
    on_result: Callable[[dict, int, int], None] | None = None,
) -> BatchRun:
    """Calibrate every task of ``manifest`` not yet done in ``out``.

    Parameters
    ----------
    manifest : Manifest
    out : path
        Results folder (created); rerunning with the same folder resumes.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:port``); default: local processes.
    workers : int, optional
        Local worker processes; default the number of cores.
    backend : {"auto", "dask", "processes"}
        Local execution engine; ``auto`` uses Dask when installed.
    on_result : callable, optional
        Called as ``on_result(row, done, to_do)`` after each result is stored (progress).

    Returns
    -------
    BatchRun
    """
    if backend not in ("auto", "dask", "processes"):
        raise RczoneError(f"backend must be auto, dask or processes, got {backend!r}")
    use_dask = scheduler is not None or backend == "dask" or (backend == "auto" and have_dask())
    if use_dask and not have_dask():
        raise RczoneError(
            "a Dask scheduler needs dask.distributed: pip install 'rczone[dask]'"
            " (or run without --scheduler to use local processes)"
        )
    workers = workers or os.cpu_count() or 1
    if workers < 1:
        raise RczoneError(f"workers must be >= 1, got {workers}")
    store = ResultStore(out)
    t0 = time.perf_counter()
    done = store.done()
    todo = [t for t in manifest.tasks if t.key not in done]
    computed = failed = 0
    if todo:
        results: Iterable[dict] = (
            _dask_results(todo, scheduler, workers) if use_dask else _process_results(todo, workers)
        )
        for row in results:
            store.write(row)
            computed += 1
            failed += row["status"] != "ok"
            if on_result:
                on_result(row, computed, len(todo))
    path = store.consolidate()
    return BatchRun(
        len(manifest.tasks), len(manifest.tasks) - len(todo), computed, failed, time.perf_counter() - t0, path
    )
