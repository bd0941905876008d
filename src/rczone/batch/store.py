"""Batch results on disk: one small file per finished task, written atomically; one table.

Layout of the output folder::

    parts/<task>.json      one row per finished task (zone x method), complete or absent
    results.parquet        the rows of the manifest's tasks, consolidated atomically
    summary.json, report.html, *.png   the summary (see rczone.batch.summary)
    .lock                  held by the run writing into the folder

A task is *done* when its part exists and carries the task's fingerprint (a hash of every
setting and of the files the task reads, :attr:`~rczone.batch.manifest.Task.fingerprint`),
so a run that is killed loses at most the tasks in flight, the next run skips everything
done (resume), and a changed setting or file is computed anew. Parts are written by the
coordinating process only, and one run at a time holds the folder (:meth:`ResultStore.locked`),
so no two writers ever touch the same file and the table always agrees with the summary. A
part is one JSON object (floats round-trip exactly, NaN included): a few tens of microseconds
to write and read, where a one-row Parquet file costs milliseconds, which at thousands of
tasks is time taken from the workers. A part that is damaged, foreign, or holds values of the
wrong type is not a result: its task is computed again and the part replaced.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import io
import json
import os
import re
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from rczone.atomic import ensure_folder, output_error, write_bytes_atomic
from rczone.batch.manifest import Task
from rczone.errors import RczoneError

RESULTS = "results.parquet"
LOCK = ".lock"
_HELD: set[str] = set()  # folders locked by this process (the lock itself is per process)
_HELD_GUARD = threading.Lock()

#: Columns of a row and the JSON types they hold (others hold numbers or null).
TEXT = ("key", "zone", "method", "model", "source", "status", "error", "fingerprint", "flags", "engine")
FLAGS = ("converged", "trustworthy")
COUNTS = ("n_evals",)
STATUSES = ("ok", "failed")


class FolderBusyError(RczoneError, RuntimeError):
    """Another run is writing into the same results folder."""


def part_name(key: str) -> str:
    """A file name for a task key: readable, and unique through a short hash."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", key)[:80]
    return f"{safe}-{hashlib.sha1(key.encode()).hexdigest()[:10]}.json"


def _plain(v: object) -> object:
    """NumPy scalars as Python numbers (JSON knows only those)."""
    if isinstance(v, np.generic):
        return v.item()
    return v


def _is_number(v: object) -> bool:
    return v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))


def valid_row(row: object) -> bool:
    """True if ``row`` has the shape of a result row (the types a task writes, column by column)."""
    if not isinstance(row, dict) or row.get("status") not in STATUSES:
        return False
    for k, v in row.items():
        if k in TEXT or k.endswith("_verdict"):
            ok = isinstance(v, str) or (v is None and k not in ("key", "zone", "method", "fingerprint"))
        elif k in FLAGS or k.endswith("_at_bound"):
            ok = isinstance(v, bool) or v is None
        elif k in COUNTS:
            ok = v is None or (isinstance(v, int) and not isinstance(v, bool))
        else:
            ok = _is_number(v)
        if not ok:
            return False
    return all(isinstance(row.get(k), str) for k in ("key", "zone", "method", "fingerprint"))


class ResultStore:
    """The results folder of one batch.

    Rows already on disk are read once; rows written since are kept in memory, so
    consolidating a run of thousands of tasks reads nothing back.

    Raises
    ------
    OutputError
        If the folder cannot be created (a file in its place, read-only, ...).
    """

    def __init__(self, folder: str | os.PathLike) -> None:
        self.folder = ensure_folder(folder)
        self.parts = ensure_folder(self.folder / "parts")
        self._rows: dict[str, dict] | None = None

    @contextlib.contextmanager
    def locked(self) -> Iterator[ResultStore]:
        """Hold the folder for one run; a second run into it is refused with one line."""
        path = self.folder / LOCK
        here = os.path.realpath(self.folder)
        with _HELD_GUARD:  # a POSIX lock does not exclude threads of one process: this does
            if here in _HELD:
                raise FolderBusyError(
                    f"results folder {os.fspath(self.folder)!r} is in use by another run in this process"
                )
            _HELD.add(here)
        try:
            yield from self._lock_file(path)
        finally:
            with _HELD_GUARD:
                _HELD.discard(here)

    def _lock_file(self, path: Path) -> Iterator[ResultStore]:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise output_error(path, exc) from None
        try:
            try:
                # a POSIX record lock belongs to this process: forked workers do not hold it, and it
                # ends with the process however it ends
                fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise output_error(path, exc, "lock") from None
                holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "?"
                raise FolderBusyError(
                    f"results folder {os.fspath(self.folder)!r} is in use by another run (pid {holder});"
                    " wait for it to finish, or give another --out"
                ) from None
            os.ftruncate(fd, 0)
            os.pwrite(fd, str(os.getpid()).encode("ascii"), 0)
            self._rows = None  # another run may have written since: read the parts again
            yield self
        finally:
            os.close(fd)  # releases the lock

    def _load(self) -> dict[str, dict]:
        if self._rows is None:
            rows: dict[str, dict] = {}
            for p in sorted(self.parts.glob("*.json")):
                try:
                    row = json.loads(p.read_text(encoding="utf-8"))
                except (OSError, ValueError, RecursionError):  # a foreign or damaged file: not a result
                    continue
                if valid_row(row) and p.name == part_name(row["key"]):
                    rows[row["key"]] = row
            self._rows = rows
        return self._rows

    def done(self, tasks: Iterable[Task] | None = None) -> set[str]:
        """Keys of the tasks whose result is on disk (of ``tasks``: with the same fingerprint)."""
        rows = self._load()
        if tasks is None:
            return set(rows)
        return {t.key for t in tasks if t.key in rows and rows[t.key].get("fingerprint") == t.fingerprint}

    def write(self, row: dict) -> Path:
        """Write one task's row atomically (:class:`~rczone.errors.OutputError` if it cannot be)."""
        row = {k: _plain(v) for k, v in row.items()}
        data = json.dumps(row, allow_nan=True).encode("utf-8")
        path = write_bytes_atomic(self.parts / part_name(row["key"]), data)
        self._load()[row["key"]] = row
        return path

    def table(self, tasks: Iterable[Task] | None = None) -> pd.DataFrame:
        """Stored rows (one per task), in key order; of ``tasks``: those done with their fingerprint."""
        rows = self._load()
        keys = sorted(rows) if tasks is None else sorted(self.done(tasks))
        if not keys:
            return pd.DataFrame(columns=["key", "zone", "method", "status", "error"])
        df = pd.DataFrame([rows[k] for k in keys])
        for c in df.columns:  # JSON null in a number column: NaN, so every column has one type
            if c not in TEXT and df[c].dtype == object and all(_is_number(v) for v in df[c]):
                df[c] = df[c].astype(float)
        return df

    def consolidate(self, table: pd.DataFrame | None = None) -> Path:
        """Write ``results.parquet`` (``table``, default all rows) atomically and return its path."""
        buf = io.BytesIO()
        (self.table() if table is None else table).to_parquet(buf, index=False)
        return write_bytes_atomic(self.folder / RESULTS, buf.getvalue())
