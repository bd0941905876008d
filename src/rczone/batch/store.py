"""Batch results on disk: one small file per finished task, written atomically; one table.

Layout of the output folder::

    parts/<task>.json      one row per finished task (zone x method), complete or absent
    results.parquet        all rows, consolidated atomically at the end of every run
    summary.json, report.html, *.png   the summary (see rczone.batch.summary)

A task is *done* when its part exists, so a run that is killed loses at most the tasks in
flight, and the next run skips everything done (resume). Parts are written by the
coordinating process only, so no two writers ever touch the same file. A part is one JSON
object (floats round-trip exactly, NaN included): a few tens of microseconds to write and
read, where a one-row Parquet file costs milliseconds, which at thousands of tasks is time
taken from the workers. The table users read is ``results.parquet``.
"""

from __future__ import annotations

import hashlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

from rczone.atomic import write_bytes_atomic

RESULTS = "results.parquet"


def part_name(key: str) -> str:
    """A file name for a task key: readable, and unique through a short hash."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", key)[:80]
    return f"{safe}-{hashlib.sha1(key.encode()).hexdigest()[:10]}.json"


def _plain(v: object) -> object:
    """NumPy scalars as Python numbers (JSON knows only those)."""
    if isinstance(v, np.generic):
        return v.item()
    return v


class ResultStore:
    """The results folder of one batch.

    Rows already on disk are read once (:meth:`done`); rows written since are kept in
    memory, so consolidating a run of thousands of tasks reads nothing back.
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / "parts"
        self.parts.mkdir(parents=True, exist_ok=True)
        self._rows: dict[str, dict] | None = None

    def _load(self) -> dict[str, dict]:
        if self._rows is None:
            rows: dict[str, dict] = {}
            for p in sorted(self.parts.glob("*.json")):
                try:
                    row = json.loads(p.read_text(encoding="utf-8"))
                except (OSError, ValueError):  # a foreign or damaged file: not a result
                    continue
                if isinstance(row, dict) and isinstance(row.get("key"), str):
                    rows[row["key"]] = row
            self._rows = rows
        return self._rows

    def done(self) -> set[str]:
        """Keys of the tasks whose result is on disk."""
        return set(self._load())

    def write(self, row: dict) -> Path:
        """Write one task's row atomically."""
        row = {k: _plain(v) for k, v in row.items()}
        data = json.dumps(row, allow_nan=True).encode("utf-8")
        path = write_bytes_atomic(self.parts / part_name(row["key"]), data)
        self._load()[row["key"]] = row
        return path

    def table(self) -> pd.DataFrame:
        """Every stored row (one per task), in key order."""
        rows = self._load()
        if not rows:
            return pd.DataFrame(columns=["key", "zone", "method", "status", "error"])
        return pd.DataFrame([rows[k] for k in sorted(rows)])

    def consolidate(self) -> Path:
        """Write ``results.parquet`` (all rows) atomically and return its path."""
        buf = io.BytesIO()
        self.table().to_parquet(buf, index=False)
        return write_bytes_atomic(self.folder / RESULTS, buf.getvalue())
