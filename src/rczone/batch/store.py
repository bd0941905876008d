"""Batch results on disk: one small file per finished task, written atomically; one table.

Layout of the output folder::

    parts/<task>.json      one row per finished task (zone x method), complete or absent
    results.parquet        the rows of the manifest's tasks, consolidated atomically
    stream/*.parquet       the rows of a run in progress, in segments of a few hundred rows
    summary.json, report.html, *.png   the summary (see rczone.batch.summary)
    .lock                  held by the run writing into the folder

Nothing is written outside the folder: every file is written by
:func:`rczone.files.atomic.write_bytes_in`, which follows no symbolic link below the folder (a link
planted at a part's or the table's name is replaced, a link in place of ``parts`` refused), and
the lock file is opened with ``O_NOFOLLOW`` and must be a regular file with one name (a link
planted there is refused with one line, its target never opened). The lock is the portable one
of the ``filelock`` package (``flock`` on POSIX, ``LockFileEx`` on Windows), taken on the
descriptor opened so.

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
import hashlib
import io
import json
import os
import re
import stat
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from rczone.batch.manifest import Task
from rczone.errors import RczoneError
from rczone.files.atomic import (
    NOFOLLOW,
    ensure_folder,
    ensure_folder_in,
    open_in,
    output_error,
    write_bytes_in,
)

RESULTS = "results.parquet"
LOCK = ".lock"
_HELD: set[str] = set()  # folders locked by this process (the lock itself is per process)
_HELD_GUARD = threading.Lock()
_LOCK_FDS: set[int] = set()  # descriptors of the lock files held, closed in forked children
STREAM = "stream"
STREAM_ROWS = 256
"""Rows gathered into one segment of the Parquet stream (:meth:`ResultStore.stream`)."""
STREAM_SECONDS = 10.0
"""Longest wait before gathered rows are written to the stream, s."""
WRITERS = 8
"""Threads writing the parts of one unit of work (:meth:`ResultStore.write_all`)."""
MAX_PART_BYTES = 1 << 20
"""Largest part file read back (bytes); a part is a few kilobytes, a larger file is not a result."""


def _close_lock_fds_in_child() -> None:
    # flock belongs to the open file: a forked worker would hold the folder after its coordinator
    # died. Its copy of the descriptor is closed at once (the coordinator's lock stays).
    for fd in tuple(_LOCK_FDS):
        with contextlib.suppress(OSError):
            os.close(fd)
    _LOCK_FDS.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_close_lock_fds_in_child)

#: Columns of a row and the JSON types they hold (others hold numbers or null).
TEXT = (
    *("key", "zone", "method", "model", "source", "status", "error", "fingerprint", "flags", "engine"),
    "drift_tests",
)
FLAGS = ("converged", "trustworthy", "drift")
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


def _holder(fd: int) -> str:
    """The pid written in a held lock file ("?" where the holder's lock hides it, as on Windows)."""
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        text = os.read(fd, 32).decode("ascii", "replace").strip()
    except OSError:
        return "?"
    return text if text.isdigit() else "?"


def _read_part(path: Path) -> str:
    """A part's text: a regular file of at most MAX_PART_BYTES, never a pipe or a link's target."""
    fd = os.open(path, os.O_RDONLY | NOFOLLOW | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_PART_BYTES:
            raise ValueError("not a part")
        with os.fdopen(os.dup(fd), "rb") as fh:
            return fh.read(MAX_PART_BYTES + 1).decode("utf-8")
    finally:
        os.close(fd)


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
        self.parts = ensure_folder_in(self.folder, "parts")
        self._rows: dict[str, dict] | None = None
        self._pending: list[dict] = []  # rows not yet in a stream segment
        self._segments = 0
        self._flushed = time.monotonic()

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
        from filelock import lock_descriptor

        fd = open_in(self.folder, LOCK)  # O_NOFOLLOW, a regular file with one name: never a link's target
        _LOCK_FDS.add(fd)
        try:
            try:
                # whole-file lock on this descriptor: it ends with the process however it ends
                held = lock_descriptor(fd, blocking=False)
            except OSError as exc:
                raise output_error(path, exc, "lock") from None
            if not held:
                raise FolderBusyError(
                    f"results folder {os.fspath(self.folder)!r} is in use by another run (pid {_holder(fd)});"
                    " wait for it to finish, or give another --out"
                )
            os.ftruncate(fd, 0)
            os.lseek(fd, 0, os.SEEK_SET)
            os.write(fd, str(os.getpid()).encode("ascii"))
            self._rows = None  # another run may have written since: read the parts again
            yield self
        finally:
            _LOCK_FDS.discard(fd)
            os.close(fd)  # releases the lock

    def _load(self) -> dict[str, dict]:
        if self._rows is None:
            rows: dict[str, dict] = {}
            for p in sorted(self.parts.glob("*.json")):
                try:
                    row = json.loads(_read_part(p))
                except (OSError, ValueError, RecursionError):  # a foreign or damaged file: not a result
                    continue
                if valid_row(row) and p.name == part_name(row["key"]):
                    rows[row["key"]] = row
            self._rows = rows
        return self._rows

    def done(
        self, tasks: Iterable[Task] | None = None, fingerprints: Mapping[str, str] | None = None
    ) -> set[str]:
        """Keys of the tasks whose result is on disk (of ``tasks``: with the same fingerprint).

        ``fingerprints`` (task key to :attr:`~rczone.batch.manifest.Task.fingerprint`) saves
        computing them again: each hashes the task's settings and files.
        """
        rows = self._load()
        if tasks is None:
            return set(rows)
        fp = fingerprints if fingerprints is not None else {t.key: t.fingerprint for t in tasks}
        return {t.key for t in tasks if t.key in rows and rows[t.key].get("fingerprint") == fp[t.key]}

    def write(self, row: dict) -> Path:
        """Write one task's row atomically (:class:`~rczone.errors.OutputError` if it cannot be)."""
        path, row = self._write_part(row)
        self._load()[row["key"]] = row
        return path

    def write_all(self, rows: list[dict]) -> list[Path]:
        """Write the parts of several rows (a unit of work's), each atomically, at once.

        The parts are written by :data:`WRITERS` threads: every part is still synced to the disk
        before its rename, but the file system commits concurrent syncs together (on ext4, eight
        writers made a synced part cost 0.6 ms instead of 8 ms), so storing results keeps pace
        with many workers. The first error (:class:`~rczone.errors.OutputError`) is raised once
        every write has ended; the parts written are complete.
        """
        if len(rows) < 2:
            return [self.write(r) for r in rows]
        with ThreadPoolExecutor(min(WRITERS, len(rows)), thread_name_prefix="rczone-part") as pool:
            futures = [pool.submit(self._write_part, r) for r in rows]
        written = [f for f in futures if f.exception() is None]
        for f in written:
            row = f.result()[1]
            self._load()[row["key"]] = row
        for f in futures:
            if f.exception() is not None:
                raise f.exception()
        return [f.result()[0] for f in written]

    def _write_part(self, row: dict) -> tuple[Path, dict]:
        row = {k: _plain(v) for k, v in row.items()}
        data = json.dumps(row, allow_nan=True).encode("utf-8")
        return write_bytes_in(self.folder, f"parts/{part_name(row['key'])}", data), row

    def table(
        self, tasks: Iterable[Task] | None = None, fingerprints: Mapping[str, str] | None = None
    ) -> pd.DataFrame:
        """Stored rows (one per task), in key order; of ``tasks``: those done with their fingerprint."""
        rows = self._load()
        keys = sorted(rows) if tasks is None else sorted(self.done(tasks, fingerprints))
        if not keys:
            return pd.DataFrame(columns=["key", "zone", "method", "status", "error"])
        return _frame([rows[k] for k in keys])

    def consolidate(self, table: pd.DataFrame | None = None) -> Path:
        """Write ``results.parquet`` (``table``, default all rows) atomically and return its path."""
        return write_bytes_in(self.folder, RESULTS, _parquet(self.table() if table is None else table))

    def stream(self, rows: list[dict], *, flush: bool = False) -> Path | None:
        """Add rows to the run's Parquet stream, ``stream/*.parquet``, readable while the run goes on.

        Rows are gathered and written as one segment (atomically) once :data:`STREAM_ROWS` rows
        or :data:`STREAM_SECONDS` have accumulated, so a segment costs one synced write per
        hundreds of rows; ``pandas.read_parquet("<out>/stream")`` reads every segment. The parts
        remain the record a rerun resumes from; :meth:`clear_stream` removes the segments once
        ``results.parquet`` holds every row.

        Parameters
        ----------
        rows : list of dict
            Rows just stored (:meth:`write_all`).
        flush : bool
            Write the gathered rows now.

        Returns
        -------
        Path or None
            The segment written, if one was.
        """
        self._pending.extend(rows)
        due = len(self._pending) >= STREAM_ROWS or time.monotonic() - self._flushed >= STREAM_SECONDS
        if not self._pending or not (flush or due):
            return None
        self._segments += 1
        name = f"{STREAM}/{os.getpid()}-{self._segments:06d}.parquet"
        path = write_bytes_in(self.folder, name, _parquet(_frame(self._pending)))
        self._pending, self._flushed = [], time.monotonic()
        return path

    def clear_stream(self) -> None:
        """Remove the stream's segments (a link in place of ``stream/`` is refused, never followed)."""
        folder = ensure_folder_in(self.folder, STREAM)
        for p in folder.glob("*.parquet"):
            with contextlib.suppress(FileNotFoundError):
                p.unlink()  # removes a link planted there, never what it points to
        self._pending, self._segments = [], 0


def _frame(rows: list[dict]) -> pd.DataFrame:
    """Rows as a table; JSON null in a number column becomes NaN, so every column has one type."""
    df = pd.DataFrame(rows)
    for c in df.columns:
        if c not in TEXT and df[c].dtype == object and all(_is_number(v) for v in df[c]):
            df[c] = df[c].astype(float)
    return df


def _parquet(df: pd.DataFrame) -> bytes:
    buf = io.BytesIO()
    df.to_parquet(buf, index=False)
    return buf.getvalue()
