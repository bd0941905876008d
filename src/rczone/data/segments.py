"""Time segments of a record: night windows, constant-flow stretches, gap-free stretches.

A :class:`Segment` is a closed interval ``[start, end]`` of UTC epoch seconds; selecting
it keeps the samples with ``start <= t <= end``.

Night windows
    For every local calendar day ``d`` the window runs from ``start`` on ``d`` to ``end``
    on ``d + 1`` when ``end <= start`` (the default 18:00 to 06:00 crosses midnight),
    else from ``start`` to ``end`` on ``d``. Both ends are local wall-clock times in the
    record's time zone, converted to UTC with :mod:`zoneinfo`, so a night in which
    daylight saving ends lasts 13 h and one in which it starts 11 h. (A wall-clock time
    that does not exist is read with the offset before the change, PEP 495 ``fold=0``.)
    Windows are clipped to the record and empty ones are dropped.

Constant-flow stretches
    A greedy left-to-right scan: a stretch grows while ``max(m) - min(m) <= tolerance``
    over its samples and no sample is NaN; when the next sample breaks it, the stretch
    is kept if it lasts at least ``min_duration`` seconds (first to last sample) and a
    new one starts at the breaking sample. On such a stretch the model is LTI (Lin et al. 2012,
    eq. (5)).

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

import datetime as dt
import zoneinfo
from dataclasses import dataclass

import numpy as np

from rczone.errors import DataError


@dataclass(frozen=True)
class Segment:
    """A closed time interval ``[start, end]`` in UTC epoch seconds."""

    start: float
    end: float

    @property
    def duration(self) -> float:
        """Length (s)."""
        return self.end - self.start

    def mask(self, t: np.ndarray) -> np.ndarray:
        """Boolean mask of the times ``t`` inside the segment."""
        t = np.asarray(t, dtype=float)
        return (t >= self.start) & (t <= self.end)


def _clock(text: str) -> dt.time:
    try:
        h, m = (int(p) for p in text.split(":"))
        return dt.time(h, m)
    except ValueError:
        raise DataError(f"night window time must be 'HH:MM', got {text!r}") from None


def night_segments(
    t_first: float, t_last: float, tz: str, start: str = "18:00", end: str = "06:00"
) -> list[Segment]:
    """Night windows (local wall-clock ``start`` to ``end``) overlapping ``[t_first, t_last]``.

    Parameters
    ----------
    t_first, t_last : float
        Record span, UTC epoch seconds.
    tz : str
        IANA time zone of the wall clock.
    start, end : str
        Local clock times ``"HH:MM"``.

    Returns
    -------
    list of Segment
        Clipped to the record, in time order.
    """
    zone = zoneinfo.ZoneInfo(tz)
    s_clock, e_clock = _clock(start), _clock(end)
    crosses = e_clock <= s_clock
    d0 = dt.datetime.fromtimestamp(t_first, zone).date() - dt.timedelta(days=1)
    d1 = dt.datetime.fromtimestamp(t_last, zone).date()
    out = []
    day = d0
    while day <= d1:
        a = dt.datetime.combine(day, s_clock, tzinfo=zone).timestamp()
        e_day = day + dt.timedelta(days=1) if crosses else day
        b = dt.datetime.combine(e_day, e_clock, tzinfo=zone).timestamp()
        lo, hi = max(a, t_first), min(b, t_last)
        if hi > lo:
            out.append(Segment(lo, hi))
        day += dt.timedelta(days=1)
    return out


def constant_segments(t: np.ndarray, x: np.ndarray, tolerance: float, min_duration: float) -> list[Segment]:
    """Stretches where ``x`` stays within a band of width ``tolerance`` (see module docstring).

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times (s).
    x : ndarray, shape (N,)
        Signal, e.g. the supply mass flow (kg/s).
    tolerance : float
        Allowed ``max - min`` within a stretch, in the unit of ``x``.
    min_duration : float
        Shortest stretch kept (s).

    Returns
    -------
    list of Segment
    """
    if tolerance < 0 or min_duration < 0:
        raise DataError(f"tolerance and min_duration must be >= 0, got {tolerance!r}, {min_duration!r}")
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    out = []
    n = x.size
    k = 0
    while k < n:
        if not np.isfinite(x[k]):
            k += 1
            continue
        lo = hi = x[k]
        j = k + 1
        while j < n and np.isfinite(x[j]):
            lo2, hi2 = min(lo, x[j]), max(hi, x[j])
            if hi2 - lo2 > tolerance:
                break
            lo, hi = lo2, hi2
            j += 1
        if t[j - 1] - t[k] >= min_duration and j - 1 > k:
            out.append(Segment(float(t[k]), float(t[j - 1])))
        k = j
    return out


def finite_segments(
    t: np.ndarray, values: np.ndarray, min_duration: float = 0.0, max_step: float | None = None
) -> list[Segment]:
    """Stretches where every column of ``values`` (shape (N, k)) is finite.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times (s).
    values : ndarray, shape (N, k)
        Channels that must all be finite.
    min_duration : float
        Shortest stretch kept (s).
    max_step : float or None
        A time step longer than this also ends a stretch (a hole in the time stamps).

    Returns
    -------
    list of Segment
    """
    t = np.asarray(t, dtype=float)
    ok = np.all(np.isfinite(np.asarray(values, dtype=float).reshape(t.size, -1)), axis=1)
    breaks = np.zeros(t.size, dtype=bool)
    if max_step is not None and t.size > 1:
        breaks[1:] = np.diff(t) > max_step
    out = []
    k = 0
    while k < t.size:
        if not ok[k]:
            k += 1
            continue
        j = k + 1
        while j < t.size and ok[j] and not breaks[j]:
            j += 1
        if j - 1 > k and t[j - 1] - t[k] >= min_duration:
            out.append(Segment(float(t[k]), float(t[j - 1])))
        k = j
    return out


def intersect(a: list[Segment], b: list[Segment]) -> list[Segment]:
    """Pairwise intersections of two segment lists (each sorted and non-overlapping)."""
    out = []
    i = j = 0
    while i < len(a) and j < len(b):
        lo, hi = max(a[i].start, b[j].start), min(a[i].end, b[j].end)
        if hi > lo:
            out.append(Segment(lo, hi))
        if a[i].end < b[j].end:
            i += 1
        else:
            j += 1
    return out
