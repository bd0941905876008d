"""Load building trend logs (CSV or Parquet, wide or long) into :class:`ZoneData`.

The pipeline, each step documented in its own module:

1. read the table (:func:`read_table`): ``.csv``/``.csv.gz``/``.txt`` (comma separated),
   ``.tsv`` (tab separated), ``.parquet``/``.pq``;
2. pick the column map (:mod:`rczone.data.columnmap`; without one, the default layout);
3. time stamps to UTC epoch seconds with explicit daylight-saving policies
   (:mod:`rczone.data.timestamps`);
4. wide logs: rows must be strictly increasing in time (duplicates and steps back are
   errors naming the rows). Long logs (one row per point and time stamp): rows may come
   in any order, a repeated (point, time) pair is an error, and the points are pivoted
   onto the union of their time stamps;
5. every value must be a number (or empty / one of ``na_values``); each channel is
   converted to SI and checked for plausibility (:mod:`rczone.data.units`); a channel
   that is entirely empty is an error;
6. optional resampling onto a uniform grid -- linear for temperatures and heat, hold
   for flows, NaN across gaps longer than ``max_gap`` (:mod:`rczone.data.resample`).
   Unless the map sets it, a channel's ``max_gap`` is the larger of 1800 s and three
   times the median step between its own samples, so an hourly log is not all gaps while
   a 1-min log still breaks at a half-hour outage;
7. ``Tsd`` = the mean of the surroundings at each time (NaN if any of them is missing:
   a mean over fewer rooms would be a different input);
8. gaps are listed, and suspicious findings (gaps, flat temperatures, irregular
   sampling, dropped DST rows) become :class:`RczoneWarning` warnings
   (:mod:`rczone.data.quality`).

Every problem in the data raises :class:`~rczone.errors.DataError` with one line naming
the column, row or key and what was expected -- never a traceback from pandas.
"""

from __future__ import annotations

import gzip
import io
import warnings
import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from pyarrow import ArrowException

from rczone.data.columnmap import (
    DEFAULT_MAX_GAP,
    UNNAMED_TIME,
    ColumnMap,
    default_column_map,
    is_unnamed,
    read_column_map,
)
from rczone.data.derived import Combination
from rczone.data.quality import FLAT_SECONDS, RczoneWarning, find_gaps, longest_flat_run
from rczone.data.resample import hold_previous, interpolate_linear, uniform_grid
from rczone.data.timestamps import parse_times, rows_text, to_local
from rczone.data.units import SI_UNITS, check_plausible, to_si
from rczone.data.zonedata import ZoneData
from rczone.errors import DataError, did_you_mean, user_stacklevel

CSV_SUFFIXES = (".csv", ".csv.gz", ".txt", ".tsv")
LONG_STEP = 3 * 3600.0
"""A median time step longer than this (s) is reported: a room's dynamics are hours."""
PARQUET_SUFFIXES = (".parquet", ".pq")
MAX_DATA_BYTES = 100_000_000
"""Largest trend log read (bytes, after decompression for ``.csv.gz``): a year of 1-minute samples
of a dozen columns is about 60 MB. A larger file (or a gzip bomb) is refused before it is parsed."""
MAX_ROWS = 2_000_000
"""Most rows of a trend log (a year at 15-second samples); the same as the resampled grid's limit
(:data:`rczone.data.resample.MAX_SAMPLES`)."""


def _csv_source(path: Path) -> Path | io.BytesIO:
    """A CSV file as pandas reads it: the file, or a ``.gz`` decompressed here within the limit."""
    from rczone.files.text import _too_large

    if not path.name.lower().endswith(".gz"):
        return path
    out = io.BytesIO()
    with gzip.open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            out.write(block)
            if out.tell() > MAX_DATA_BYTES:
                raise _too_large(
                    path,
                    "data file (decompressed)",
                    out.tell(),
                    MAX_DATA_BYTES,
                    "rczone.data.load.MAX_DATA_BYTES",
                )
    out.seek(0)
    return out


def _check_rows(n: int, path: Path) -> None:
    if n > MAX_ROWS:
        raise DataError(
            f"{path}: {n:,} rows, more than the limit of {MAX_ROWS:,} (rczone.data.load.MAX_ROWS);"
            " use a shorter record (the column map's [time] start and end) or a coarser log"
        )


