"""Atomic writes: a result file is either complete or absent, never half written.

Every result rczone writes (JSON, Parquet parts, reports, saved models, schedules) goes through
these functions, so an interrupted run never leaves a truncated file where a reader expects a
result. A place that cannot take the result (a folder where a file is expected, a file where a
folder is expected, a read-only folder, a full disk) raises :class:`~rczone.errors.OutputError`
with one line naming the path, and leaves nothing behind. This module imports nothing of rczone
but its errors; every layer may use it.
"""

from __future__ import annotations

import errno
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from rczone.errors import OutputError

_REASONS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "the file system is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.ENAMETOOLONG: "the name is too long",
}


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def output_error(path: str | os.PathLike, exc: OSError, what: str = "write") -> OutputError:
    """One line saying why ``path`` cannot take a result, from the operating system's error."""
    reason = _REASONS.get(exc.errno or 0) or (exc.strerror or type(exc).__name__).lower()
    return OutputError(f"cannot {what} {os.fspath(path)!r}: {reason}")


def ensure_folder(path: str | os.PathLike) -> Path:
    """Create the folder ``path`` (and its parents) for results, or raise :class:`OutputError`.

    An existing file at ``path``, or at one of its parents, is an error naming it.
    """
    path = Path(path)
    for p in (path, *path.parents):
        if p.exists() and not p.is_dir():
            raise OutputError(
                f"cannot write results into {os.fspath(path)!r}: {os.fspath(p)!r} is a file, not a folder;"
                " give a folder name"
            )
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise output_error(path, exc, "create the folder") from None
    return path


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename.

    The file is made readable by all (``0644``) like a file written by ``open``, not private
    (``0600``) like the temporary file.

    Raises
    ------
    OutputError
        If ``path`` is a folder, its folder cannot be created or written, or the disk is full;
        no file (temporary or partial) is left behind.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {os.fspath(path)!r}: it is a folder; give a file name")
    ensure_folder(path.parent)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise output_error(path, exc) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise output_error(path, exc) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 text atomically."""
    return write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: str | os.PathLike, obj: Any) -> Path:
    """Write ``obj`` as JSON atomically; numpy values become plain numbers, NaN becomes null."""
    return write_text_atomic(path, json.dumps(_jsonable(obj), indent=2, allow_nan=False) + "\n")
