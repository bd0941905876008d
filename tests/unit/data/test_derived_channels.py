"""Column maps with derived channels, channels a model does not use, and the unnamed time column (issue 22).

Expected values are computed here from the raw columns with plain arithmetic (1 kW = 1000 W), never
with rczone's converters.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.data import load_zone_data, parse_column_map
from rczone.data.derived import Combination, parse_expression
from rczone.errors import DataError

SIGNALS = {"Ti": "temperature", "To": "temperature", "Ph": "power"}  # a model without solar gains


def _frame(n: int = 12) -> pd.DataFrame:
    rng = np.random.default_rng(3)
    return pd.DataFrame(
        {
            "time": 300.0 * np.arange(n),
            "room": 21.0 + rng.normal(0, 0.2, n),
            "out": 4.0 + rng.normal(0, 1.0, n),
            "HC1": rng.uniform(0.0, 2.0, n),  # kW
            "HC2": rng.uniform(0.0, 3.0, n),  # kW
            "sun": rng.uniform(0.0, 0.3, n),  # kW/m2
        }
    )


def _load(tmp_path, frame: pd.DataFrame, doc: dict, signals=SIGNALS, **csv):
    path = tmp_path / "log.csv"
    frame.to_csv(path, **({"index": False} | csv))
    return load_zone_data(path, parse_column_map(doc, signals=signals), signals=signals)


@pytest.mark.parametrize(
    ("text", "terms", "offset"),
    [
        ("Ph1 + Ph2", (("Ph1", 1.0), ("Ph2", 1.0)), 0.0),
        ("1000 * P_kW", (("P_kW", 1000.0),), 0.0),
        ("T - 0.5", (("T", 1.0),), -0.5),
        ("a - b", (("a", 1.0), ("b", -1.0)), 0.0),
        ("-a + 2e3*b", (("a", -1.0), ("b", 2000.0)), 0.0),
        ("`zone temp [degF]` / 2", (("zone temp [degF]", 0.5),), 0.0),
        ("RM241.Q * 3 + RM241.Q", (("RM241.Q", 4.0),), 0.0),
    ],
)
def test_expressions_read_as_linear_combinations(text, terms, offset):
    assert parse_expression(text) == Combination(terms, offset)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a * b", "no product of two columns"),
        ("a +", "expected a column or a number, found the end"),
        ("__import__('os')", "cannot read"),
        ("a / 0", "division by zero"),
        ("3 + 4", "names no column"),
        ("a b", "expected \\+ or -"),
        ("", "non-empty expression"),
        (" + ".join(f"c{k}" for k in range(40)), "more than 32 columns"),
        ("a" * 600, "longer than 500"),
    ],
)
def test_bad_expressions_are_one_line_errors(text, message):
    with pytest.raises(DataError, match=message):
        parse_expression(text, "[columns].Ph.expr")


def test_a_sum_of_two_circuits_in_kw_is_one_channel_in_watts(tmp_path):
    f = _frame()
    doc = {
        "columns": {
            "Ti": "room",
            "To": "out",
            "Ph": {"expr": "HC1 + HC2", "unit": "kW"},
        }
    }
    z = _load(tmp_path, f, doc)
    ph = z.values[:, z.channels.index("Ph")]
    np.testing.assert_allclose(ph, (f["HC1"] + f["HC2"]).to_numpy() * 1000.0, rtol=1e-12)


def test_scale_and_offset_apply_before_the_unit(tmp_path):
    f = _frame()
    doc = {
        "columns": {
            "Ti": {"column": "room", "offset": -0.5},  # a sensor reading 0.5 K high
            "To": "out",
            "Ph": {"column": "HC1", "scale": 1000.0},  # kW logged, W declared
        }
    }
    z = _load(tmp_path, f, doc)
    np.testing.assert_allclose(z.values[:, z.channels.index("Ti")], f["room"].to_numpy() - 0.5)
    np.testing.assert_allclose(z.values[:, z.channels.index("Ph")], 1000.0 * f["HC1"].to_numpy())


def test_a_missing_term_makes_the_sample_missing(tmp_path):
    f = _frame()
    f.loc[4, "HC2"] = np.nan
    doc = {"columns": {"Ti": "room", "To": "out", "Ph": {"expr": "HC1 + HC2", "unit": "kW"}}}
    with pytest.warns(UserWarning):  # the gap is reported
        z = _load(tmp_path, f, doc)
    ph = z.values[:, z.channels.index("Ph")]
    assert np.isnan(ph[4]) and np.isfinite(np.delete(ph, 4)).all()


def test_a_derived_channel_may_share_a_column_but_two_plain_channels_may_not():
    ok = {"columns": {"Ti": "room", "Ph": {"expr": "HC1 + HC2"}, "Q": "HC1"}}
    assert parse_column_map(ok, signals=SIGNALS).channel("Ph").columns == ("HC1", "HC2")
    with pytest.raises(DataError, match="mapped to both 'Ti' and 'To'"):
        parse_column_map({"columns": {"Ti": "room", "To": "room"}})


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"column": "a", "expr": "a + b"}, "exactly one of 'column', 'expr' or 'value', got column and expr"),
        ({"value": 3, "scale": 2}, "is a constant"),
        ({"column": "a", "scale": 0}, "scale must not be 0"),
        ({"column": "a", "scale": "big"}, "scale must be a number"),
        ({"expr": "a ** 2"}, r"expected a number after .a \*."),
    ],
)
def test_bad_derived_channels(spec, message):
    with pytest.raises(DataError, match=message):
        parse_column_map({"columns": {"Ti": "room", "Ph": spec}}, signals=SIGNALS)


def test_a_channel_the_model_does_not_use_is_ignored_and_listed(tmp_path):
    """Defect 6: one map serves candidates with and without solar gains."""
    doc = {"columns": {"Ti": "room", "To": "out", "Ph": "HC1", "Ps": {"column": "sun", "unit": "kW/m2"}}}
    z = _load(tmp_path, _frame(), doc)
    assert "Ps" not in z.channels and z.ignored == ("Ps",)
    assert z.to_frame().attrs["ignored_channels"] == ["Ps"]
    # the same map, read for a model with solar gains, loads it
    z2 = _load(tmp_path, _frame(), doc, signals={**SIGNALS, "Ps": "irradiance"})
    assert "Ps" in z2.channels and z2.ignored == ()


def test_a_typo_of_an_unmapped_signal_is_still_an_error_with_the_right_hint():
    doc = {"columns": {"Ti": "room", "To": "out", "Phh": "HC1"}}
    with pytest.raises(DataError, match=r"the model's 'Ph' is not mapped; did you mean 'Ph'\?"):
        parse_column_map(doc, signals=SIGNALS)


def test_without_a_model_an_unknown_channel_says_how_to_load_it():
    with pytest.raises(DataError) as info:
        parse_column_map({"columns": {"Ti": "room", "Ps": "sun"}})
    text = str(info.value)
    assert "did you mean 'Ts'" not in text  # the wrong hint of issue 22
    assert "unknown channel 'Ps'" in text and "declare quantity" in text


def test_the_unnamed_index_column_is_the_time_with_column_empty(tmp_path):
    """Defect 7: a frame written with its index (pandas' header 'Unnamed: 0')."""
    f = _frame().set_index("time")
    f.index.name = None
    doc = {"time": {"column": ""}, "columns": {"Ti": "room", "To": "out", "Ph": "HC1"}}
    z = _load(tmp_path, f, doc, index=True)
    np.testing.assert_array_equal(z.t, 300.0 * np.arange(12))
    # pandas' own name for it works as well
    doc["time"]["column"] = "Unnamed: 0"
    assert _load(tmp_path, f, doc, index=True).t[-1] == 3300.0


def test_a_missing_time_column_beside_an_unnamed_one_says_how(tmp_path):
    f = _frame().set_index("time")
    f.index.name = None
    doc = {"columns": {"Ti": "room", "To": "out", "Ph": "HC1"}}
    with pytest.raises(DataError, match=r'no time column \'time\'; the column 1 has no name .*column = ""'):
        _load(tmp_path, f, doc, index=True)
    doc["time"] = {"column": ""}
    with pytest.raises(DataError, match="every column has one"):
        _load(tmp_path, _frame(), doc)


def test_a_parquet_file_saved_with_its_index_keeps_the_time(tmp_path):
    f = _frame().set_index("time")
    f.index.name = None
    f.to_parquet(tmp_path / "log.parquet")
    doc = {"time": {"column": ""}, "columns": {"Ti": "room", "To": "out", "Ph": "HC1"}}
    z = load_zone_data(tmp_path / "log.parquet", parse_column_map(doc, signals=SIGNALS), signals=SIGNALS)
    np.testing.assert_array_equal(z.t, 300.0 * np.arange(12))


def test_a_long_log_scales_a_point_but_does_not_sum_points(tmp_path):
    t = np.repeat(300.0 * np.arange(6), 2)
    long = pd.DataFrame({"time": t, "point": ["R", "O"] * 6, "value": np.tile([21.0, 4.0], 6)})
    long.to_csv(tmp_path / "long.csv", index=False)
    base = {"long": {"point": "point", "value": "value"}}
    doc = base | {"columns": {"Ti": {"column": "R", "offset": -1.0}, "To": {"expr": "2 * O"}}}
    z = load_zone_data(tmp_path / "long.csv", parse_column_map(doc))
    np.testing.assert_allclose(z.values[:, z.channels.index("Ti")], 20.0)
    np.testing.assert_allclose(z.values[:, z.channels.index("To")], 8.0)
    bad = base | {"columns": {"Ti": "R", "To": {"expr": "O + R"}}}
    with pytest.raises(DataError, match="combines several points"):
        load_zone_data(tmp_path / "long.csv", parse_column_map(bad))
