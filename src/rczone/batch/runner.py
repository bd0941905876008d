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

import contextlib
import os
import signal
import sys
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, BrokenExecutor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path

from rczone.batch.manifest import Manifest, Task
from rczone.batch.store import ResultStore
from rczone.batch.summary import BatchRun, write_summary
from rczone.batch.task import run_tasks, run_unit
from rczone.errors import RczoneError
from rczone.files.atomic import immediate

CONNECT_TIMEOUT = 20.0
"""Seconds to wait for a Dask scheduler to answer."""
WORKER_TIMEOUT = 60.0
"""Seconds to wait for the first Dask worker to join the scheduler."""
UNITS_PER_WORKER = 16
"""Units of work a Dask run aims at per worker: the workers idle at the end for about half a unit
each, 1/32 of the run; fewer, larger units would cost less scheduling but more idle tail."""
MAX_UNIT = 64
"""Most zones in one unit of work (a unit lost with its worker is computed again whole)."""


@dataclass(frozen=True)
class Lost:
    """The tasks of one zone that the infrastructure could not run, and why."""

    tasks: list[Task]
    reason: str


def _by_zone(tasks: list[Task]) -> list[list[Task]]:
    groups: dict[str, list[Task]] = {}
    for t in tasks:
        groups.setdefault(t.zone, []).append(t)
    return list(groups.values())


def unit_size(zones: int, workers: int) -> int:
    """Zones per unit of work for ``zones`` zones on ``workers`` Dask workers.

    About :data:`UNITS_PER_WORKER` units per worker, at most :data:`MAX_UNIT` zones each: a
    zone-night costs tens of milliseconds of compute, a Dask task about a millisecond of
    scheduling and transfer (more across machines), so a unit of tens of zones keeps scheduling
    below 1 % while the idle tail stays near 3 % (docs/batch.md has the measurements).

    Parameters
    ----------
    zones : int
        Zones to calibrate.
    workers : int
        Worker processes of the cluster.

    Returns
    -------
    int
        At least 1.
    """
    return max(1, min(MAX_UNIT, zones // (max(1, workers) * UNITS_PER_WORKER)))


def _units(groups: list[list[Task]], size: int) -> list[list[list[Task]]]:
    return [groups[i : i + size] for i in range(0, len(groups), size)]


def _why(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _exit_without_teardown() -> None:
    """Make this worker process end, when it ends, without tearing its interpreter down.

    Run in the worker processes of the run's own ``LocalCluster`` (:func:`_connect`). A worker that
    has fitted zones holds numba's compiled kernels, SciPy and pandas; freeing all of that when the
    process exits took 1-4 s (longer than the nanny's 4 s grace on a loaded machine, which then kills
    it), and closing the cluster waited for it: 3-4 s of a 20-30 s run. At exit, after the worker has
    closed (its results sent), the process flushes its output and logs and leaves with
    :func:`os._exit`. Never done to the workers of a cluster the run did not start: they may run
    other people's work.
    """
    import atexit

    def leave() -> None:
        import logging
        import sys

        logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError, AttributeError):
                pass
        os._exit(0)

    atexit.register(leave)  # atexit runs last-registered first: this one, then nothing else


def _connect(scheduler: str | None, workers: int):
    """A Dask client (and the LocalCluster it owns, if any); connection problems are one line."""
    import dask
    from dask.distributed import Client, LocalCluster

    if not scheduler:
        # no dashboard, so no one reads the workers' statistical profiler, which samples every
        # thread's stack every 10 ms: 2 ms of CPU per zone-night (about 6 %) in each worker
        with dask.config.set({"distributed.worker.profile.enabled": False}):
            cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            )
        client = Client(cluster)
        client.run(_exit_without_teardown)  # closing the cluster then takes 0.1 s, not 3-4 s
        return client, cluster
    if "://" not in scheduler or not scheduler.split("://", 1)[1]:
        raise RczoneError(
            f"--scheduler {scheduler!r} is not a Dask scheduler address; expected e.g. tcp://host:8786"
        )
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT), None
    except (OSError, ValueError, TypeError) as exc:  # unreachable, refused, malformed
        raise RczoneError(
            f"cannot connect to the Dask scheduler {scheduler!r} ({_why(exc)}); check the address and"
            " that `dask scheduler` runs there"
        ) from None


def _close(client, cluster) -> None:
    client.close(timeout=10)
    if cluster is not None:
        cluster.close(timeout=10)


