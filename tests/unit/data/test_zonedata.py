"""ZoneData behaviour and the loader's resampling, gaps and warnings on known signals."""

from __future__ import annotations

import dataclasses
import datetime as dt
import warnings

import numpy as np
import pandas as pd
import pytest

from rczone.data import RczoneWarning, Segment, load_zone_data, parse_column_map, zone_data_from_frame
from rczone.data.quality import find_gaps, longest_flat_run
from rczone.errors import DataError

T0 = dt.datetime(2011, 11, 5, 12, tzinfo=dt.UTC).timestamp()  # New York: DST ends 6 Nov 06:00 UTC
CFM = 0.3048**3 / 60.0


def test_unaligned_long_log_is_resampled_exactly(tmp_path):
    """Two temperatures on their own irregular clocks and a change-of-value flow log -> grid."""
    rng = np.random.default_rng(11)
    t_ti = T0 + np.sort(rng.uniform(0, 86400, 300))
    t_to = T0 + np.sort(rng.uniform(0, 86400, 200))
    t_m = np.array([T0, T0 + 3000.0, T0 + 50000.0])
    ti = lambda t: 20.0 + 1e-5 * (t - T0)  # noqa: E731 - linear signals are reproduced exactly
    to = lambda t: 5.0 - 2e-5 * (t - T0)  # noqa: E731
    m_cmd = np.array([0.12, 0.06, 0.09])
    offset = lambda t: [dt.datetime.fromtimestamp(x, dt.UTC).isoformat() for x in t]  # noqa: E731
    frame = pd.concat(
        [
            pd.DataFrame({"ts": offset(t_ti), "pt": "ZN-T", "v": ti(t_ti) * 1.8 + 32}),
            pd.DataFrame({"ts": offset(t_to), "pt": "OA-T", "v": to(t_to) * 1.8 + 32}),
            pd.DataFrame({"ts": offset(t_m), "pt": "SA-F", "v": m_cmd / 1.2 / CFM}),
        ]
    )
    frame.to_csv(tmp_path / "long.csv", index=False)
    cmap = parse_column_map(
        {
            "time": {"column": "ts", "timezone": "America/New_York"},
            "long": {"point": "pt", "value": "v"},
            "columns": {
                "Ti": {"column": "ZN-T", "unit": "degF"},
                "To": {"column": "OA-T", "unit": "degF"},
                "m": {"column": "SA-F", "unit": "cfm"},
            },
            "resample": {"step": 300, "max_gap": 3600, "hold_max_gap": 86400},
        }
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RczoneWarning)  # edges before a channel's first sample are gaps
        data = load_zone_data(tmp_path / "long.csv", cmap)
    assert data.step == 300.0 and data.is_uniform and np.all(data.t % 300 == 0)
    inside = (data.t >= max(t_ti[0], t_to[0])) & (data.t <= min(t_ti[-1], t_to[-1]))
    np.testing.assert_allclose(data.channel("Ti")[inside], ti(data.t[inside]), rtol=0, atol=1e-9)
    np.testing.assert_allclose(data.channel("To")[inside], to(data.t[inside]), rtol=0, atol=1e-9)
    expected_m = np.select([data.t < T0 + 3000, data.t < T0 + 50000], [0.12, 0.06], 0.09)
    ok = data.t <= t_m[-1]  # nothing is held past the last flow sample
    np.testing.assert_allclose(data.channel("m")[ok], expected_m[ok], rtol=0, atol=1e-12)
    assert np.isnan(data.channel("m")[~ok]).all()


def good(n=40, step=600.0):
    t = T0 + step * np.arange(n)
    return pd.DataFrame(
        {
            "time": t,
            "Ti": 22 + 0.01 * np.arange(n),
            "To": 5 + 0.02 * np.arange(n),
            "m": np.where(np.arange(n) < 20, 0.1, 0.05),
        }
    )


CMAP = parse_column_map(
    {
        "time": {"timezone": "America/New_York"},
        "columns": {"Ti": "Ti", "To": "To", "m": "m"},
        "resample": {"max_gap": 900},
    }
)


def test_gaps_are_listed_and_warned():
    frame = good()
    frame.loc[5:9, "Ti"] = np.nan
    frame = frame.drop(index=range(30, 33))  # a 40-min hole in the time stamps: longer than max_gap
    with pytest.warns(RczoneWarning) as record:
        data = zone_data_from_frame(frame, CMAP, source="z")
    messages = [str(w.message) for w in record]
    assert any(
        "channel 'Ti' has 2 gap(s), longest 1 h from 2011-11-05T08:40:00-04:00 to 2011-11-05T09:40:00-04:00"
        in m
        for m in messages
    )
    ti_gaps = [g for g in data.gaps if g.channel == "Ti"]
    assert [(g.start - T0, g.end - T0, g.n_missing) for g in ti_gaps] == [
        (2400.0, 6000.0, 5),
        (17400.0, 19800.0, 0),
    ]
    assert not any("irregular" in m for m in messages)  # a hole is a gap, not irregular sampling
    assert data.warnings == tuple(messages)
    with pytest.raises(DataError, match="channel 'Ti' has 5 missing sample"):
        data.arrays(("To",), ("m",))
    *_, y = data.arrays(("To",), ("m",), allow_nan=True)
    assert np.isnan(y[5:10, 0]).all()
    (longest, *_) = sorted(data.complete_segments(["Ti", "To", "m"]), key=lambda s: -s.duration)
    assert (longest.start - T0, longest.end - T0) == (6000.0, 17400.0)


