"""Time stamps to UTC epoch seconds, with the daylight-saving policies."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pytest

from rczone.data.timestamps import parse_times


def utc(*args) -> float:
    return dt.datetime(*args, tzinfo=dt.UTC).timestamp()


NY = "America/New_York"
FALL = pd.Series(
    [
        "2011-11-06 00:30",
        "2011-11-06 01:00",
        "2011-11-06 01:30",
        "2011-11-06 01:00",
        "2011-11-06 01:30",
        "2011-11-06 02:00",
    ]
)


def test_infer_uses_row_order():
    t, keep, notes = parse_times(FALL, tz=NY, ambiguous="infer")
    assert keep.all() and notes == []
    np.testing.assert_array_equal(t, [utc(2011, 11, 6, 4, 30) + 1800.0 * k for k in range(6)])


@pytest.mark.parametrize(("policy", "hour"), [("first", 5), ("second", 6)])
def test_first_and_second(policy, hour):
    t, _, _ = parse_times(pd.Series(["2011-11-06 01:30"]), tz=NY, ambiguous=policy)
    assert t[0] == utc(2011, 11, 6, hour, 30)


def test_drop_ambiguous_rows():
    t, keep, notes = parse_times(FALL, tz=NY, ambiguous="drop")
    np.testing.assert_array_equal(keep, [True, False, False, False, False, True])
    np.testing.assert_array_equal(t, [utc(2011, 11, 6, 4, 30), utc(2011, 11, 6, 7)])
    assert "dropped 4 ambiguous" in notes[0] and "data rows 2, 3, 4, 5" in notes[0]


SPRING = pd.Series(["2011-03-13 01:30", "2011-03-13 02:30", "2011-03-13 03:30"])


def test_nonexistent_shift_forward_and_drop():
    t, _, _ = parse_times(SPRING, tz=NY, nonexistent="shift_forward")
    np.testing.assert_array_equal(t, [utc(2011, 3, 13, 6, 30), utc(2011, 3, 13, 7), utc(2011, 3, 13, 7, 30)])
    t, keep, notes = parse_times(SPRING, tz=NY, nonexistent="drop")
    np.testing.assert_array_equal(keep, [True, False, True])
    np.testing.assert_array_equal(t, [utc(2011, 3, 13, 6, 30), utc(2011, 3, 13, 7, 30)])
    assert "do not exist" in notes[0]


def test_offsets_seconds_and_aware_datetimes():
    s = pd.Series(["2011-11-06T01:30:00-04:00", "2011-11-06T01:30:00-05:00", "2011-11-06T07:00:00Z"])
    t, _, _ = parse_times(s, tz=NY)
    np.testing.assert_array_equal(t, [utc(2011, 11, 6, 5, 30), utc(2011, 11, 6, 6, 30), utc(2011, 11, 6, 7)])
    t, _, _ = parse_times(pd.Series([0, 300, 600]))
    np.testing.assert_array_equal(t, [0.0, 300.0, 600.0])
    t, _, _ = parse_times(pd.Series(["0", "300.5"]))  # numbers written as text
    np.testing.assert_array_equal(t, [0.0, 300.5])
    aware = pd.Series(pd.to_datetime(["2011-08-02 18:00"]).tz_localize("Europe/Berlin"))
    t, _, _ = parse_times(aware, tz=NY)  # its own zone wins over the map's
    assert t[0] == utc(2011, 8, 2, 16)


def test_naive_utc_default():
    t, _, _ = parse_times(pd.Series(["2011-08-02T18:00:00"]))
    assert t[0] == utc(2011, 8, 2, 18)


def test_datetimes_declared_as_seconds_are_refused():
    from rczone.errors import DataError

    with pytest.raises(DataError, match=r"holds date-times, not seconds"):
        parse_times(pd.Series(pd.to_datetime(["2011-08-02 18:00"])), fmt="seconds")