def _first_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _check_header(frame: pd.DataFrame, header: list[str], path: Path, sep: str) -> None:
    """Duplicate column names, and a header that is one column because of another delimiter."""
    seen: dict[str, int] = {}
    for k, name in enumerate(header, 1):
        if name in seen and name.strip():
            raise DataError(
                f"{path}: column {name!r} appears twice in the header (columns {seen[name]} and {k});"
                " rename or remove one"
            )
        seen[name] = k
    if frame.shape[1] == 1 and header:
        other = next((d for d in (";", "\t", "|") if d in header[0] and d != sep), None)
        if other is not None:
            shown = "tab" if other == "\t" else repr(other)
            expected = "tab" if sep == "\t" else repr(sep)
            raise DataError(
                f"{path}: the header is one column {header[0][:60]!r}; the file seems separated by {shown},"
                f" rczone reads {expected}-separated {path.suffix} files: save it comma-separated"
                " (or tab-separated as .tsv)"
            )


def read_table(path: str | Path, na_values: tuple[str, ...] = ()) -> pd.DataFrame:
    """Read a CSV or Parquet trend log into a DataFrame, turning reader failures into DataError."""
    from rczone.files.text import _too_large, nfkc, regular_file

    path = Path(path)
    name = path.name.lower()
    st = regular_file(path, "data file")  # before opening: a pipe or /dev/zero is one line, not a hang
    if st.st_size > MAX_DATA_BYTES:
        raise _too_large(path, "data file", st.st_size, MAX_DATA_BYTES, "rczone.data.load.MAX_DATA_BYTES")
    try:
        if name.endswith(PARQUET_SUFFIXES):
            import pyarrow.parquet as pq

            parquet = pq.ParquetFile(path)
            _check_rows(parquet.metadata.num_rows, path)
            frame = _parquet_frame(parquet, path)
            # a file's own metadata is not read (the loader builds a new frame from the arrays); pandas
            # deep-copies attrs at every column access, a fifth of reading a virtual night's file
            frame.attrs = {}
            if not isinstance(frame.index, pd.RangeIndex):  # a frame saved with its index: a column
                name = frame.index.name
                frame = frame.reset_index(names="" if name is None else str(name))
            frame.columns = [nfkc(str(c)) for c in frame.columns]  # names in one Unicode form
            _check_header(frame, list(frame.columns), path, ",")
            return frame
        if name.endswith(CSV_SUFFIXES):
            sep = "\t" if name.endswith(".tsv") else ","
            source = _csv_source(path)
            header = pd.read_csv(source, sep=sep, header=None, nrows=1, dtype=str, keep_default_na=False)
            if isinstance(source, io.BytesIO):
                source.seek(0)
            frame = pd.read_csv(source, sep=sep, na_values=list(na_values) or None)
            _check_rows(len(frame), path)
            names = [nfkc(str(c)) for c in header.iloc[0]]  # names in one Unicode form
            _check_header(frame, names, path, sep)
            frame.columns = [nfkc(str(c)) for c in frame.columns]
            return frame
    except DataError:
        raise
    except UnicodeDecodeError as exc:
        raise DataError(
            f"{path}: cannot read the table: not UTF-8 text (byte 0x{exc.object[exc.start]:02x});"
            " save it as UTF-8"
        ) from None
    except (EOFError, zlib.error, gzip.BadGzipFile) as exc:
        raise DataError(
            f"{path}: cannot read the table: the file ends early or is damaged ({_first_line(exc)})"
        ) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, OSError, ValueError, ArrowException) as exc:
        raise DataError(f"{path}: cannot read the table: {_first_line(exc)}") from None
    raise DataError(
        f"{path}: unknown file type; expected one of {', '.join(CSV_SUFFIXES + PARQUET_SUFFIXES)}"
    )


def _parquet_frame(parquet, path: Path) -> pd.DataFrame:
    """The frame of ``path``, opened as ``parquet`` (a ``pyarrow.parquet.ParquetFile``), as ``pandas.read_parquet`` makes it.

    The file opened once (``read_parquet`` opens it again through pyarrow's dataset layer) and read
    on this thread: 0.5 ms instead of 1.2 ms for a night's file, a batch reads thousands.
    """
    try:
        from pandas.io._util import arrow_table_to_pandas  # what read_parquet itself converts with
    except ImportError:  # another pandas: its own reader
        return pd.read_parquet(path)
    table = parquet.read(use_threads=False, use_pandas_metadata=True)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "make_block is deprecated")  # as read_parquet does
        try:
            return arrow_table_to_pandas(table)
        except TypeError:  # a private function whose signature another pandas changed
            return pd.read_parquet(path)


