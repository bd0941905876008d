"""Round trips: SI data written as a BMS would (degF, cfm, kW, local time across DST) load back equal.

The file contents are produced here with independent formulas (F = 1.8 C + 32, 1 ft = 0.3048 m,
local wall-clock from :mod:`zoneinfo`), never with rczone's own converters.
"""

from __future__ import annotations

import datetime as dt
import zoneinfo

import numpy as np
import pandas as pd
import pytest

from rczone.data import RczoneWarning, load_zone_data, parse_column_map

NY = zoneinfo.ZoneInfo("America/New_York")
RHO = 1.15  # deliberately not the default, to check the configured density is used
CFM = 0.3048**3 / 60.0  # m3/s per cfm
SURR = ("Tf", "Tc", "Tn1", "Tn2", "Thw")
# Spans that contain a daylight-saving change in New York (UTC epoch seconds, step 600 s).
FALL_BACK = 1320494400.0  # 2011-11-05 12:00 UTC; clocks go back 2011-11-06 06:00 UTC
SPRING_FORWARD = 1299931200.0  # 2011-03-12 12:00 UTC; clocks go forward 2011-03-13 07:00 UTC


def si_original(t0: float) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    t = t0 + 600.0 * np.arange(220)
    s = (t - t0) / 3600.0
    ch = {
        "Ti": 22.0 + 1.5 * np.sin(s / 3.0),
        "To": 5.0 + 8.0 * np.cos(s / 4.0),
        "Ts": 14.0 + 10.0 * np.sin(s / 5.0) ** 2,
        "m": np.where(s % 6 < 3, 0.12, 0.04),
        "Q": 50.0 + 10.0 * np.sin(s),
    }
    for k, name in enumerate(SURR):
        ch[name] = 21.0 + 0.3 * k + np.sin(s / (2.0 + k))
    return t, ch


