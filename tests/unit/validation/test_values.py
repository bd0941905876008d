"""The one validation layer the command line and the API share (issue 39): each check as a table."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rczone import validation
from rczone.errors import DataError, ParameterError


@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        (-1, r"seed must be an integer from 0 to 2\*\*63 - 1, got -1"),
        (2**63, r"from 0 to 2\*\*63 - 1"),
        (1.5, r"got 1\.5"),
        (True, r"got True"),
        ("3", r"got '3'"),
        (None, r"got None"),
    ],
)
def test_a_seed_is_a_non_negative_integer_below_2_63(value, pattern):
    with pytest.raises(ParameterError, match=pattern):
        validation.seed(value)


def test_a_seed_keeps_numpy_integers_and_the_limits():
    assert validation.seed(np.int64(7)) == 7 and isinstance(validation.seed(np.int64(7)), int)
    assert validation.seed(0) == 0 and validation.seed(2**63 - 1) == 2**63 - 1


@pytest.mark.parametrize(
    ("text", "count"),
    [("3", 3), (" 12 ", 12), ("²", None), ("①", None), ("٣", None), ("a,b", None), ("", None), ("-1", None)],
)
def test_only_ascii_digits_are_a_count(text, count):
    assert validation.ascii_count(text) == count


@pytest.mark.parametrize(
    ("steps", "pattern"),
    [(0, r">= 1"), (10**12, r"not less than the 50 samples"), (50, r"not less than"), (True, r"got True")],
)
def test_steps_ahead_leave_a_sample_to_predict(steps, pattern):
    with pytest.raises(ParameterError, match=pattern):
        validation.steps_ahead(steps, 50)
    assert validation.steps_ahead(49, 50) == 49


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e308, -300.0, -273.15, "20", True, None])
def test_a_temperature_is_finite_above_absolute_zero(value):
    with pytest.raises(ParameterError, match="x0 of Ti"):
        validation.temperature(value, "x0 of Ti")


@pytest.mark.parametrize(
    ("value", "quantity"), [(1e300, "flow"), (-1e10, "power"), (1e6, "irradiance"), (-274.0, "temperature")]
)
def test_an_input_stays_within_what_a_building_reaches(value, quantity):
    with pytest.raises(ParameterError, match="constant m"):
        validation.input_value(value, "constant m", quantity)
    assert validation.input_value(0.1, "constant m", "flow") == 0.1


@pytest.mark.parametrize(
    ("column", "pattern"),
    [
        (["x", "y", "z"], r"column 'To' holds .* \(e\.g\. 'x'\), not numbers"),
        (["1", "2", "3"], r"column 'To' holds"),
        ([True, False, True], r"column 'To' holds bool"),
        (pd.date_range("2020", periods=3, freq="h"), r"column 'To' holds datetime"),
        ([1j, 2j, 3j], r"column 'To' holds complex"),
    ],
)
def test_a_column_without_numbers_is_named(column, pattern):
    with pytest.raises(DataError, match=pattern):
        validation.numeric_column(pd.DataFrame({"To": column}), "To")


def test_a_numeric_column_is_floats_with_its_missing_samples():
    out = validation.numeric_column(pd.DataFrame({"To": [1, None, 3]}), "To")
    assert out.dtype == float and np.isnan(out[1]) and out[2] == 3.0


@pytest.mark.parametrize(
    ("t", "pattern"),
    [
        ([0.0, 300.0, 300.0], r"does not increase at sample 3"),
        ([0.0, math.nan, 600.0], r"not finite at sample 2"),
        ([0.0, 300.0, 1e15], r"spans 1e\+15 s, more than a century \(a step of 1e\+15 s after sample 2\)"),
        ([], r"no samples"),
    ],
)
def test_a_time_axis_is_finite_increasing_and_shorter_than_a_century(t, pattern):
    with pytest.raises(DataError, match=pattern):
        validation.time_axis(np.array(t))


def test_missing_inputs_are_named_with_the_first_time():
    u = np.array([[1.0, 2.0], [np.nan, 2.0], [1.0, np.inf]])
    with pytest.raises(
        DataError, match=r"input 'To' is missing or not finite at 1 sample\(s\), first at t = 60 s"
    ):
        validation.finite_inputs(np.array([0.0, 60.0, 120.0]), u, ["To", "Q"])


def test_a_result_out_of_the_range_of_temperatures_is_refused():
    frame = pd.DataFrame({"Ti": [20.0, 21.0, math.nan], "Te": [1.0, 2e4, 3.0]})
    with pytest.raises(DataError, match=r"leaves the range of temperatures at sample 2 of 'Te'"):
        validation.finite_result(frame, "the simulation")