def load_zone_data(
    path: str | Path,
    column_map: ColumnMap | str | Path | None = None,
    *,
    flat_seconds: float = FLAT_SECONDS,
    signals: Mapping[str, str] | None = None,
    required: Sequence[str] = (),
) -> ZoneData:
    """Load a trend log file into SI arrays.

    Parameters
    ----------
    path : str or Path
        CSV or Parquet file.
    column_map : ColumnMap, path to a TOML file, or None
        None uses the default layout (:func:`~rczone.data.columnmap.default_column_map`).
    flat_seconds : float
        A temperature exactly constant for longer than this (s) is reported as flat.
    signals : mapping of channel name to quantity, optional
        The signals of the model the data are for: without a column map, every column named as
        one of them is read (:func:`~rczone.data.columnmap.default_column_map`); with a map, they
        give the quantity of channels the map does not declare.
    required : sequence of str
        Of the ``signals``, the columns a file without a column map must have.

    Returns
    -------
    ZoneData

    Raises
    ------
    DataError
        For any data problem, with one line saying what and where.
    FileNotFoundError
        If ``path`` (or the map file) does not exist.
    """
    cmap = read_column_map(column_map, signals) if isinstance(column_map, str | Path) else column_map
    frame = read_table(path, cmap.na_values if cmap is not None else ())
    return zone_data_from_frame(
        frame, cmap, source=Path(path).name, flat_seconds=flat_seconds, signals=signals, required=required
    )


def _require(columns: list[str], needed: str, what: str, source: str) -> None:
    if needed not in columns:
        raise DataError(f"{source}: no {what} {needed!r}; {did_you_mean(needed, columns)}")


def _time_column(columns: list[str], cmap: ColumnMap, source: str) -> str:
    """The table's time column: the map's, or for ``column = ""`` the first column without a name."""
    unnamed = [c for c in columns if is_unnamed(c)]
    if cmap.time_column == UNNAMED_TIME:
        if not unnamed:
            raise DataError(
                f'{source}: [time] column = "" names the column without a name (a table written with its'
                f" index), but every column has one; name the time column ({did_you_mean('time', columns)})"
            )
        return unnamed[0]
    if cmap.time_column not in columns and unnamed:
        raise DataError(
            f"{source}: no time column {cmap.time_column!r}; the column {columns.index(unnamed[0]) + 1} has no"
            f' name (an index written with the table?): to use it, write column = "" under [time] in the'
            " column map"
        )
    _require(columns, cmap.time_column, "time column", source)
    return cmap.time_column


def _combine(combo: Combination, column_values) -> np.ndarray:
    """``offset + sum(k * column)`` of a derived channel (NaN where any of its columns is)."""
    total = None
    for column, k in combo.terms:
        x = column_values(column)
        total = k * x if total is None else total + k * x
    return total + combo.offset if combo.offset else total


def _numbers(raw: pd.Series, column: str, rows: np.ndarray, source: str) -> np.ndarray:
    """Column as float; a non-empty entry that is not a number is an error naming its row."""
    if pd.api.types.is_bool_dtype(raw.dtype):
        raise DataError(f"{source}: column {column!r} holds true/false values, expected numbers")
    if pd.api.types.is_float_dtype(raw.dtype) or pd.api.types.is_integer_dtype(raw.dtype):
        return raw.to_numpy(dtype=float, na_value=np.nan)  # numbers already: nothing to check
    x = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    bad = np.flatnonzero(np.isnan(x) & raw.notna().to_numpy())
    if bad.size:
        raise DataError(
            f"{source}: column {column!r} has a non-numeric value {raw.iloc[bad[0]]!r} at"
            f" {rows_text(rows[bad])}; clean it or list it in na_values of the column map"
        )
    return x


