"""Time stamps of trend logs to UTC epoch seconds.

Accepted time columns
    * numbers: seconds since 1970-01-01 00:00 UTC (Unix time), or milliseconds with
      ``format = "milliseconds"``. Relative times (starting at 0) work for everything except
      the night window, which then refers to 1970-01-01 in the map's time zone. Every time
      must lie in the years 1677 to 2262 (what a nanosecond time stamp can hold); numbers
      beyond that which would be plausible dates in milliseconds are an error saying so;
    * ISO 8601 strings *with* an offset (``2011-11-06T01:30:00-05:00`` or ``...Z``):
      converted to UTC, so a log that changes offset at a daylight-saving change is
      read exactly;
    * ISO 8601 strings *without* an offset, or naive Parquet timestamps: local wall-clock
      times in the column map's ``timezone``, localized as below;
    * time-zone-aware Parquet timestamps: converted to UTC.

    A column that mixes stamps with and without offsets is an error.

Daylight-saving changes in naive local times (explicit policies)
    *Ambiguous* stamps (the repeated hour when DST ends) follow ``ambiguous``:
    ``"infer"`` (default) decides first/second occurrence from the order of the rows,
    which is right for any log written in time order (in a long log, each point's rows
    are inferred separately); ``"first"`` takes the summer-time occurrence, ``"second"``
    the standard-time one, ``"drop"`` removes those rows (and says so), ``"raise"``
    refuses. *Nonexistent* stamps (the skipped hour when DST starts; a correct clock
    never writes them, so they usually mean a logger that ignores DST) follow
    ``nonexistent``: ``"raise"`` (default), ``"shift_forward"`` (to the first valid
    instant) or ``"drop"``.

Rows are reported as *data rows*, counted from 1 for the first row after the header.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from rczone.errors import DataError

_OFFSET = re.compile(r"[T ]\d{1,2}:\d{2}(?::\d{2}(?:\.\d+)?)?\s*(?:Z|[+-]\d{2}(?::?\d{2})?)$", re.IGNORECASE)
_EPOCH = pd.Timestamp(0, tz="UTC")
LATEST = float(pd.Timestamp.max.value // 10**9)
"""Largest magnitude of epoch seconds a time stamp can hold (year 2262; 1677 below zero)."""
EPOCH_PLAUSIBLE = 3.15e8
"""1980-01-01 in epoch seconds: numbers that are this late only in milliseconds are milliseconds."""


def rows_text(rows: np.ndarray, limit: int = 5) -> str:
    """``"data rows 3, 7, 9 and 12 more"`` for 0-based row positions."""
    rows = np.asarray(rows)
    shown = ", ".join(str(int(r) + 1) for r in rows[:limit])
    more = f" and {rows.size - limit} more" if rows.size > limit else ""
    return f"data row{'s' if rows.size > 1 else ''} {shown}{more}"


def _epoch_seconds(idx: pd.DatetimeIndex) -> np.ndarray:
    return np.asarray((idx - _EPOCH) / pd.Timedelta(seconds=1), dtype=float)


def _numeric(raw: pd.Series, column: str, unit: float = 1.0) -> np.ndarray:
    """Numbers of seconds (``unit`` = 1) or milliseconds (``unit`` = 1e-3) as seconds."""
    t = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    what = "seconds" if unit == 1.0 else "milliseconds"
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise DataError(
            f"time column {column!r}: not a number of {what} at {rows_text(bad)}"
            f" (value {raw.iloc[bad[0]]!r}); use Unix seconds or ISO 8601 stamps"
        )
    t = t * unit
    far = np.flatnonzero(np.abs(t) > LATEST)
    if far.size:
        k = int(far[0])
        if unit == 1.0 and np.all(np.abs(t) / 1e3 <= LATEST) and np.all(t / 1e3 >= EPOCH_PLAUSIBLE):
            raise DataError(
                f"time column {column!r}: {raw.iloc[k]} at {rows_text(far)} is after the year 2262 in"
                " seconds; the times look like milliseconds since 1970: set [time] format ="
                ' "milliseconds" in a column map'
            )
        raise DataError(
            f"time column {column!r}: {raw.iloc[k]} at {rows_text(far)} is {what} outside the years"
            " 1677 to 2262; use Unix seconds or ISO 8601 stamps"
        )
    return t


def _looks_numeric(raw: pd.Series) -> bool:
    if pd.api.types.is_bool_dtype(raw.dtype):
        return False
    if pd.api.types.is_numeric_dtype(raw.dtype):
        return True
    if not (pd.api.types.is_object_dtype(raw.dtype) or pd.api.types.is_string_dtype(raw.dtype)):
        return False
    return bool(pd.to_numeric(raw, errors="coerce").notna().all())


def _parse_iso(raw: pd.Series, column: str) -> pd.DatetimeIndex:
    text = raw.astype("string").str.strip()
    empty = np.flatnonzero(text.isna().to_numpy() | (text == "").fillna(True).to_numpy())
    if empty.size:
        raise DataError(f"time column {column!r}: empty time stamp at {rows_text(empty)}")
    aware = text.str.contains(_OFFSET).to_numpy(dtype=bool)
    if aware.any() and not aware.all():
        raise DataError(
            f"time column {column!r}: mixes stamps with a UTC offset ({rows_text(np.flatnonzero(aware), 2)})"
            f" and without ({rows_text(np.flatnonzero(~aware), 2)}); write all stamps one way"
        )
    parsed = pd.to_datetime(text, format="ISO8601", utc=bool(aware.all()), errors="coerce")
    bad = np.flatnonzero(parsed.isna().to_numpy())
    if bad.size:
        raise DataError(
            f"time column {column!r}: {text.iloc[bad[0]]!r} at {rows_text(bad)} is not an ISO 8601 time"
            " stamp; expected e.g. '2011-08-02T18:00:00', '2011-08-02 18:00:00-04:00' or Unix seconds"
        )
    return pd.DatetimeIndex(parsed)


def _localize(
    idx: pd.DatetimeIndex,
    tz: str,
    ambiguous: str,
    nonexistent: str,
    groups: np.ndarray | None,
    column: str,
) -> tuple[pd.DatetimeIndex, np.ndarray, list[str]]:
    """Localize naive wall-clock times; returns UTC index of kept rows, keep mask, notes."""
    n = len(idx)
    yes = np.ones(n, dtype=bool)
    nonexist = np.asarray(idx.tz_localize(tz, ambiguous=yes, nonexistent="NaT").isna())
    amb = np.asarray(idx.tz_localize(tz, ambiguous="NaT", nonexistent="NaT").isna()) & ~nonexist
    keep = np.ones(n, dtype=bool)
    notes: list[str] = []
    if nonexist.any():
        rows = np.flatnonzero(nonexist)
        if nonexistent == "raise":
            raise DataError(
                f"time column {column!r}: local time {idx[rows[0]]} at {rows_text(rows)} does not exist in"
                f" {tz} (clocks jump forward for daylight saving); set [time] nonexistent ="
                ' "shift_forward" or "drop", or a fixed-offset timezone if the logger ignores DST'
            )
        if nonexistent == "drop":
            keep &= ~nonexist
            notes.append(f"dropped {rows.size} time stamp(s) that do not exist in {tz} ({rows_text(rows)})")
    if amb.any():
        rows = np.flatnonzero(amb)
        if ambiguous == "raise":
            raise DataError(
                f"time column {column!r}: local time {idx[rows[0]]} at {rows_text(rows)} is ambiguous in"
                f' {tz} (repeated hour when daylight saving ends); set [time] ambiguous = "infer",'
                ' "first", "second" or "drop", or write stamps with a UTC offset'
            )
        if ambiguous == "drop":
            keep &= ~amb
            notes.append(f"dropped {rows.size} ambiguous local time stamp(s) in {tz} ({rows_text(rows)})")
    sub = idx[keep]
    shift = "shift_forward" if nonexistent == "shift_forward" else "raise"
    if ambiguous in ("first", "second"):
        flags = np.full(len(sub), ambiguous == "first")
        local = sub.tz_localize(tz, ambiguous=flags, nonexistent=shift)
    elif ambiguous == "infer" and amb[keep].any():
        pos = np.arange(n)[keep]
        labels = np.zeros(len(sub), dtype=int) if groups is None else pd.factorize(groups[keep])[0]
        out = np.empty(len(sub), dtype=np.int64)
        for g in np.unique(labels):
            sel = np.flatnonzero(labels == g)
            try:
                part = sub[sel].tz_localize(tz, ambiguous="infer", nonexistent=shift)
            except Exception:  # pandas raises its own error types; one line for the user instead
                rows = pos[sel][amb[keep][sel]]
                raise DataError(
                    f"time column {column!r}: cannot tell which of the repeated local times at"
                    f" {rows_text(rows)} ({tz}, end of daylight saving) come first; the rows must be"
                    ' in time order, or set [time] ambiguous = "first", "second" or "drop"'
                ) from None
            out[sel] = part.tz_convert("UTC").as_unit("ns").asi8
        local = pd.DatetimeIndex(out.view("datetime64[ns]")).tz_localize("UTC")
    else:
        local = sub.tz_localize(tz, ambiguous="NaT", nonexistent=shift)
    return pd.DatetimeIndex(local).tz_convert("UTC"), keep, notes


def parse_times(
    raw: pd.Series,
    *,
    fmt: str = "auto",
    tz: str = "UTC",
    ambiguous: str = "infer",
    nonexistent: str = "raise",
    groups: np.ndarray | None = None,
    column: str = "time",
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Convert a time column to UTC epoch seconds.

    Parameters
    ----------
    raw : pandas.Series
        The time column as read.
    fmt : {"auto", "iso", "seconds", "milliseconds"}
        How to read it; ``"auto"`` takes numbers as seconds and strings as ISO 8601.
    tz : str
        IANA time zone of naive (offset-free) stamps.
    ambiguous, nonexistent : str
        Daylight-saving policies (see the module docstring).
    groups : ndarray or None
        Point names of a long log, so that ``"infer"`` works per point.
    column : str
        Column name for messages.

    Returns
    -------
    t : ndarray of float
        UTC epoch seconds of the kept rows, in row order.
    keep : ndarray of bool, shape (len(raw),)
        False for rows dropped by a ``"drop"`` policy.
    notes : list of str
        What was dropped, for the warnings list.
    """
    n = len(raw)
    keep = np.ones(n, dtype=bool)
    is_datetime = pd.api.types.is_datetime64_any_dtype(raw.dtype)
    if fmt in ("seconds", "milliseconds") and is_datetime:
        raise DataError(f'time column {column!r} holds date-times, not {fmt}; set [time] format = "auto"')
    if fmt == "milliseconds":
        return _numeric(raw, column, 1e-3), keep, []
    if fmt == "seconds" or (fmt == "auto" and not is_datetime and _looks_numeric(raw)):
        return _numeric(raw, column), keep, []
    try:
        return _parse_dates(raw, is_datetime, tz, ambiguous, nonexistent, groups, column, keep)
    except (pd.errors.OutOfBoundsDatetime, OverflowError):
        raise DataError(
            f"time column {column!r}: a time stamp lies outside the years 1677 to 2262 that rczone"
            " handles; check the dates"
        ) from None


def _parse_dates(
    raw: pd.Series,
    is_datetime: bool,
    tz: str,
    ambiguous: str,
    nonexistent: str,
    groups: np.ndarray | None,
    column: str,
    keep: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Date-times (Parquet) or ISO 8601 strings to UTC epoch seconds (see :func:`parse_times`)."""
    if is_datetime:
        idx = pd.DatetimeIndex(raw)
        bad = np.flatnonzero(idx.isna())
        if bad.size:
            raise DataError(f"time column {column!r}: missing time stamp at {rows_text(bad)}")
    else:
        idx = _parse_iso(raw, column)
    if idx.tz is not None:
        return _epoch_seconds(idx.tz_convert("UTC")), keep, []
    utc, keep, notes = _localize(idx, tz, ambiguous, nonexistent, groups, column)
    return _epoch_seconds(utc), keep, notes


def to_local(t: np.ndarray, tz: str) -> pd.DatetimeIndex:
    """UTC epoch seconds to a time-zone-aware index in ``tz`` (for display)."""
    return pd.to_datetime(np.asarray(t, dtype=float), unit="s", utc=True).tz_convert(tz)
