"""The column map: a small TOML file saying which trend-log column is which model channel.

A building management system (BMS) names its points after the site (``RM241.ZN-T``),
logs them in its own units and local time. The column map tells rczone which column is
which channel, in which unit, and how to read the time stamps. Without a map the default
layout is used (see :func:`default_column_map`).

Format
------
Every key is optional except ``[columns]``. Unknown keys are errors (with a suggestion of
the close name), so a typo never silently drops a setting::

    name = "Pugh Hall 241"        # label used in messages (default: the file name)
    air_density = 1.2             # kg/m3, turns volume flows (m3/s, L/s, cfm) into kg/s
    na_values = ["Offline", "---"]  # extra strings meaning "no value" (CSV only)
    min_samples = 10              # fewer usable samples than this is an error (default 2)

    [time]
    column = "Timestamp"          # default "time"; "" is the unnamed column of a table written
                                  #   with its index (pandas reads its header as "Unnamed: 0")
    format = "auto"               # "auto" | "iso" | "seconds" | "milliseconds" (Unix epoch, UTC)
    timezone = "America/New_York" # IANA zone of naive local stamps and of the night window
                                  # (default "UTC"; a fixed offset is e.g. "Etc/GMT+5" = UTC-5)
    start = "2014-07-01"          # only the rows from this local date (or date and time) on ...
    end = "2014-08-15"            # ... and before this one (either may be left out)
    ambiguous = "infer"           # repeated local hour at the end of DST:
                                  #   "infer" (from the order of the rows, default), "first"
                                  #   (summer time), "second" (standard time), "drop", "raise"
    nonexistent = "raise"         # skipped local hour at the start of DST:
                                  #   "raise" (default), "shift_forward", "drop"

    [long]                        # only for long logs: one row per point and time stamp
    point = "PointName"           # column holding the point name
    value = "Value"               # column holding the value

    [columns]                     # channel = column (default unit) or a table
    Ti = { column = "RM241.ZN-T", unit = "degF" }   # room temperature (the output)
    To = { column = "OA-T", unit = "degF" }         # outdoor temperature
    Ts = { column = "RM241.SA-T", unit = "degF" }   # supply-air temperature
    m  = { column = "RM241.SA-F", unit = "cfm" }    # supply-air flow (mass flow inside)
    Q  = { value = 50, unit = "W" }                 # a constant instead of a column
    # Tsd = "Tsurr"                                 # either a Tsd column or [surroundings]
    m2 = { column = "VAV2", unit = "L/s", quantity = "flow" }  # any other channel
    Qh = { expr = "HC1.Q + HC2.Q", unit = "kW", quantity = "power" }  # derived: a sum of columns
    m3 = { column = "VAV3", scale = 0.5, unit = "L/s", quantity = "flow" }  # scale * column + offset

    [surroundings]                # temperatures around the zone; Tsd = their mean
    Tf  = { column = "RM141.ZN-T", unit = "degF" }
    Tc  = { column = "RM341.ZN-T", unit = "degF" }
    Tn1 = { column = "RM240.ZN-T", unit = "degF" }
    Tn2 = { column = "RM242.ZN-T", unit = "degF" }
    Thw = { column = "HALL2.ZN-T", unit = "degF" }

    [resample]                    # omit to keep the time stamps as given
    step = 300                    # s, uniform grid aligned to multiples of step (UTC epoch)
    max_gap = 1800                # s, never interpolate across a longer gap (default: the
                                  #   larger of 1800 s and 3 median sampling steps of the channel)
    hold_max_gap = 7200           # s, same for held flows (default: as max_gap)

    [night]                       # night window in local time (default 18:00 to 06:00)
    start = "18:00"
    end = "06:00"

Channels ``Ti``, ``To``, ``Ts``, ``Tsd`` (temperatures), ``m`` (flow) and ``Q`` (power)
are known, and so are the signals of the model the data are read for (a heater ``Ph``, the
sun ``Ps``). A channel the model does not use is ignored (listed in :attr:`ColumnMap.ignored`),
so one map serves candidates with and without solar gains; without a model, any other name
needs ``quantity = "temperature" | "flow" | "power"``. Default units: degC, kg/s, W. Accepted
units are listed in :mod:`rczone.data.units`. In a long log ``column`` is the point name.

A derived channel (``expr``, or ``scale`` and ``offset`` on a column) is a linear combination
of columns computed in the declared unit before the conversion to SI
(:mod:`rczone.data.derived`); it is missing where any of its columns is.
"""