def _check_order(t: np.ndarray, rows: np.ndarray, where: str, source: str) -> None:
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if not bad.size:
        return
    k = int(bad[0])
    a, b = int(rows[k]) + 1, int(rows[k + 1]) + 1
    stamp = pd.Timestamp(t[k + 1], unit="s", tz="UTC").isoformat()
    if dt[k] == 0:
        n = int(np.sum(dt == 0))
        raise DataError(
            f"{source}: duplicate time stamp {stamp} in {where} at data rows {a} and {b}"
            f" ({n} duplicate(s) in all); remove repeated rows"
        )
    raise DataError(
        f"{source}: time stamps in {where} go backwards at data row {b} ({stamp} follows"
        f" {pd.Timestamp(t[k], unit='s', tz='UTC').isoformat()} at data row {a});"
        " sort the log by time"
    )


def _times(source: str, raw: pd.Series, **kwargs) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """:func:`parse_times` with the file named in its errors."""
    try:
        return parse_times(raw, **kwargs)
    except DataError as exc:
        raise DataError(f"{source}: {exc}") from None


def _samples_wide(frame: pd.DataFrame, cmap: ColumnMap, source: str, notes: list[str]):
    cols = [str(c) for c in frame.columns]
    tcol = _time_column(cols, cmap, source)
    for ch in cmap.channels:
        for c in ch.columns:
            _require(cols, c, f"column for channel {ch.name!r}", source)
    t, keep, dropped = _times(
        source,
        frame[tcol],
        fmt=cmap.time_format,
        tz=cmap.timezone,
        ambiguous=cmap.ambiguous,
        nonexistent=cmap.nonexistent,
        column=tcol,
    )
    notes += dropped
    rows = np.flatnonzero(keep)
    _check_order(t, rows, f"column {tcol!r}", source)
    kept = frame.iloc[rows]
    numbers: dict[str, np.ndarray] = {}

    def values(column: str) -> np.ndarray:
        if column not in numbers:
            numbers[column] = _numbers(kept[column], column, rows, source)
        return numbers[column]

    samples = {}
    for ch in cmap.channels:
        if ch.combination is not None:
            samples[ch.name] = (t, _combine(ch.combination, values), rows)
    return t, samples


def _samples_long(frame: pd.DataFrame, cmap: ColumnMap, source: str, notes: list[str]):
    cols = [str(c) for c in frame.columns]
    tcol = _time_column(cols, cmap, source)
    for needed, what in (
        (cmap.long_point, "point-name column"),
        (cmap.long_value, "value column"),
    ):
        _require(cols, needed, what, source)
    points = frame[cmap.long_point].astype("string")
    present = [str(p) for p in points.dropna().unique()]
    for ch in cmap.channels:
        if len(ch.columns) > 1:
            raise DataError(
                f"{source}: channel {ch.name!r} combines several points ({ch.column}); in a long log a"
                " channel is one point (with a scale and offset if needed): sum the points before"
            )
    wanted = {c for ch in cmap.channels for c in ch.columns}
    for ch in cmap.channels:
        for point in ch.columns:
            if point not in present:
                raise DataError(
                    f"{source}: no point {point!r} (channel {ch.name!r}) in column {cmap.long_point!r};"
                    f" {did_you_mean(point, present)}"
                )
    rows = np.flatnonzero(points.isin(wanted).fillna(False).to_numpy())
    sub = frame.iloc[rows]
    t, keep, dropped = _times(
        source,
        sub[tcol],
        fmt=cmap.time_format,
        tz=cmap.timezone,
        ambiguous=cmap.ambiguous,
        nonexistent=cmap.nonexistent,
        groups=sub[cmap.long_point].astype(str).to_numpy(),
        column=tcol,
    )
    notes += dropped
    rows = rows[keep]
    sub = frame.iloc[rows]
    values = _numbers(sub[cmap.long_value], cmap.long_value, rows, source)
    pts = sub[cmap.long_point].astype(str).to_numpy()
    by_point = {}
    for p in wanted:
        sel = np.flatnonzero(pts == p)
        order = np.argsort(t[sel], kind="stable")
        sel = sel[order]
        _check_order(t[sel], rows[sel], f"column {tcol!r} for point {p!r}", source)
        by_point[p] = (t[sel], values[sel], rows[sel])
    axis = np.unique(t)
    samples = {}
    for ch in cmap.channels:
        if ch.combination is not None:
            t_p, x_p, rows_p = by_point[ch.columns[0]]
            samples[ch.name] = (t_p, _combine(ch.combination, lambda _, x=x_p: x), rows_p)
    return axis, samples