def test_automatic_gap_threshold_follows_the_sampling():
    """Default max_gap = max(1800 s, 3 median steps): hourly logs are not all gaps, holes still are."""
    cmap = parse_column_map({"columns": {"Ti": "Ti", "Q": {"value": 50}}})
    hourly = good(n=48, step=3600.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RczoneWarning)
        data = zone_data_from_frame(hourly, cmap)
    assert data.gaps == () and data.max_gaps["Ti"] == 3 * 3600.0 and data.max_gaps["Q"] == np.inf
    minutes = good(n=300, step=60.0).drop(index=range(100, 140))  # a 41-min hole
    with pytest.warns(RczoneWarning, match=r"channel 'Ti' has 1 gap\(s\), longest 0.683 h"):
        data = zone_data_from_frame(minutes, cmap)
    assert data.max_gaps["Ti"] == 1800.0
    assert [(g.start - T0, g.end - T0) for g in data.gaps] == [(99 * 60.0, 140 * 60.0)]


def test_irregular_sampling_is_warned():
    frame = good(n=20)
    frame["time"] = T0 + np.cumsum(np.r_[0.0, np.tile([300.0, 600.0], 10)[:19]])
    with pytest.warns(RczoneWarning, match=r"sampling is irregular \(time steps from 300 s to 600 s\)"):
        data = zone_data_from_frame(frame, CMAP)
    assert not data.is_uniform


def test_flat_sensor_warning_and_strict_mode():
    frame = good(n=60)
    frame["To"] = 7.25  # frozen for 9 h 50 min
    with pytest.warns(
        RczoneWarning, match=r"channel 'To' \(column 'To'\) stays exactly at 7.25 degC for 9.83 h"
    ):
        zone_data_from_frame(frame, CMAP)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RczoneWarning)
        with pytest.raises(RczoneWarning):
            zone_data_from_frame(frame, CMAP)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RczoneWarning)
        zone_data_from_frame(frame, CMAP, flat_seconds=86400.0)  # threshold is configurable
        zone_data_from_frame(good(n=60), CMAP)  # constant flow is not a flat sensor


def test_dropped_dst_rows_are_warned():
    frame = pd.DataFrame(
        {"time": ["2011-11-06 00:30", "2011-11-06 01:30", "2011-11-06 02:30"], "Ti": [21.0] * 3}
    )
    cmap = parse_column_map(
        {
            "time": {"timezone": "America/New_York", "ambiguous": "drop"},
            "columns": {"Ti": "Ti"},
            "resample": {"max_gap": 20000},
        }
    )
    with pytest.warns(RczoneWarning, match=r"dropped 1 ambiguous local time stamp\(s\) .*data row 2"):
        data = zone_data_from_frame(frame, cmap)
    assert len(data) == 2


def test_zone_data_is_immutable_and_select_returns_a_new_one():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RczoneWarning)
        data = zone_data_from_frame(good(n=150), CMAP)  # 12:00 UTC 5 Nov to 12:50 UTC 6 Nov 2011
    with pytest.raises(ValueError, match="read-only"):
        data.values[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        data.step = 5.0
    with pytest.raises(TypeError):
        data.units["Ti"] = "K"
    t, *_ = data.arrays(("To",))
    t[0] = -1.0  # arrays() returns copies
    assert data.t[0] == T0
    # 18:00 EDT = 22:00 UTC on 5 Nov to 06:00 EST = 11:00 UTC on 6 Nov: 13 h
    assert data.nights() == [Segment(T0 + 10 * 3600, T0 + 23 * 3600)]
    night = data.select(data.nights()[0])
    assert len(night) == 13 * 6 + 1 and night.t[0] == T0 + 36000 and night.t[-1] == T0 + 23 * 3600
    assert len(data) == 150  # unchanged
    stretches = data.constant_flow_segments(tolerance=1e-6, min_duration=3000.0)
    assert stretches == [Segment(T0, T0 + 19 * 600), Segment(T0 + 20 * 600, T0 + 149 * 600)]
    frame = data.to_frame()
    assert list(frame.columns) == ["time", "Ti", "To", "m"]
    np.testing.assert_array_equal(frame["time"], data.t)
    assert str(data.times()[0]) == "2011-11-05 08:00:00-04:00"
    assert "150 samples" in repr(data)


def test_quality_helpers_on_known_cases():
    t = np.arange(8.0)
    x = np.array([np.nan, 1.0, 2.0, np.nan, np.nan, 3.0, 3.0, np.nan])
    gaps = [(g.start, g.end, g.n_missing) for g in find_gaps(t, x, "x", max_gap=1.5)]
    assert gaps == [(0.0, 1.0, 1), (2.0, 5.0, 2), (6.0, 7.0, 1)]
    assert [(g.start, g.end) for g in find_gaps(np.array([0.0, 1.0, 5.0]), np.ones(3), "x", 2.0)] == [
        (1.0, 5.0)
    ]
    assert find_gaps(t, np.full(8, np.nan), "x", 1.0)[0].n_missing == 8
    assert longest_flat_run(np.array([0.0, 1.0, 3.0, 4.0, 9.0]), np.array([1.0, 2.0, 2.0, 2.0, 5.0])) == (
        3.0,
        1.0,
        4.0,
    )