from __future__ import annotations

import math
import re
import zoneinfo
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rczone.data.derived import Combination, parse_expression
from rczone.data.units import DEFAULT_AIR_DENSITY, SI_UNITS, canonical_unit
from rczone.errors import DataError, did_you_mean
from rczone.files.text import nfkc, read_toml

KNOWN_CHANNELS = {
    "Ti": ("temperature", "room"),
    "To": ("temperature", "outdoor"),
    "Ts": ("temperature", "supply"),
    "Tsd": ("temperature", "room"),
    "m": ("flow", "flow"),
    "Q": ("power", "power"),
}
"""Channel name -> (quantity, plausibility role) of the channels rczone knows."""

DEFAULT_SURROUNDINGS = ("Tf", "Tc", "Tn1", "Tn2", "Thw")
"""The paper's five surrounding spaces: floor, ceiling, two neighbours, hallway."""

_ROLE_OF_QUANTITY = {
    "temperature": "temperature",
    "flow": "flow",
    "power": "power",
    "irradiance": "irradiance",
}
AMBIGUOUS = ("infer", "first", "second", "drop", "raise")
NONEXISTENT = ("raise", "shift_forward", "drop")
TIME_FORMATS = ("auto", "iso", "seconds", "milliseconds")
DEFAULT_MAX_GAP = 1800.0

_TOP_KEYS = (
    "name",
    "air_density",
    "na_values",
    "min_samples",
    "time",
    "long",
    "columns",
    "surroundings",
    "resample",
    "night",
)
_SECTION_KEYS = {
    "time": ("column", "format", "timezone", "ambiguous", "nonexistent", "start", "end"),
    "long": ("point", "value"),
    "resample": ("step", "max_gap", "hold_max_gap"),
    "night": ("start", "end"),
}
_CHANNEL_KEYS = ("column", "expr", "value", "unit", "quantity", "scale", "offset")


@dataclass(frozen=True)
class Channel:
    """One model channel and where it comes from.

    Attributes
    ----------
    name : str
        Channel name used by models (``"Ti"``, ``"Tf"``...).
    column : str or None
        Source column (wide log) or point name (long log), or the expression of a derived
        channel (as written, for messages); None for a constant.
    value : float or None
        Constant value in ``unit`` when there is no column.
    unit : str
        Declared unit (canonical spelling).
    quantity : str
        ``"temperature"``, ``"flow"`` or ``"power"``.
    role : str
        Plausibility role, a key of :data:`rczone.data.units.PLAUSIBLE`.
    combination : Combination or None
        How the value is computed from the table's columns (:mod:`rczone.data.derived`); None for
        a constant. A plain column is the combination of that column alone.
    """

    name: str
    column: str | None
    value: float | None
    unit: str
    quantity: str
    role: str
    combination: Combination | None = None

    def __post_init__(self) -> None:
        if self.combination is None and self.column is not None:
            object.__setattr__(self, "combination", Combination(((self.column, 1.0),)))

    @property
    def columns(self) -> tuple[str, ...]:
        """The table's columns (or a long log's points) this channel reads."""
        return () if self.combination is None else self.combination.columns


