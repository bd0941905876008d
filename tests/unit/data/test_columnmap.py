"""Column map: a valid TOML map is read as written; every bad setting is a clear DataError."""

from __future__ import annotations

import textwrap

import pytest

from rczone.data import default_column_map, parse_column_map, read_column_map
from rczone.data.columnmap import DEFAULT_SURROUNDINGS
from rczone.errors import DataError

FULL = """
name = "Pugh Hall 241"
air_density = 1.18
na_values = ["Offline"]
min_samples = 12

[time]
column = "Timestamp"
format = "iso"
timezone = "America/New_York"
ambiguous = "second"
nonexistent = "shift_forward"

[long]
point = "PointName"
value = "Value"

[columns]
Ti = { column = "RM241.ZN-T", unit = "degF" }
m = { column = "RM241.SA-F", unit = "CFM" }
Q = { value = 50 }
m2 = { column = "VAV2", unit = "l/s", quantity = "flow" }

[surroundings]
Tf = { column = "RM141.ZN-T", unit = "°F" }
Thw = "HALL"

[resample]
step = 300
max_gap = 900
hold_max_gap = 7200

[night]
start = "19:30"
end = "05:00"
"""


def test_full_map_is_read_as_written(tmp_path):
    path = tmp_path / "map.toml"
    path.write_text(FULL)
    cmap = read_column_map(path)
    assert (cmap.name, cmap.air_density, cmap.na_values, cmap.min_samples) == (
        "Pugh Hall 241",
        1.18,
        ("Offline",),
        12,
    )
    assert (cmap.time_column, cmap.time_format, cmap.timezone) == ("Timestamp", "iso", "America/New_York")
    assert (cmap.ambiguous, cmap.nonexistent) == ("second", "shift_forward")
    assert cmap.is_long and (cmap.long_point, cmap.long_value) == ("PointName", "Value")
    assert (cmap.step, cmap.max_gap, cmap.hold_max_gap) == (300.0, 900.0, 7200.0)
    assert (cmap.night_start, cmap.night_end) == ("19:30", "05:00")
    assert cmap.channel_names == ("Ti", "m", "Q", "m2", "Tf", "Thw")
    assert cmap.surroundings == ("Tf", "Thw")
    ti, m, q, m2, tf, thw = cmap.channels
    assert (ti.column, ti.unit, ti.quantity, ti.role) == ("RM241.ZN-T", "degF", "temperature", "room")
    assert (m.unit, m.quantity) == ("cfm", "flow")  # spelling normalized
    assert (q.column, q.value, q.unit) == (None, 50.0, "W")  # SI default unit
    assert (m2.unit, m2.quantity, m2.role) == ("L/s", "flow", "flow")
    assert (tf.unit, thw.column, thw.unit) == ("degF", "HALL", "degC")


def test_defaults_of_a_minimal_map():
    cmap = parse_column_map({"columns": {"Ti": "T"}})
    assert (cmap.time_column, cmap.time_format, cmap.timezone) == ("time", "auto", "UTC")
    assert (cmap.ambiguous, cmap.nonexistent, cmap.step, cmap.max_gap) == ("infer", "raise", None, None)
    assert (cmap.night_start, cmap.night_end, cmap.air_density) == ("18:00", "06:00", 1.2)
    assert not cmap.is_long


def test_default_layout_with_five_surroundings_and_with_tsd():
    cols = ["time", "Ti", "To", "Ts", "m", "Q", *DEFAULT_SURROUNDINGS]
    cmap = default_column_map(cols)
    assert cmap.surroundings == DEFAULT_SURROUNDINGS
    cmap = default_column_map(["time", "Ti", "To", "Ts", "m", "Q", "Tsd", "Tf"])
    assert cmap.surroundings == () and set(cmap.channel_names) == {"Ti", "To", "Ts", "m", "Q", "Tsd", "Tf"}