def _dask_results(
    groups: list[list[Task]],
    client,
    where: str,
    retries: int,
    worker_timeout: float,
    *,
    size: int | None,
    stats: dict,
) -> Iterator[list[dict] | Lost]:
    """Run the zones on the cluster in units of ``size`` zones (default :func:`unit_size`).

    A unit whose worker died (or ran out of memory) is split into its zones, each run on its own,
    so a zone that kills its worker takes only itself down. ``stats`` receives the number of
    workers and of units submitted.
    """
    from dask.distributed import KilledWorker, as_completed

    try:
        client.wait_for_workers(1, timeout=worker_timeout)
    except (TimeoutError, OSError) as exc:
        reason = f"no Dask worker joined {where} within {worker_timeout:g} s"
        reason += f" ({_why(exc)})" if not isinstance(exc, TimeoutError) else "; start workers"
        for g in groups:
            yield Lost(g, reason)
        return
    stats["workers"] = max(1, sum(client.nthreads().values()))  # task slots: threads of every worker
    units = _units(groups, size or unit_size(len(groups), stats["workers"]))
    index: dict = {}

    def submit(batch: list[list[list[Task]]]) -> list:
        # the scheduler reruns a task whose worker died (up to its allowed-failures), then
        # raises KilledWorker; retries= reruns a single zone after any other exception (a unit
        # of several zones is split instead: its other zones need not wait for a second failure)
        futures = client.map(
            run_unit, batch, run_zone=run_tasks, pure=False, retries=retries if len(batch[0]) == 1 else 0
        )
        index.update((f.key, u) for f, u in zip(futures, batch))
        stats["submitted"] = stats.get("submitted", 0) + len(batch)
        return futures

    running = as_completed(submit(units))
    for fut in running:
        unit = index.pop(fut.key)
        try:
            rows = fut.result()
        except (KilledWorker, MemoryError) as exc:
            if len(unit) > 1:  # one zone may have taken the unit down: each runs on its own
                running.update(submit([[zone] for zone in unit]))
                continue
            yield Lost(unit[0], _why(exc))
        except Exception as exc:  # run_unit returns every zone error: this is the cluster's
            yield Lost([t for zone in unit for t in zone], _why(exc))
        else:
            yield rows


#: Linux's prctl option that sends a signal to a process when its parent dies.
PR_SET_PDEATHSIG = 1

#: Seconds between two looks at the coordinating process where no parent-death signal exists.
PARENT_WATCH_S = 1.0


def _leave_ctrl_c_to_the_parent(parent: int) -> None:
    """A local worker process ignores Ctrl-C and ends with its coordinating process ``parent``.

    The terminal's Ctrl-C reaches every process of the group; a worker that raised it would print
    its own traceback beside the command's one line (the console script ends the workers,
    :func:`rczone.cli.run`; a caller of :func:`run_batch` gets ``KeyboardInterrupt`` and the
    workers stop after their zone). SIGTERM takes its default action (a forked worker inherits the
    command's handler). A coordinator killed outright (``kill -9``) runs no handler: the worker
    then ends by itself (:func:`_end_with_parent`).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _end_with_parent(parent)


def _gone(pid: int) -> bool:
    """Whether no process ``pid`` exists any more."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # exists, owned by another user (a reused number): not ours to judge
        return False
    return False


def _end_with_parent(parent: int) -> None:
    """End this process when the coordinating process ``parent`` ends.

    On Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` (proc(5)) has the kernel kill the worker when the
    process that started it exits; a daemon thread also looks every :data:`PARENT_WATCH_S` seconds
    whether ``parent`` still exists (other systems, or a worker started by a fork server). A
    coordinator that ended before either was in place is caught at once.
    """
    if sys.platform.startswith("linux") and os.getppid() == parent:
        with contextlib.suppress(OSError, AttributeError):
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if _gone(parent):
        os._exit(1)

    def watch() -> None:
        while not _gone(parent):
            time.sleep(PARENT_WATCH_S)
        os._exit(1)

    threading.Thread(target=watch, name="rczone-parent-watch", daemon=True).start()


def _executor() -> ProcessPoolExecutor:
    """A one-process executor whose process leaves Ctrl-C to this one and ends with it."""
    return ProcessPoolExecutor(
        max_workers=1, initializer=_leave_ctrl_c_to_the_parent, initargs=(os.getpid(),)
    )