def _on_axis(axis: np.ndarray, t: np.ndarray, x: np.ndarray) -> np.ndarray:
    out = np.full(axis.shape, np.nan)
    out[np.searchsorted(axis, t)] = x
    return out


def _gap_limit(explicit: float | None, t: np.ndarray, x: np.ndarray) -> float:
    """The map's max_gap, else max(1800 s, 3 x median step between the channel's finite samples)."""
    if explicit is not None:
        return explicit
    tf = t[np.isfinite(x)]
    typical = float(np.median(np.diff(tf))) if tf.size > 1 else 0.0
    return max(DEFAULT_MAX_GAP, 3.0 * typical)


def _warn(message: str, collected: list[str]) -> None:
    collected.append(message)
    warnings.warn(message, RczoneWarning, stacklevel=user_stacklevel())


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.3g} h"


def _window(axis: np.ndarray, samples: dict, cmap: ColumnMap, source: str):
    """Only the samples within ``[start, end)`` of the column map (UTC epoch seconds)."""
    lo = -np.inf if cmap.start is None else cmap.start
    hi = np.inf if cmap.end is None else cmap.end
    keep = (axis >= lo) & (axis < hi)
    if not keep.any():
        first, last = (
            pd.Timestamp(x, unit="s", tz="UTC").tz_convert(cmap.timezone) for x in (axis[0], axis[-1])
        )
        raise DataError(
            f"{source}: no rows between [time] start and end of the column map; the data run from"
            f" {first:%Y-%m-%d %H:%M} to {last:%Y-%m-%d %H:%M} ({cmap.timezone})"
        )
    out = {}
    for name, (t_c, raw, rows) in samples.items():
        k = (t_c >= lo) & (t_c < hi)
        out[name] = (t_c[k], raw[k], rows[k])
    return axis[keep], out


