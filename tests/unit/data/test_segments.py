"""Night windows across midnight and daylight-saving changes; constant-flow stretches."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from rczone.data.segments import Segment, constant_segments, finite_segments, intersect, night_segments


def utc(*args) -> float:
    return dt.datetime(*args, tzinfo=dt.UTC).timestamp()


NIGHTS = [
    # (tz, record start, record end (UTC), expected windows (UTC)) -- offsets from the tz rules:
    # New York EDT = UTC-4, EST = UTC-5 (2011: DST 13 Mar 02:00 -> 6 Nov 02:00); Berlin CEST = UTC+2,
    # CET = UTC+1 (2011: DST ends 30 Oct 03:00).
    (
        "America/New_York",
        utc(2011, 8, 2, 12),
        utc(2011, 8, 3, 12),
        [(utc(2011, 8, 2, 22), utc(2011, 8, 3, 10))],
    ),
    (
        "America/New_York",
        utc(2011, 11, 5, 12),
        utc(2011, 11, 6, 12),
        [(utc(2011, 11, 5, 22), utc(2011, 11, 6, 11))],
    ),
    (
        "America/New_York",
        utc(2011, 3, 12, 12),
        utc(2011, 3, 13, 12),
        [(utc(2011, 3, 12, 23), utc(2011, 3, 13, 10))],
    ),
    (
        "Europe/Berlin",
        utc(2011, 10, 29, 12),
        utc(2011, 10, 30, 12),
        [(utc(2011, 10, 29, 16), utc(2011, 10, 30, 5))],
    ),
    # record starting and ending inside nights: clipped, two windows
    (
        "America/New_York",
        utc(2011, 8, 3, 2),
        utc(2011, 8, 4, 3),
        [(utc(2011, 8, 3, 2), utc(2011, 8, 3, 10)), (utc(2011, 8, 3, 22), utc(2011, 8, 4, 3))],
    ),
    (
        "UTC",
        utc(2011, 1, 1, 0),
        utc(2011, 1, 3, 0),
        [
            (utc(2011, 1, 1, 0), utc(2011, 1, 1, 6)),
            (utc(2011, 1, 1, 18), utc(2011, 1, 2, 6)),
            (utc(2011, 1, 2, 18), utc(2011, 1, 3, 0)),
        ],
    ),
]


@pytest.mark.parametrize(("tz", "t0", "t1", "expected"), NIGHTS)
def test_night_windows(tz, t0, t1, expected):
    assert night_segments(t0, t1, tz) == [Segment(a, b) for a, b in expected]


def test_night_lengths_at_dst_changes():
    (fall,) = night_segments(utc(2011, 11, 5, 12), utc(2011, 11, 6, 12), "America/New_York")
    (spring,) = night_segments(utc(2011, 3, 12, 12), utc(2011, 3, 13, 12), "America/New_York")
    assert (fall.duration, spring.duration) == (13 * 3600.0, 11 * 3600.0)


def test_window_within_one_day():
    got = night_segments(utc(2011, 8, 2, 0), utc(2011, 8, 3, 0), "America/New_York", "01:00", "05:00")
    assert got == [Segment(utc(2011, 8, 2, 5), utc(2011, 8, 2, 9))]


def test_constant_flow_stretches():
    step = 60.0
    t = step * np.arange(400)
    m = np.empty(t.size)
    m[:120] = 0.12  # 0 .. 7140 s
    m[120:150] = 0.04  # 30 min: shorter than min_duration
    m[150:400] = 0.08  # 9000 .. 23940 s
    noise = np.random.default_rng(1).uniform(-4e-4, 4e-4, t.size)
    m = m + noise
    m[300] = np.nan  # a missing sample splits the last stretch
    got = constant_segments(t, m, tolerance=1e-3, min_duration=3600.0)
    assert got == [Segment(0.0, 7140.0), Segment(9000.0, 17940.0), Segment(18060.0, 23940.0)]
    assert constant_segments(t, m, tolerance=1e-3, min_duration=8000.0) == [Segment(9000.0, 17940.0)]


def test_constant_segments_reject_negative_tolerance():
    from rczone.errors import DataError

    with pytest.raises(DataError, match="tolerance and min_duration must be >= 0"):
        constant_segments(np.arange(3.0), np.ones(3), -1.0, 0.0)


def test_finite_segments_and_intersection():
    t = np.arange(10.0)
    x = np.c_[np.ones(10), np.ones(10)]
    x[3, 0] = np.nan
    x[7, 1] = np.nan
    assert finite_segments(t, x) == [Segment(0.0, 2.0), Segment(4.0, 6.0), Segment(8.0, 9.0)]
    assert finite_segments(t, x, min_duration=2.0) == [Segment(0.0, 2.0), Segment(4.0, 6.0)]
    tt = np.r_[0.0, 1.0, 2.0, 6.0, 7.0]
    assert finite_segments(tt, np.ones(5), max_step=2.0) == [Segment(0.0, 2.0), Segment(6.0, 7.0)]
    a = [Segment(0.0, 5.0), Segment(7.0, 9.0)]
    b = [Segment(1.0, 8.0)]
    assert intersect(a, b) == [Segment(1.0, 5.0), Segment(7.0, 8.0)]
    assert Segment(1.0, 5.0).mask(t).sum() == 5