@dataclass(frozen=True)
class ColumnMap:
    """Validated column map (see the module docstring for the TOML format).

    ``time_column`` ``""`` is the unnamed column a table written with its index has
    (:data:`UNNAMED_TIME`); ``ignored`` lists the mapped channels the model the data were read for
    does not use (they are not loaded).
    """

    channels: tuple[Channel, ...]
    surroundings: tuple[str, ...] = ()
    time_column: str = "time"
    time_format: str = "auto"
    timezone: str = "UTC"
    ambiguous: str = "infer"
    nonexistent: str = "raise"
    long_point: str | None = None
    long_value: str | None = None
    air_density: float = DEFAULT_AIR_DENSITY
    step: float | None = None
    max_gap: float | None = None
    hold_max_gap: float | None = None
    start: float | None = None
    end: float | None = None
    night_start: str = "18:00"
    night_end: str = "06:00"
    na_values: tuple[str, ...] = ()
    min_samples: int = 2
    name: str = ""
    ignored: tuple[str, ...] = ()
    source: str = field(default="<defaults>", compare=False)

    @property
    def is_long(self) -> bool:
        """True for a long log (one row per point and time stamp)."""
        return self.long_point is not None

    @property
    def channel_names(self) -> tuple[str, ...]:
        """Names of the mapped channels, in order."""
        return tuple(c.name for c in self.channels)

    def channel(self, name: str) -> Channel:
        """The channel called ``name``."""
        for c in self.channels:
            if c.name == name:
                return c
        raise DataError(f"no channel {name!r} in the column map; {did_you_mean(name, self.channel_names)}")


def read_column_map(path: str | Path, signals: Mapping[str, str] | None = None) -> ColumnMap:
    """Read and validate a TOML column map.

    ``signals`` (channel name -> quantity, from the model the data are for) gives the quantity of
    channels the map does not declare one for (a model's heater ``Ph`` is a power).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    DataError
        For invalid TOML or any invalid setting (the message names the key).
    """
    path = Path(path)
    return parse_column_map(nfkc(read_toml(path, "column map")), source=str(path), signals=signals)


def _check_keys(table: Mapping, allowed: Sequence[str], where: str, source: str) -> None:
    if not isinstance(table, Mapping):
        raise DataError(f"column map {source}: {where} must be a table, got {type(table).__name__}")
    for key in table:
        if key not in allowed:
            raise DataError(
                f"column map {source}: unknown key {key!r} in {where}; {did_you_mean(key, allowed)}"
                f" (allowed: {', '.join(allowed)})"
            )


