"""Batch calibration of many zones: manifest, tasks, resumable results, summary.

``rczone fit-many MANIFEST`` and :func:`run_batch` calibrate every zone of a manifest
(:mod:`rczone.batch.manifest`) on local processes or a Dask cluster
(:mod:`rczone.batch.runner`), one task per zone and method (:mod:`rczone.batch.task`),
storing each result atomically as it arrives so that a rerun resumes
(:mod:`rczone.batch.store`), and write a summary (:mod:`rczone.batch.summary`).
"""

from rczone.batch.manifest import Manifest, Task, parse_manifest, read_manifest
from rczone.batch.runner import run_batch
from rczone.batch.store import ResultStore
from rczone.batch.summary import BatchRun, summarize, write_summary
from rczone.batch.task import run_task

__all__ = [
    "BatchRun",
    "Manifest",
    "ResultStore",
    "Task",
    "parse_manifest",
    "read_manifest",
    "run_batch",
    "run_task",
    "summarize",
    "write_summary",
]
