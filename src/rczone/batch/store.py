"""Batch results on disk: one Parquet part per finished task, written atomically; one table.

Layout of the output folder::

    parts/<task>.parquet   one row per finished task (zone x method), complete or absent
    results.parquet        all rows, consolidated atomically at the end of every run
    summary.json, report.html, *.png   the summary (see rczone.batch.summary)

A task is *done* when its part exists, so a run that is killed loses at most the tasks in
flight, and the next run skips everything done (resume). Parts are written by the
coordinating process only, so no two writers ever touch the same file.
"""

from __future__ import annotations

import hashlib
import io
import re
from pathlib import Path

import pandas as pd

from rczone.report.io import write_bytes_atomic

RESULTS = "results.parquet"


def part_name(key: str) -> str:
    """A file name for a task key: readable, and unique through a short hash."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", key)[:80]
    return f"{safe}-{hashlib.sha1(key.encode()).hexdigest()[:10]}.parquet"


class ResultStore:
    """The results folder of one batch."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / "parts"
        self.parts.mkdir(parents=True, exist_ok=True)

    def done(self) -> set[str]:
        """Keys of the tasks whose result is on disk."""
        keys = set()
        for p in self.parts.glob("*.parquet"):
            try:
                keys.update(pd.read_parquet(p, columns=["key"])["key"])
            except Exception:  # a foreign or damaged file: not a result, recompute the task
                continue
        return keys

    def write(self, row: dict) -> Path:
        """Write one task's row atomically."""
        buf = io.BytesIO()
        pd.DataFrame([row]).to_parquet(buf, index=False)
        return write_bytes_atomic(self.parts / part_name(row["key"]), buf.getvalue())

    def table(self) -> pd.DataFrame:
        """Every stored row (one per task), in key order."""
        frames = []
        for p in sorted(self.parts.glob("*.parquet")):
            try:
                frames.append(pd.read_parquet(p))
            except Exception:
                continue
        if not frames:
            return pd.DataFrame(columns=["key", "zone", "method", "status", "error"])
        df = pd.concat(frames, ignore_index=True)
        return df.drop_duplicates("key", keep="last").sort_values("key").reset_index(drop=True)

    def consolidate(self) -> Path:
        """Write ``results.parquet`` (all rows) atomically and return its path."""
        buf = io.BytesIO()
        self.table().to_parquet(buf, index=False)
        return write_bytes_atomic(self.folder / RESULTS, buf.getvalue())