def _process_results(groups: list[list[Task]], workers: int, retries: int) -> Iterator[list[dict] | Lost]:
    """Run the groups on ``workers`` single-process executors, one zone at a time each.

    A pool of N processes breaks as a whole when one of them dies, failing every queued
    zone; an executor per worker fails only its own zone, which is retried in a fresh one.
    """
    queue = deque(range(len(groups)))
    attempts: Counter[int] = Counter()
    idle: list[ProcessPoolExecutor] = []
    running: dict[Future, tuple[ProcessPoolExecutor, int]] = {}
    try:
        while queue or running:
            while queue and len(running) < workers:
                ex = idle.pop() if idle else _executor()
                i = queue.popleft()
                try:
                    fut = ex.submit(run_tasks, groups[i])
                except BrokenExecutor:  # an idle worker died between zones: a fresh one takes the zone
                    ex.shutdown(wait=False, cancel_futures=True)
                    ex = _executor()
                    fut = ex.submit(run_tasks, groups[i])
                running[fut] = (ex, i)
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for fut in finished:
                ex, i = running.pop(fut)
                try:
                    rows = fut.result()
                except Exception as exc:  # the worker died (killed, out of memory) or ran out of memory
                    ex.shutdown(wait=False, cancel_futures=True)
                    attempts[i] += 1
                    if attempts[i] <= retries:
                        queue.append(i)
                    else:
                        reason = "worker process died" if "BrokenProcessPool" in _why(exc) else _why(exc)
                        yield Lost(groups[i], f"{reason} (tried {attempts[i]} times)")
                else:
                    idle.append(ex)
                    yield rows
    finally:
        for ex, _ in running.values():
            ex.shutdown(wait=False, cancel_futures=True)
        for ex in idle:
            ex.shutdown(wait=True)


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
    *,
    on_start: Callable[[int, int], None] | None = None,
    retries: int = 1,
    worker_timeout: float = WORKER_TIMEOUT,
    unit: int | None = None,
    title: str = "rczone batch",
) -> BatchRun:
    """Calibrate every task of ``manifest`` not yet done in ``out``, then write the table and summary.

    Parameters
    ----------
    manifest : Manifest
    out : path
        Results folder (created); rerunning with the same folder resumes. One run at a time
        may write into it (a second is refused with :class:`~rczone.batch.store.FolderBusyError`).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:port``); default: local processes.
    workers : int, optional
        Local worker processes; default the number of cores.
    backend : {"auto", "dask", "processes"}
        Local execution engine; ``auto`` uses Dask when installed.
    on_result : callable, optional
        Called as ``on_result(row, done, to_do)`` after each result is stored (progress).
    on_start : callable, optional
        Called as ``on_start(resumed, to_do)`` once the stored results are known.
    retries : int
        How many times a task lost to the infrastructure is run again in this run.
    worker_timeout : float
        Seconds to wait for a Dask worker before giving up (every task then counts as lost).
    unit : int, optional
        Zones per unit of work on Dask (one scheduled task); default :func:`unit_size`. Local
        processes always run one zone at a time (a dying worker takes only its own zone).
    title : str
        Title of the summary report.

    Returns
    -------
    BatchRun

    Raises
    ------
    OutputError
        The folder cannot take the results (a file in its place, read-only, disk full); the
        results stored until then are complete and resumed by the next run.
    FolderBusyError
        Another run is writing into ``out``.
    """
    if backend not in ("auto", "dask", "processes"):
        raise RczoneError(f"backend must be auto, dask or processes, got {backend!r}")
    use_dask = scheduler is not None or backend == "dask" or (backend == "auto" and have_dask())
    if use_dask and not have_dask():
        raise RczoneError(
            "a Dask scheduler needs dask.distributed: pip install 'rczone[dask]'"
            " (or run without --scheduler to use local processes)"
        )
    workers = (os.cpu_count() or 1) if workers is None else workers
    if workers < 1:
        raise RczoneError(f"workers must be >= 1, got {workers}")
    if unit is not None and (isinstance(unit, bool) or not isinstance(unit, int) or unit < 1):
        raise RczoneError(f"zones per task must be a positive integer, got {unit!r}")
    store = ResultStore(out)
    t0 = time.perf_counter()
    with store.locked(), immediate():  # results stored as they arrive, whatever the caller stages
        fingerprints = {t.key: t.fingerprint for t in manifest.tasks}
        store.clear_stream()  # segments of an interrupted run: its rows are in the parts
        done = store.done(manifest.tasks, fingerprints)
        todo = [t for t in manifest.tasks if t.key not in done]
        computed = failed = 0
        compute = cpu = 0.0
        lost: dict[str, str] = {}
        connection = _connect(scheduler, workers) if todo and use_dask else None
        try:
            if on_start:
                on_start(len(manifest.tasks) - len(todo), len(todo))
            groups = _by_zone(todo)
            stats = {"workers": workers, "submitted": 0 if connection else len(groups)}
            outcomes = (
                _dask_results(
                    groups,
                    connection[0],
                    scheduler or "the local cluster",
                    retries,
                    worker_timeout,
                    size=unit,
                    stats=stats,
                )
                if connection
                else _process_results(groups, workers, retries)
            )
            for outcome in outcomes:
                if isinstance(outcome, Lost):
                    lost.update((t.key, outcome.reason) for t in outcome.tasks)
                    continue
                stored = [{**row, "fingerprint": fingerprints[row["key"]]} for row in outcome]
                store.write_all(stored)
                store.stream(stored)
                for row in outcome:
                    computed += 1
                    failed += row["status"] != "ok"
                    compute += float(row.get("seconds") or 0.0)
                    cpu += float(row.get("cpu_seconds") or 0.0)
                    if on_result:
                        on_result(row, computed + len(lost), len(todo))
        finally:
            if connection:
                _close(*connection)
        table = store.table(manifest.tasks, fingerprints)
        path = store.consolidate(table)
        store.clear_stream()  # results.parquet holds every row now
        totals = write_summary(table, store.folder, title=title)
    return BatchRun(
        total=len(manifest.tasks),
        skipped=len(manifest.tasks) - len(todo),
        computed=computed,
        failed=failed,
        lost=len(lost),
        lost_reasons=tuple(dict.fromkeys(lost.values())),
        seconds=time.perf_counter() - t0,
        results=path,
        folder=store.folder,
        totals=totals,
        table=table,
        workers=stats["workers"] if todo else workers,
        compute_seconds=compute,
        cpu_seconds=cpu,
        submitted=stats["submitted"] if todo else 0,
    )