def zone_data_from_frame(
    frame: pd.DataFrame,
    column_map: ColumnMap | None = None,
    *,
    source: str = "<frame>",
    flat_seconds: float = FLAT_SECONDS,
    signals: Mapping[str, str] | None = None,
    required: Sequence[str] = (),
) -> ZoneData:
    """Build :class:`ZoneData` from a table already in memory (same rules as :func:`load_zone_data`)."""
    cmap = (
        column_map
        if column_map is not None
        else default_column_map(list(frame.columns), source, signals, required)
    )
    if not isinstance(cmap, ColumnMap):
        raise DataError(f"column_map must be a ColumnMap, a TOML path or None, got {type(cmap).__name__}")
    if len(frame) == 0:
        raise DataError(f"{source}: the table has no data rows")
    if all(ch.column is None for ch in cmap.channels):
        raise DataError(f"{source}: the column map gives only constants; map at least one column (e.g. Ti)")
    notes: list[str] = []
    if cmap.is_long:
        axis, samples = _samples_long(frame, cmap, source, notes)
    else:
        axis, samples = _samples_wide(frame, cmap, source, notes)
    if cmap.start is not None or cmap.end is not None:
        axis, samples = _window(axis, samples, cmap, source)

    collected: list[str] = []
    for n in notes:
        _warn(f"{source}: {n}", collected)

    # Convert to SI and check each channel on its own samples (rows are the file's rows).
    si_samples = {}
    for ch in cmap.channels:
        if ch.column is None:
            continue
        t_c, raw, rows = samples[ch.name]
        if not np.isfinite(raw).any():
            raise DataError(
                f"{source}: column {ch.column!r} (channel {ch.name!r}) has no values (all empty/NaN)"
            )
        si = to_si(raw, ch.unit, ch.quantity, ch.column, cmap.air_density)
        check_plausible(si, raw, ch.role, ch.unit, ch.column, cmap.air_density, rows)
        si_samples[ch.name] = (t_c, si)

    if cmap.step is not None:
        t_out = uniform_grid(float(axis[0]), float(axis[-1]), cmap.step)  # refuses absurd sizes
    else:
        t_out = axis
    limits: dict[str, float] = {}
    columns: dict[str, np.ndarray] = {}
    for ch in cmap.channels:
        if ch.column is None:
            value = to_si([ch.value], ch.unit, ch.quantity, ch.name, cmap.air_density)
            check_plausible(value, np.array([ch.value]), ch.role, ch.unit, ch.name, cmap.air_density)
            columns[ch.name] = np.full(t_out.shape, value[0])
            limits[ch.name] = np.inf
            continue
        t_c, si = si_samples[ch.name]
        explicit = (
            cmap.hold_max_gap if ch.quantity == "flow" and cmap.hold_max_gap is not None else cmap.max_gap
        )
        limits[ch.name] = limit = _gap_limit(explicit, t_c, si)
        if cmap.step is None:
            columns[ch.name] = _on_axis(t_out, t_c, si)
        elif ch.quantity == "flow":
            columns[ch.name] = hold_previous(t_c, si, t_out, limit)
        else:
            columns[ch.name] = interpolate_linear(t_c, si, t_out, limit)
    quantities = {ch.name: ch.quantity for ch in cmap.channels}
    units = {ch.name: SI_UNITS[ch.quantity] for ch in cmap.channels}
    source_units = {ch.name: ch.unit for ch in cmap.channels}
    if cmap.surroundings:
        columns["Tsd"] = np.mean(np.column_stack([columns[s] for s in cmap.surroundings]), axis=1)
        limits["Tsd"] = min(limits[s] for s in cmap.surroundings)
        quantities["Tsd"], units["Tsd"], source_units["Tsd"] = "temperature", "degC", "derived"

    if t_out.size < cmap.min_samples:
        raise DataError(
            f"{source}: only {t_out.size} sample(s) after loading, at least {cmap.min_samples} needed"
            + (f" (resampling step {cmap.step:g} s)" if cmap.step is not None else "")
        )

    # Findings that do not stop loading.
    finite_limits = [v for v in limits.values() if np.isfinite(v)]
    if cmap.step is None and t_out.size > 2 and finite_limits:
        dt = np.diff(t_out)
        dt = dt[dt <= min(finite_limits)]  # longer steps are reported as gaps below
        if dt.size and np.ptp(dt) > 1e-9 * dt.max():
            _warn(
                f"{source}: sampling is irregular (time steps from {dt.min():g} s to {dt.max():g} s);"
                " set [resample] step in the column map for a uniform grid",
                collected,
            )
    if t_out.size > 2:
        typical = float(np.median(np.diff(t_out)))
        if typical > LONG_STEP:
            _warn(
                f"{source}: the median time step is {_hours(typical)}, too coarse for a room's thermal"
                " dynamics; are the times in the right unit (seconds, or [time] format ="
                ' "milliseconds")?',
                collected,
            )
    gaps = []
    for name, x in columns.items():
        if not np.isfinite(limits[name]):
            continue  # a constant has no gaps
        found = find_gaps(t_out, x, name, limits[name])
        gaps += found
        if found:
            worst = max(found, key=lambda g: g.duration)
            when = to_local(np.array([worst.start, worst.end]), cmap.timezone)
            _warn(
                f"{source}: channel {name!r} has {len(found)} gap(s), longest {_hours(worst.duration)}"
                f" from {when[0].isoformat()} to {when[1].isoformat()}",
                collected,
            )
    for ch in cmap.channels:
        if ch.quantity != "temperature" or ch.column is None:
            continue
        dur, a, _ = longest_flat_run(t_out, columns[ch.name])
        if dur > flat_seconds:
            when = to_local(np.array([a]), cmap.timezone)[0].isoformat()
            _warn(
                f"{source}: channel {ch.name!r} (column {ch.column!r}) stays exactly at"
                f" {columns[ch.name][np.searchsorted(t_out, a)]:g} degC for {_hours(dur)} from {when};"
                " stuck sensor?",
                collected,
            )

    names = tuple(columns)
    return ZoneData(
        t=t_out,
        values=np.column_stack([columns[n] for n in names]) if names else np.empty((t_out.size, 0)),
        channels=names,
        units=units,
        source_units=source_units,
        quantities=quantities,
        source=cmap.name or source,
        timezone=cmap.timezone,
        night=(cmap.night_start, cmap.night_end),
        step=cmap.step,
        max_gaps=limits,
        surroundings=cmap.surroundings,
        ignored=cmap.ignored,
        gaps=tuple(sorted(gaps, key=lambda g: (g.start, g.channel))),
        warnings=tuple(collected),
    )
