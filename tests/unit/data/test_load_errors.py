"""Every kind of bad input is one DataError line naming what was wrong (table-driven)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.data import load_zone_data, parse_column_map, read_column_map
from rczone.errors import DataError

T0 = 1312322400.0  # 2011-08-02 22:00 UTC = 18:00 EDT


def good_frame(n: int = 8) -> pd.DataFrame:
    t = T0 + 300.0 * np.arange(n)
    ramp = np.linspace(0.0, 1.0, n)
    return pd.DataFrame(
        {
            "time": t,
            "Ti": 23.0 + ramp,
            "To": 28.0 - ramp,
            "Ts": 13.0 + ramp,
            "m": 0.1 + 0.0 * ramp,
            "Q": 50.0 + ramp,
            "Tsd": 23.5 + ramp,
        }
    )


def rename(col, new):
    return lambda f: f.rename(columns={col: new})


def setcell(col, row, value):
    def edit(f):
        f = f.astype({col: object}) if isinstance(value, str) else f
        f.loc[row, col] = value
        return f

    return edit


def setcol(col, values):
    def edit(f):
        f[col] = values
        return f

    return edit


def iso_times(strings):
    return setcol("time", strings)


FOUR = ["2011-08-02 18:00", "2011-08-02 18:05", "2011-08-02 18:10", "2011-08-02 18:15"]

# (id, edit of the good frame, column-map dict or None, expected message pattern)
FRAME_CASES = [
    ("missing column", rename("Ti", "Tii"), None, r"missing column\(s\) 'Ti'.*did you mean 'Tii'"),
    ("missing time column", rename("time", "Time"), None, r"missing column\(s\) 'time'.*did you mean 'Time'"),
    (
        "mapped column missing",
        lambda f: f,
        {"columns": {"Ti": "Tin"}},
        r"no column for channel 'Ti' 'Tin'; did you mean 'Ti'",
    ),
    (
        "duplicate timestamps",
        setcell("time", 3, T0 + 600.0),
        None,
        r"duplicate time stamp .* data rows 3 and 4",
    ),
    ("time goes backwards", setcell("time", 3, T0), None, r"go backwards at data row 4"),
    ("all-NaN column", setcol("Ts", np.nan), None, r"column 'Ts' \(channel 'Ts'\) has no values"),
    ("70 declared as degC", setcol("Ti", 70.0), None, r"'Ti' \(room temperature.*look like 'degF'"),
    ("kelvin declared as degC", setcol("To", 300.0), None, r"outdoor temperature.*look like 'K'"),
    (
        "negative flow",
        setcell("m", 2, -0.05),
        None,
        r"'m' \(zone air mass flow.*data row 3.*flows must be >= 0",
    ),
    (
        "L/s declared as m3/s",
        setcol("m", 90.0),
        {"columns": {"Ti": "Ti", "m": {"column": "m", "unit": "m3/s"}}},
        r"look like 'm3/h' or 'L/s' or 'cfm'",
    ),
    (
        "non-numeric value",
        setcell("Ti", 1, "Offline"),
        None,
        r"non-numeric value 'Offline' at data row 2.*na_values",
    ),
    ("too little data", lambda f: f.iloc[:5], {"min_samples": 10, "columns": {"Ti": "Ti"}}, r"only 5 sample"),
    ("empty table", lambda f: f.iloc[:0], None, r"no data rows"),
    (
        "bad time stamp",
        lambda f: f.iloc[:4].pipe(iso_times(["2011-08-02 18:00", "yesterday", *FOUR[2:]])),
        None,
        r"'yesterday' at data row 2 is not an ISO 8601",
    ),
    (
        "empty time stamp",
        lambda f: f.iloc[:4].pipe(iso_times([*FOUR[:3], None])),
        None,
        r"empty time stamp at data row 4",
    ),
    (
        "mixed offsets",
        lambda f: f.iloc[:4].pipe(iso_times([*FOUR[:2], "2011-08-02 18:10-04:00", "2011-08-02 18:15-04:00"])),
        None,
        r"mixes stamps with a UTC offset \(data rows 3, 4\) and without \(data rows 1, 2\)",
    ),
    (
        "nonexistent local time",
        lambda f: f.iloc[:3].pipe(iso_times(["2011-03-13 01:30", "2011-03-13 02:30", "2011-03-13 03:30"])),
        {"time": {"timezone": "America/New_York"}, "columns": {"Ti": "Ti"}},
        r"2011-03-13 02:30:00 at data row 2 does not exist in America/New_York",
    ),
    (
        "ambiguous local time refused",
        lambda f: f.iloc[:3].pipe(iso_times(["2011-11-06 00:30", "2011-11-06 01:30", "2011-11-06 02:30"])),
        {"time": {"timezone": "America/New_York", "ambiguous": "raise"}, "columns": {"Ti": "Ti"}},
        r"2011-11-06 01:30:00 at data row 2 is ambiguous",
    ),
    (
        "ambiguous local time not inferable",
        lambda f: f.iloc[:3].pipe(iso_times(["2011-11-06 00:30", "2011-11-06 01:30", "2011-11-06 02:30"])),
        {"time": {"timezone": "America/New_York"}, "columns": {"Ti": "Ti"}},
        r"cannot tell which of the repeated local times at data row 2",
    ),
    (
        "only constants",
        lambda f: f,
        {"columns": {"Q": {"value": 50}}},
        r"only constants; map at least one column",
    ),
    (
        "implausible constant",
        lambda f: f,
        {"columns": {"Ti": "Ti", "m": {"value": -1.0}}},
        r"column 'm' \(zone air mass flow.*flows must be >= 0",
    ),
    (
        "unknown unit",
        lambda f: f,
        {"columns": {"Ti": {"column": "Ti", "unit": "degG"}}},
        r"column 'Ti': unknown temperature unit 'degG'; known units: degC, degF, K; did you mean",
    ),
    (
        "unknown flow unit",
        lambda f: f,
        {"columns": {"m": {"column": "m", "unit": "cmf"}}},
        r"unknown flow unit 'cmf'; known units: kg/s, m3/s, m3/h, L/s, cfm; did you mean 'cfm'",
    ),
]


@pytest.mark.parametrize(
    ("edit", "doc", "pattern"), [c[1:] for c in FRAME_CASES], ids=[c[0] for c in FRAME_CASES]
)
def test_bad_frame(tmp_path, edit, doc, pattern):
    frame = edit(good_frame())
    path = tmp_path / "zone.csv"
    frame.to_csv(path, index=False)
    with pytest.raises(DataError, match=pattern):
        cmap = parse_column_map(doc) if doc is not None else None
        load_zone_data(path, cmap)


LONG = {"long": {"point": "Point", "value": "Value"}, "columns": {"Ti": "RM241.ZN-T", "To": "OA-T"}}


def long_frame() -> pd.DataFrame:
    t = T0 + 300.0 * np.arange(4)
    return pd.DataFrame(
        {
            "time": np.r_[t, t],
            "Point": ["RM241.ZN-T"] * 4 + ["OA-T"] * 4,
            "Value": np.r_[[22.0] * 4, [30.0] * 4],
        }
    )


LONG_CASES = [
    (
        "missing point",
        {**LONG, "columns": {"Ti": "RM241.ZN-T", "To": "OAT"}},
        lambda f: f,
        r"no point 'OAT' \(channel 'To'\) in column 'Point'; did you mean 'OA-T'",
    ),
    (
        "duplicate point/time",
        LONG,
        lambda f: pd.concat([f, f.iloc[[1]]], ignore_index=True),
        r"duplicate time stamp .*point 'RM241.ZN-T'.* data rows 2 and 9",
    ),
    (
        "missing value column",
        {**LONG, "long": {"point": "Point", "value": "Val"}},
        lambda f: f,
        r"no value column 'Val'; did you mean 'Value'",
    ),
    ("bad value", LONG, setcell("Value", 6, "n/a?"), r"non-numeric value 'n/a\?' at data row 7"),
]


@pytest.mark.parametrize(
    ("doc", "edit", "pattern"), [c[1:] for c in LONG_CASES], ids=[c[0] for c in LONG_CASES]
)
def test_bad_long_log(tmp_path, doc, edit, pattern):
    path = tmp_path / "long.csv"
    edit(long_frame()).to_csv(path, index=False)
    with pytest.raises(DataError, match=pattern):
        load_zone_data(path, parse_column_map(doc))


def test_unknown_file_type(tmp_path):
    path = tmp_path / "zone.xlsx"
    path.write_text("x")
    with pytest.raises(DataError, match=r"unknown file type; expected one of .csv"):
        load_zone_data(path)


def test_unreadable_parquet(tmp_path):
    path = tmp_path / "zone.parquet"
    path.write_text("not parquet")
    with pytest.raises(DataError, match=r"cannot read the table"):
        load_zone_data(path)


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_zone_data(tmp_path / "nope.csv")


def test_na_values_from_map_are_missing_not_errors(tmp_path):
    frame = setcell("Ti", 1, "Offline")(good_frame())
    frame.to_csv(tmp_path / "z.csv", index=False)
    toml = tmp_path / "m.toml"
    toml.write_text('na_values = ["Offline"]\n[columns]\nTi = "Ti"\n')
    with pytest.warns(UserWarning, match=r"channel 'Ti' has 1 gap"):
        data = load_zone_data(tmp_path / "z.csv", toml)
    assert np.isnan(data.channel("Ti")[1]) and np.isfinite(data.channel("Ti")[[0, 2]]).all()
    assert read_column_map(toml).na_values == ("Offline",)


ARRAY_CASES = [
    (
        "unknown input",
        dict(input_names=("To", "Tsdd")),
        r"channel 'Tsdd' is not in the data.*did you mean 'Tsd'",
    ),
    ("unknown flow", dict(input_names=("To",), flow_names=("mm",)), r"channel 'mm'.*did you mean 'm'"),
    ("unknown output", dict(input_names=("To",), output="Tin"), r"channel 'Tin'.*did you mean 'Ti'"),
    (
        "too few samples",
        dict(input_names=("To",), min_samples=50),
        r"only 8 samples, the model needs at least 50",
    ),
    (
        "missing values",
        dict(input_names=("To", "Ts")),
        r"channel 'Ts' has 1 missing sample\(s\), first at 2011-08-02T18:10",
    ),
]


@pytest.mark.parametrize("kwargs,pattern", [c[1:] for c in ARRAY_CASES], ids=[c[0] for c in ARRAY_CASES])
def test_bad_arrays_request(tmp_path, kwargs, pattern):
    frame = setcell("Ts", 2, np.nan)(good_frame())
    frame.to_csv(tmp_path / "z.csv", index=False)
    cmap = parse_column_map(
        {
            "time": {"timezone": "America/New_York"},
            "columns": {n: n for n in ("Ti", "To", "Ts", "m", "Q", "Tsd")},
        }
    )
    with pytest.warns(UserWarning):
        data = load_zone_data(tmp_path / "z.csv", cmap)
    with pytest.raises(DataError, match=pattern):
        data.arrays(**kwargs)