BAD_MAPS = [
    (
        "unknown section key",
        {"columns": {"Ti": "a"}, "time": {"timezon": "UTC"}},
        r"unknown key 'timezon' in \[time\]; did you mean 'timezone'",
    ),
    (
        "unknown top key",
        {"columns": {"Ti": "a"}, "colums": {}},
        r"unknown key 'colums' in the top level; did you mean 'columns'",
    ),
    (
        "unknown time zone",
        {"columns": {"Ti": "a"}, "time": {"timezone": "America/NewYork"}},
        r"unknown time zone 'America/NewYork'; did you mean 'America/New_York'",
    ),
    (
        "unknown channel",
        {"columns": {"Tii": "a"}},
        r"unknown channel 'Tii' in \[columns\] \(a typo of 'Ti'\?\)",
    ),
    (
        "unknown channel key",
        {"columns": {"Ti": {"colum": "a"}}},
        r"unknown key 'colum' in \[columns\].Ti; did you mean 'column'",
    ),
    (
        "column and value",
        {"columns": {"Ti": {"column": "a", "value": 3}}},
        r"needs exactly one of 'column', 'expr' or 'value', got column and value",
    ),
    (
        "Tsd and surroundings",
        {"columns": {"Ti": "a", "Tsd": "b"}, "surroundings": {"Tf": "c"}},
        r"either Tsd .* not both",
    ),
    ("no columns", {"time": {"timezone": "UTC"}}, r"missing the \[columns\] table"),
    ("empty columns", {"columns": {}}, r"\[columns\] is empty"),
    (
        "half long",
        {"columns": {"Ti": "a"}, "long": {"point": "p"}},
        r"\[long\] needs both 'point' and 'value'",
    ),
    (
        "negative step",
        {"columns": {"Ti": "a"}, "resample": {"step": -5}},
        r"\[resample\] step must be > 0, got -5",
    ),
    (
        "bad clock",
        {"columns": {"Ti": "a"}, "night": {"start": "25:00"}},
        r"\[night\] start must be a clock time 'HH:MM'",
    ),
    (
        "bad choice",
        {"columns": {"Ti": "a"}, "time": {"ambiguous": "firts"}},
        r"ambiguous = 'firts' is not one of infer, first, second, drop, raise; did you mean 'first'",
    ),
    (
        "density as text",
        {"columns": {"Ti": "a"}, "air_density": "1.2"},
        r"air_density must be a number, got '1.2'",
    ),
    (
        "wrong quantity",
        {"columns": {"m": {"column": "a", "quantity": "power"}}},
        r"\[columns\].m is a flow, not a power",
    ),
    ("min_samples", {"columns": {"Ti": "a"}, "min_samples": 1}, r"min_samples must be an integer >= 2"),
    (
        "unknown unit",
        {"columns": {"Q": {"column": "a", "unit": "kWh"}}},
        r"column 'a': unknown power unit 'kWh'; known units: W, kW, Btu/h",
    ),
    (
        "same name twice",
        {"columns": {"Ti": "a"}, "surroundings": {"Ti": "b"}},
        r"'Ti' is in both \[columns\] and \[surroundings\]",
    ),
    (
        "na_values not list",
        {"columns": {"Ti": "a"}, "na_values": "Offline"},
        r"na_values must be a list of strings",
    ),
]


@pytest.mark.parametrize(("doc", "pattern"), [c[1:] for c in BAD_MAPS], ids=[c[0] for c in BAD_MAPS])
def test_bad_map(doc, pattern):
    with pytest.raises(DataError, match=pattern):
        parse_column_map(doc)


def test_invalid_toml(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text("[columns\nTi = 'a'\n")
    with pytest.raises(DataError, match=r"m.toml.: not valid TOML"):
        read_column_map(path)


def test_default_layout_names_all_missing_columns():
    with pytest.raises(DataError, match=r"missing column\(s\) 'Ts', 'Tn2' .*'Tn2': did you mean 'Tn_2'"):
        default_column_map(["time", "Ti", "To", "m", "Q", "Tf", "Tc", "Tn1", "Tn_2", "Thw"])


def test_the_documented_example_is_valid():
    """The format description in the module docstring (copied to the README) parses as written."""
    import tomllib

    import rczone.data.columnmap as module

    doc = module.__doc__
    block = doc[doc.index("::\n") + 3 : doc.index("\nChannels ``Ti``")]
    cmap = parse_column_map(tomllib.loads(textwrap.dedent(block)))
    assert cmap.channel_names == ("Ti", "To", "Ts", "m", "Q", "m2", "Qh", "m3", *DEFAULT_SURROUNDINGS)
    assert (cmap.timezone, cmap.step, cmap.hold_max_gap) == ("America/New_York", 300.0, 7200.0)