def bms_values(ch: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    out = {n: ch[n] * 1.8 + 32.0 for n in ("Ti", "To", "Ts", *SURR)}
    out["m"] = ch["m"] / RHO / CFM
    out["Q"] = ch["Q"] / 1000.0
    return out


def stamps(t: np.ndarray, how: str):
    if how == "naive_local":
        return [dt.datetime.fromtimestamp(x, NY).replace(tzinfo=None).isoformat(sep=" ") for x in t]
    if how == "offset":
        return [dt.datetime.fromtimestamp(x, NY).isoformat() for x in t]
    if how == "aware_ts":
        return pd.to_datetime([dt.datetime.fromtimestamp(x, NY) for x in t]).tz_convert("America/New_York")
    if how == "naive_ts":
        return pd.to_datetime([dt.datetime.fromtimestamp(x, NY).replace(tzinfo=None) for x in t])
    raise ValueError(how)


def column_map(long: bool):
    names = {n: f"RM241.{n}-T" for n in ("Ti", "To", "Ts", *SURR)}
    doc = {
        "air_density": RHO,
        "time": {"column": "Timestamp", "timezone": "America/New_York"},
        "columns": {
            **{n: {"column": names[n], "unit": "degF"} for n in ("Ti", "To", "Ts")},
            "m": {"column": "RM241.SA-F", "unit": "cfm"},
            "Q": {"column": "RM241.PLUG", "unit": "kW"},
        },
        "surroundings": {n: {"column": names[n], "unit": "degF"} for n in SURR},
    }
    if long:
        doc["long"] = {"point": "Point", "value": "Value"}
    return parse_column_map(doc), {**names, "m": "RM241.SA-F", "Q": "RM241.PLUG"}


def write(path, t, values, names, how, long, fmt, shuffle=False):
    time = stamps(t, how)
    if long:
        parts = [pd.DataFrame({"Timestamp": time, "Point": names[n], "Value": values[n]}) for n in names]
        frame = pd.concat(parts, ignore_index=True)
        if shuffle:
            frame = frame.sample(frac=1.0, random_state=np.random.default_rng(3).integers(1 << 30))
    else:
        frame = pd.DataFrame({"Timestamp": time, **{names[n]: values[n] for n in names}})
    if fmt == "csv":
        frame.to_csv(path, index=False)
    else:
        frame.to_parquet(path, index=False)


CASES = [
    # (time stamps, long, file format, shuffled long rows)
    ("naive_local", False, "csv", False),
    ("offset", False, "csv", False),
    ("naive_local", True, "csv", False),
    ("offset", True, "csv", True),
    ("aware_ts", False, "parquet", False),
    ("naive_ts", False, "parquet", False),
    ("naive_ts", True, "parquet", False),
    ("aware_ts", True, "parquet", True),
]


@pytest.mark.parametrize("t0", [FALL_BACK, SPRING_FORWARD], ids=["fall_back", "spring_forward"])
@pytest.mark.parametrize(("how", "long", "fmt", "shuffle"), CASES)
def test_round_trip_equals_si_original(tmp_path, t0, how, long, fmt, shuffle):
    t, ch = si_original(t0)
    cmap, names = column_map(long)
    path = tmp_path / f"log.{fmt}"
    write(path, t, bms_values(ch), names, how, long, fmt, shuffle)
    data = load_zone_data(path, cmap)
    np.testing.assert_array_equal(data.t, t)
    for name, x in ch.items():
        np.testing.assert_allclose(data.channel(name), x, rtol=0, atol=1e-9, err_msg=name)
    tsd = np.mean([ch[n] for n in SURR], axis=0)
    np.testing.assert_allclose(data.channel("Tsd"), tsd, rtol=0, atol=1e-9)
    assert data.units["m"] == "kg/s" and data.source_units["m"] == "cfm"
    assert data.gaps == () and data.warnings == ()


def test_round_trip_from_toml_file(tmp_path):
    t, ch = si_original(FALL_BACK)
    _, names = column_map(False)
    write(tmp_path / "log.csv", t, bms_values(ch), names, "naive_local", False, "csv")
    toml = tmp_path / "map.toml"
    toml.write_text(
        f'air_density = {RHO}\n[time]\ncolumn = "Timestamp"\ntimezone = "America/New_York"\n'
        "[columns]\n"
        + "".join(f'{n} = {{ column = "{names[n]}", unit = "degF" }}\n' for n in ("Ti", "To", "Ts"))
        + f'm = {{ column = "{names["m"]}", unit = "cfm" }}\nQ = {{ column = "{names["Q"]}", unit = "kW" }}\n'
        + "[surroundings]\n"
        + "".join(f'{n} = {{ column = "{names[n]}", unit = "degF" }}\n' for n in SURR)
    )
    data = load_zone_data(tmp_path / "log.csv", toml)
    np.testing.assert_array_equal(data.t, t)
    np.testing.assert_allclose(data.channel("m"), ch["m"], rtol=0, atol=1e-9)


def test_default_layout_and_arrays_order(tmp_path):
    t, ch = si_original(FALL_BACK)
    frame = pd.DataFrame({"time": t, **ch})
    frame.to_csv(tmp_path / "zone.csv", index=False)
    data = load_zone_data(tmp_path / "zone.csv")
    tt, u, m, y = data.arrays(("To", "Tsd", "Ts", "Q"), ("m",), "Ti")
    np.testing.assert_array_equal(tt, t)
    assert u.shape == (t.size, 4) and m.shape == (t.size, 1) and y.shape == (t.size, 1)
    tsd = np.mean([ch[n] for n in SURR], axis=0)
    np.testing.assert_allclose(u, np.column_stack([ch["To"], tsd, ch["Ts"], ch["Q"]]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(m[:, 0], ch["m"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(y[:, 0], ch["Ti"], rtol=0, atol=1e-12)
    # the five surroundings are channels too, for the full-scale model
    _, u5, _, _ = data.arrays(SURR, (), "Ti")
    np.testing.assert_allclose(u5, np.column_stack([ch[n] for n in SURR]), rtol=0, atol=1e-12)


def test_constant_channel_and_default_tsd_column(tmp_path):
    t, ch = si_original(FALL_BACK)
    frame = pd.DataFrame({"time": t, "Ti": ch["Ti"], "Tsd": ch["Tf"]})
    cmap = parse_column_map({"columns": {"Ti": "Ti", "Tsd": "Tsd", "Q": {"value": 0.05, "unit": "kW"}}})
    frame.to_csv(tmp_path / "z.csv", index=False)
    data = load_zone_data(tmp_path / "z.csv", cmap)
    np.testing.assert_array_equal(data.channel("Q"), np.full(t.size, 50.0))
    np.testing.assert_allclose(data.channel("Tsd"), ch["Tf"], rtol=0, atol=1e-12)


def test_arrays_follow_an_rc_network_s_names(tmp_path):
    from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

    net = RCNetwork(
        "2R1C",
        nodes=[Node("Ti", "Cr"), Node("Tw", "Cw")],
        boundaries=["To", "Tsd"],
        resistors=[Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
        parameters=[
            Parameter(n, k, 1.0)
            for n, k in [
                ("Cr", "capacitance"),
                ("Cw", "capacitance"),
                ("Rwin", "resistance"),
                ("R1", "resistance"),
                ("R2", "resistance"),
            ]
        ],
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        supply_air=[SupplyAir("Ti", flow="m", temperature="Ts")],
    )
    t, ch = si_original(FALL_BACK)
    pd.DataFrame({"time": t, **ch}).to_csv(tmp_path / "z.csv", index=False)
    data = load_zone_data(tmp_path / "z.csv")
    _, u, m, _ = data.arrays(net.input_names, net.flow_names)
    tsd = np.mean([ch[n] for n in SURR], axis=0)
    by_name = {**ch, "Tsd": tsd}
    expected = np.column_stack([by_name[n] for n in net.input_names])
    np.testing.assert_allclose(u, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(m[:, 0], ch["m"])


def test_to_frame_is_the_default_layout(tmp_path):
    """A loaded degF/cfm log written back with to_frame() loads again without a map, unchanged."""
    t, ch = si_original(FALL_BACK)
    cmap, names = column_map(False)
    write(tmp_path / "log.csv", t, bms_values(ch), names, "offset", False, "csv")
    data = load_zone_data(tmp_path / "log.csv", cmap)
    data.to_frame().drop(columns=["Tsd"]).to_csv(tmp_path / "si.csv", index=False)
    again = load_zone_data(tmp_path / "si.csv")
    np.testing.assert_array_equal(again.t, data.t)
    for name in data.channels:
        np.testing.assert_allclose(again.channel(name), data.channel(name), rtol=0, atol=1e-12)


@pytest.mark.parametrize("dtype", ["float64", "Float64", "double[pyarrow]", "object"])
def test_a_parquet_columns_numbers_and_gaps_whatever_its_dtype(tmp_path, dtype):
    # numeric columns are taken as they are, others through the numeric check: the same arrays
    t, ch = si_original(FALL_BACK)
    frame = pd.DataFrame({"time": t, **ch})
    ti = frame["Ti"].to_numpy(copy=True)
    ti[[3, 4]] = np.nan  # a gap in the measurement
    frame["Ti"] = pd.Series(ti).astype(dtype) if dtype != "object" else pd.Series(ti, dtype=object)
    frame["Q"] = frame["Q"].round().astype("int64")
    frame.to_parquet(tmp_path / "zone.parquet", index=False)
    with pytest.warns(RczoneWarning, match="gap"):  # the gap is reported, not repaired
        data = load_zone_data(tmp_path / "zone.parquet")
    _, u, _, y = data.arrays(("To", "Tsd", "Ts", "Q"), ("m",), "Ti", allow_nan=True)
    np.testing.assert_array_equal(y[:, 0], ti)
    np.testing.assert_array_equal(u[:, 3], np.round(ch["Q"]))
