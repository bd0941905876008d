"""One batch task: load a zone's data, calibrate one method, diagnose; always return a row.

Runs in a worker process. Whatever goes wrong in one zone (bad data, a failed fit, a bug)
becomes a row with ``status = "failed"`` and the error, so the batch goes on. Running out of
memory is not the zone's own error (the same zone may fit on a machine with more memory, or
when fewer zones run beside it): :class:`MemoryError` propagates, and the runner retries the
task instead of storing a failure.
"""

from __future__ import annotations

import math
import time
import traceback
from collections.abc import Callable
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from rczone.batch.manifest import Task, file_digest
from rczone.errors import RczoneError
from rczone.models import ZoneModel


def task_model(task: Task) -> ZoneModel:
    """The task's model: a built-in name or a model file (already resolved by the manifest).

    Loaded once per worker process and model (a model file again when its contents change), so
    the zones of a worker share one frozen structure and the caches keyed by it.
    """
    return _model(task.model, file_digest(task.model) if Path(task.model).is_absolute() else "")


@lru_cache(maxsize=16)
def _model(spec: str, digest: str) -> ZoneModel:  # digest: an edited model file is loaded again
    from rczone.models import load_model

    return load_model(spec)


def run_tasks(tasks: list[Task]) -> list[dict]:
    """Run the tasks of one zone (its methods), loading the data and diagnosing once."""
    cache: dict = {}
    return [run_task(t, cache) for t in tasks]


def run_unit(zones: list[list[Task]], run_zone: Callable[[list[Task]], list[dict]] = run_tasks) -> list[dict]:
    """Run one unit of work: several zones, one after the other, in one worker.

    A unit is what a Dask cluster schedules (:func:`rczone.batch.runner.run_batch` sizes it so
    scheduling costs a few percent at most); its zones share the worker's loaded model.

    Parameters
    ----------
    zones : list of list of Task
        The tasks of each zone (its methods).
    run_zone : callable
        Runs one zone's tasks and returns their rows (:func:`run_tasks`).

    Returns
    -------
    list of dict
        The rows of every zone, in order.
    """
    return [row for tasks in zones for row in run_zone(tasks)]


def _drift_columns(model: ZoneModel, data) -> dict:
    """``drift`` (None: not tested), when it started and the tests that say so (:func:`~rczone.calibration.drift.record_drift`)."""
    from rczone.calibration.drift import record_drift

    try:
        check = record_drift(model, data)
    except (RczoneError, np.linalg.LinAlgError) as exc:  # the fit stands; only the test could not run
        return {"drift": None, "drift_tests": f"not tested: {type(exc).__name__}: {exc}"}
    tested = check is not None and bool(check.traces)
    return {
        "drift": check.drifted if tested else None,
        "drift_since_s": check.since_s if tested else None,
        "drift_detected_s": check.detected_s if tested else None,
        "drift_tests": "; ".join(sorted({f"{s.test} of {s.output}" for s in check.signals}))
        if tested
        else None,
    }


def run_task(task: Task, cache: dict | None = None) -> dict:
    """Calibrate ``task`` and return its result row (never raises for a zone's own problems).

    ``cache`` (a dict) shares the zone's data and verdicts between the methods of one zone.
    """
    cache = {} if cache is None else cache
    t0, cpu0 = time.perf_counter(), time.process_time()
    row: dict = {
        "key": task.key,
        "zone": task.zone,
        "method": task.method,
        "model": task.model,
        "source": task.source.label,
        "status": "ok",
        "error": "",
    }
    try:
        from rczone.calibration.dataset import prepare
        from rczone.workflow.checks import fit_and_check

        zm = task_model(task)
        net = zm.network
        if "frame" not in cache:  # read here, where the task runs: a task carries paths, not frames
            cache["frame"] = task.source.frame(zm)
        frame = cache["frame"]
        # the row holds the estimates and the open-loop errors: the analyses a reader of one fit looks
        # at (residual whiteness, band calibration, baselines, plausibility) are not made
        settings = replace(task.settings, checks=False)
        key = ("data", tuple(sorted((settings.constants or {}).items())))
        if key not in cache:  # the zone's methods fit the same data set
            cache[key] = prepare(zm, frame, settings.constants or None)
        cal = fit_and_check(zm, cache[key], settings, label=task.source.label, analyses=False)
        r = cal.result
        row.update(
            open_loop_rmse_K=cal.open_loop.rmse_K,
            open_loop_max_K=cal.open_loop.max_abs_K,
            fit_rmse_K=r.rmse_K,
            objective_value=r.objective_value,
            llf=r.llf,
            engine=r.engine,
            converged=bool(r.converged),
            trustworthy=bool(r.trustworthy),
            n_evals=int(r.n_evals),
            flags="; ".join(r.flags),
        )
        if r.posterior is not None:  # a sampling method: how long it sampled, and whether it converged
            p = r.posterior
            row.update(draws=p.n_draws, tune=p.tune, chains=p.n_chains, divergences=p.divergences)
            row.update(max_rhat=float(p.rhat.max()), min_ess_bulk=float(p.ess_bulk.min()))
        row.update(_drift_columns(cal.model, cache[key].dataset))
        for n, e in r.parameters.items():
            row[n] = e.value
            row[f"{n}_se"] = e.std_error
            row[f"{n}_construction"] = e.construction if math.isfinite(e.construction) else None
            row[f"{n}_at_bound"] = bool(e.at_bound)
        if task.diagnose:
            from rczone.diagnostics import diagnose

            rc = tuple(n for n in r.names if n in net.parameters)
            if rc and ("diagnose", rc) not in cache:
                # at the fitted values: an operating point consistent with this zone's data
                d = diagnose(cal.model, frame, free=list(rc), constants=cal.model.provenance.get("constants"))
                cache["diagnose", rc] = {n: v.verdict for n, v in d.parameters.items()}
            for n, verdict in cache.get(("diagnose", rc), {}).items():
                row[f"{n}_verdict"] = verdict
    except MemoryError:
        raise  # not the zone's own error: the runner retries it
    except RczoneError as exc:
        row.update(status="failed", error=f"{type(exc).__name__}: {exc}")
    except Exception as exc:  # a bug or numerical failure in one zone must not stop the batch
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" ({tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
        row.update(status="failed", error=f"{type(exc).__name__}: {exc}{where}")
    row["seconds"] = time.perf_counter() - t0
    row["cpu_seconds"] = time.process_time() - cpu0  # on a loaded machine, what the zone itself cost
    return row