def _number(value, what: str, source: str, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise DataError(f"column map {source}: {what} must be a number, got {value!r}")
    if positive and value <= 0:
        raise DataError(f"column map {source}: {what} must be > 0, got {value!r}")
    return float(value)


def _text(value, what: str, source: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise DataError(f"column map {source}: {what} must be a non-empty string, got {value!r}")
    return value


def _choice(value, choices: Sequence[str], what: str, source: str) -> str:
    value = _text(value, what, source)
    if value not in choices:
        hint = did_you_mean(value, choices)
        hint = f"; {hint}" if hint.startswith("did you mean") else ""
        raise DataError(f"column map {source}: {what} = {value!r} is not one of {', '.join(choices)}{hint}")
    return value


#: Words pandas reads as a time relative to the clock: refused in ``[time] start/end``.
RELATIVE_DAYS = ("now", "today", "tomorrow", "yesterday")


def _instant(time: Mapping, key: str, tz: str, source: str) -> float | None:
    """``[time] start/end``: a date or date and time, local to the map's time zone, as UTC epoch seconds."""
    if key not in time:
        return None
    text = time[key]
    if hasattr(text, "isoformat"):  # TOML dates and date-times arrive as Python objects
        text = text.isoformat()
    text = _text(text, f"[time] {key}", source)
    import pandas as pd

    if text.strip().lower() in RELATIVE_DAYS:
        raise DataError(
            f"column map {source}: [time] {key} = {text!r} changes with the day rczone runs, and so would the"
            ' result; give a date (e.g. "2014-07-01"), or leave the key out for the end of the record'
        )
    try:
        ts = pd.Timestamp(text)
    except (ValueError, OverflowError):
        raise DataError(
            f'column map {source}: [time] {key} = {text!r} is not a date or date-time (e.g. "2014-07-01" or'
            ' "2014-07-01 18:00")'
        ) from None
    if ts is pd.NaT:
        raise DataError(f"column map {source}: [time] {key} = {text!r} is not a date")
    if ts.tzinfo is None:
        try:
            ts = ts.tz_localize(tz)
        except (ValueError, OverflowError) as exc:  # pytz/pandas: NonExistentTimeError, AmbiguousTimeError
            what = "does not exist" if "nonexistent" in str(exc).lower() else "is ambiguous"
            why = "clocks skip that hour" if what == "does not exist" else "that hour occurs twice"
            raise DataError(
                f"column map {source}: [time] {key} = {text!r} {what} in {tz} ({why} at a daylight-saving"
                " change); give a time outside the change, or with its UTC offset (e.g."
                ' "2014-11-02T01:30-05:00")'
            ) from None
    lo, hi = pd.Timestamp.min.tz_localize("UTC"), pd.Timestamp.max.tz_localize("UTC")
    try:
        inside = lo <= ts <= hi
    except (OverflowError, ValueError):
        inside = False
    if not inside:
        raise DataError(
            f"column map {source}: [time] {key} = {text!r} is outside the dates rczone handles"
            f" ({lo:%Y-%m-%d} to {hi:%Y-%m-%d}, nanosecond time stamps)"
        )
    return float(ts.value) / 1e9


def check_timezone(tz: str, source: str = "<defaults>") -> str:
    """Return ``tz`` if it is a known IANA time zone, else raise :class:`DataError`."""
    tz = _text(tz, "[time] timezone", source)
    try:
        zoneinfo.ZoneInfo(tz)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError):
        raise DataError(
            f"column map {source}: unknown time zone {tz!r}; "
            f"{did_you_mean(tz, zoneinfo.available_timezones())} (use an IANA name such as"
            " 'America/New_York', or 'Etc/GMT+5' for a fixed UTC-5)"
        ) from None
    return tz


#: ``[time] column = ""``: the column without a name, as pandas writes a frame's index to CSV (its
#: header cell is empty, which pandas reads back as ``"Unnamed: 0"``).
UNNAMED_TIME = ""
_UNNAMED = re.compile(r"^Unnamed: \d+$")


def is_unnamed(column: str) -> bool:
    """Whether ``column`` is a header cell that was empty (pandas reads it as ``"Unnamed: <k>"``)."""
    return not str(column).strip() or bool(_UNNAMED.match(str(column)))


def _time_column(value, source: str) -> str:
    if isinstance(value, str) and not value.strip():
        return UNNAMED_TIME
    return _text(value, "[time] column", source)


_CLOCK = re.compile(r"^([01]?\d|2[0-3]):([0-5]\d)$")


def check_clock(text: str, what: str, source: str = "<defaults>") -> str:
    """Return ``text`` if it is a local clock time ``"HH:MM"``, else raise :class:`DataError`."""
    if not isinstance(text, str) or not _CLOCK.match(text.strip()):
        raise DataError(f"column map {source}: {what} must be a clock time 'HH:MM', got {text!r}")
    return text.strip()


def _unknown_channel(name: str, where: str, source: str, signals: Mapping[str, str] | None, mapped) -> None:
    """Raise for a channel neither rczone nor the model knows, unless the model simply does not use it.

    With the model's ``signals``, a channel it does not use is not an error (one map serves
    candidates with and without solar gains; the caller ignores it), except when its name is
    close to one of the model's signals that the map leaves unmapped: that is a typo.
    """
    if signals is not None:
        unmapped = [s for s in signals if s not in mapped and s not in KNOWN_CHANNELS]
        unmapped += [s for s in KNOWN_CHANNELS if s in signals and s not in mapped]
        hint = did_you_mean(name, unmapped) if unmapped else ""
        if hint.startswith("did you mean"):
            raise DataError(
                f"column map {source}: channel {name!r} in {where} is not a signal of the model, and the"
                f" model's {hint.removeprefix('did you mean ').rstrip('?')} is not mapped; {hint}"
            )
        return
    hint = did_you_mean(name, KNOWN_CHANNELS)
    typo = f" (a typo of {hint.removeprefix('did you mean ').rstrip('?')}?)" if hint.startswith("did") else ""
    raise DataError(
        f"column map {source}: unknown channel {name!r} in {where}{typo}: it is neither one of"
        f" rczone's channels ({', '.join(KNOWN_CHANNELS)}) nor, with no model given, a model's signal;"
        ' read the data for the model that uses it, or declare quantity = "temperature" | "flow" |'
        ' "power" to load it anyway'
    )


def _source(
    spec: Mapping, name: str, where: str, source: str
) -> tuple[str | None, float | None, Combination | None]:
    """A channel's column, constant or expression, with its scale and offset."""
    given = [k for k in ("column", "expr", "value") if k in spec]
    if len(given) != 1:
        raise DataError(
            f"column map {source}: {where}.{name} needs exactly one of 'column', 'expr' or 'value'"
            + (f", got {' and '.join(given)}" if given else "")
        )
    scale = (
        _number(spec["scale"], f"{where}.{name}.scale", source, positive=False) if "scale" in spec else 1.0
    )
    offset = (
        _number(spec["offset"], f"{where}.{name}.offset", source, positive=False) if "offset" in spec else 0.0
    )
    if "value" in spec:
        if "scale" in spec or "offset" in spec:
            raise DataError(
                f"column map {source}: {where}.{name} is a constant; write its value, not a scale or offset"
            )
        return None, _number(spec["value"], f"{where}.{name}.value", source, positive=False), None
    if scale == 0:
        raise DataError(f"column map {source}: {where}.{name}.scale must not be 0")
    if "column" in spec:
        column = _text(spec["column"], f"{where}.{name}.column", source)
        combo = Combination(((column, 1.0),))
    else:
        column = _text(spec["expr"], f"{where}.{name}.expr", source).strip()
        combo = parse_expression(column, f"column map {source}: {where}.{name}.expr")
    return column, None, combo.scaled(scale, offset)


def _channel(
    name: str,
    spec,
    source: str,
    where: str,
    surrounding: bool,
    signals: Mapping[str, str] | None = None,
    mapped: Sequence[str] = (),
) -> Channel | None:
    """One channel of the map; None for a channel the model (``signals``) does not use."""
    if surrounding:
        quantity, role = "temperature", "room"
    else:
        quantity, role = KNOWN_CHANNELS.get(name, (None, None))
        if quantity is None and signals and name in signals:
            quantity, role = signals[name], _ROLE_OF_QUANTITY[signals[name]]
    if isinstance(spec, str):
        spec = {"column": spec}
    _check_keys(spec, _CHANNEL_KEYS, f"{where}.{name}", source)
    if "quantity" in spec:
        q = _choice(spec["quantity"], tuple(SI_UNITS), f"{where}.{name}.quantity", source)
        if quantity is not None and q != quantity:
            raise DataError(f"column map {source}: {where}.{name} is a {quantity}, not a {q}")
        quantity, role = q, role or _ROLE_OF_QUANTITY[q]
    if quantity is None:
        _unknown_channel(name, where, source, signals, mapped)
        return None
    column, value, combo = _source(spec, name, where, source)
    unit = spec.get("unit", SI_UNITS[quantity])
    unit = canonical_unit(_text(unit, f"{where}.{name}.unit", source), quantity, column or name)
    return Channel(name, column, value, unit, quantity, role, combo)


def parse_column_map(
    doc: Mapping, source: str = "<dict>", signals: Mapping[str, str] | None = None
) -> ColumnMap:
    """Validate a parsed TOML document (a dict) and build a :class:`ColumnMap`.

    Raises
    ------
    DataError
        Naming the offending key, with a suggestion for a misspelt one.
    """
    _check_keys(doc, _TOP_KEYS, "the top level", source)
    for sec, keys in _SECTION_KEYS.items():
        _check_keys(doc.get(sec, {}), keys, f"[{sec}]", source)
    if "columns" not in doc:
        raise DataError(f"column map {source}: missing the [columns] table naming the channels")
    cols = doc["columns"]
    surr = doc.get("surroundings", {})
    for table, where in ((cols, "[columns]"), (surr, "[surroundings]")):
        if not isinstance(table, Mapping):
            raise DataError(f"column map {source}: {where} must be a table, got {type(table).__name__}")
    read = {n: _channel(n, s, source, "[columns]", False, signals, tuple(cols)) for n, s in cols.items()}
    channels = [ch for ch in read.values() if ch is not None]
    ignored = tuple(n for n, ch in read.items() if ch is None)
    if not channels:
        raise DataError(f"column map {source}: [columns] is empty; map at least 'Ti'")
    for n in surr:
        if n in cols:
            raise DataError(f"column map {source}: channel {n!r} is in both [columns] and [surroundings]")
    if surr and "Tsd" in cols:
        raise DataError(
            f"column map {source}: give either Tsd in [columns] or a [surroundings] table (Tsd is"
            " then their mean), not both"
        )
    if "Tsd" in surr:
        raise DataError(f"column map {source}: 'Tsd' cannot be a surrounding; it is their mean")
    channels += [_channel(n, s, source, "[surroundings]", True) for n, s in surr.items()]
    by_column: dict[str, str] = {}
    for ch in channels:
        if ch.combination is None or not ch.combination.is_plain:
            continue  # a derived channel may share columns (Ph = Ph1 + Ph2 beside Ph1 itself)
        if ch.column in by_column:
            raise DataError(
                f"column map {source}: column {ch.column!r} is mapped to both {by_column[ch.column]!r} and"
                f" {ch.name!r}; each channel needs its own column"
            )
        by_column[ch.column] = ch.name

    time = doc.get("time", {})
    long = doc.get("long", {})
    if bool(long) and set(long) != {"point", "value"}:
        raise DataError(f"column map {source}: [long] needs both 'point' and 'value'")
    res = doc.get("resample", {})
    night = doc.get("night", {})
    na = doc.get("na_values", [])
    if not isinstance(na, list) or not all(isinstance(v, str) for v in na):
        raise DataError(f"column map {source}: na_values must be a list of strings, got {na!r}")
    min_samples = doc.get("min_samples", 2)
    if isinstance(min_samples, bool) or not isinstance(min_samples, int) or min_samples < 2:
        raise DataError(f"column map {source}: min_samples must be an integer >= 2, got {min_samples!r}")
    max_gap = _number(res["max_gap"], "[resample] max_gap", source) if "max_gap" in res else None
    cmap = ColumnMap(
        channels=tuple(channels),
        surroundings=tuple(surr),
        time_column=_time_column(time.get("column", "time"), source),
        time_format=_choice(time.get("format", "auto"), TIME_FORMATS, "[time] format", source),
        timezone=check_timezone(time.get("timezone", "UTC"), source),
        start=_instant(time, "start", time.get("timezone", "UTC"), source),
        end=_instant(time, "end", time.get("timezone", "UTC"), source),
        ambiguous=_choice(time.get("ambiguous", "infer"), AMBIGUOUS, "[time] ambiguous", source),
        nonexistent=_choice(time.get("nonexistent", "raise"), NONEXISTENT, "[time] nonexistent", source),
        long_point=_text(long["point"], "[long] point", source) if long else None,
        long_value=_text(long["value"], "[long] value", source) if long else None,
        air_density=_number(doc.get("air_density", DEFAULT_AIR_DENSITY), "air_density", source),
        step=_number(res["step"], "[resample] step", source) if "step" in res else None,
        max_gap=max_gap,
        hold_max_gap=(
            _number(res["hold_max_gap"], "[resample] hold_max_gap", source) if "hold_max_gap" in res else None
        ),
        night_start=check_clock(night.get("start", "18:00"), "[night] start", source),
        night_end=check_clock(night.get("end", "06:00"), "[night] end", source),
        na_values=tuple(na),
        min_samples=min_samples,
        name=str(doc.get("name", "")),
        ignored=ignored,
        source=source,
    )
    if cmap.start is not None and cmap.end is not None and not cmap.start < cmap.end:
        raise DataError(f"column map {source}: [time] start must be before end")
    return cmap


def default_column_map(
    columns: Sequence[str],
    source: str = "<data>",
    signals: Mapping[str, str] | None = None,
    required: Sequence[str] = (),
) -> ColumnMap:
    """The map used when none is given (the CLI's default layout).

    Without ``signals``: columns ``time`` (seconds or ISO 8601), ``Ti``, ``To``, ``Ts``, ``m``
    (kg/s), optionally ``Q`` (W; without it commands hold the paper's 50 W constant), and either
    ``Tsd`` or the five ``Tf``, ``Tc``, ``Tn1``, ``Tn2``, ``Thw``, all temperatures in degC. When
    ``Tsd`` is present it is used as is and any of the five
    also present are loaded as plain channels; otherwise Tsd is the mean of the five.

    With ``signals`` (channel name -> quantity, the signals of the model the data are for):
    ``time`` and every column named as one of the signals, in SI units; a model input the data
    lack is reported by the model (it may have a default), except the ``required`` ones, which
    are reported here with close names of the file's columns. An unnamed first column (a frame
    written with its index) is taken as the time.

    Raises
    ------
    DataError
        Naming every missing column, with close names from ``columns``.
    """
    present = [str(c) for c in columns]
    if signals is not None:
        time = "time"
        if "time" not in present and present and is_unnamed(present[0]):
            time = present[0]
        missing = [c for c in (time, *required) if c not in present]
        if missing:
            hints = "; ".join(f"{c!r}: {did_you_mean(c, present)}" for c in missing)
            raise DataError(
                f"{source}: missing column(s) {', '.join(repr(c) for c in missing)} that the model needs"
                f" ({hints}); rename them or give a column map"
            )
        channels = []
        for n, q in signals.items():
            if n in present and n != time:
                known = KNOWN_CHANNELS.get(n)
                role = known[1] if known is not None and known[0] == q else _ROLE_OF_QUANTITY[q]
                channels.append(Channel(n, n, None, SI_UNITS[q], q, role))
        if not channels:
            raise DataError(
                f"{source}: none of the model's signals ({', '.join(signals)}) is a column; rename the"
                " columns or give a column map"
            )
        return ColumnMap(channels=tuple(channels), time_column=time, source=source)
    required = ["time", "Ti", "To", "Ts", "m"]  # Q is optional: 50 W held constant
    if "Tsd" in present:
        required.append("Tsd")
    else:
        required += [s for s in DEFAULT_SURROUNDINGS]
    missing = [c for c in required if c not in present]
    if missing:
        hints = "; ".join(f"{c!r}: {did_you_mean(c, present)}" for c in missing)
        raise DataError(
            f"{source}: missing column(s) {', '.join(repr(c) for c in missing)} of the default layout"
            f" ({hints}); rename them or give a column map"
        )
    channels = [
        Channel(n, n, None, SI_UNITS[q], q, r) for n, (q, r) in KNOWN_CHANNELS.items() if n in present
    ]
    if "Tsd" in present:
        extra = [
            Channel(n, n, None, "degC", "temperature", "room") for n in DEFAULT_SURROUNDINGS if n in present
        ]
        return ColumnMap(channels=tuple(channels + extra), source=source)
    surround = [Channel(n, n, None, "degC", "temperature", "room") for n in DEFAULT_SURROUNDINGS]
    return ColumnMap(channels=tuple(channels + surround), surroundings=DEFAULT_SURROUNDINGS, source=source)
