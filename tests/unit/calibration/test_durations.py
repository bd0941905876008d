"""Durations of --warmup / --conformal: units as the help spells them, no pandas deprecation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rczone.calibration.holdout import duration_seconds, warmup_end


@pytest.mark.parametrize(
    ("text", "seconds"),
    [
        ("1d", 86400.0),
        ("1D", 86400.0),
        (" 3d ", 3 * 86400.0),
        ("2 days", 2 * 86400.0),
        ("6h", 21600.0),
        ("6H", 21600.0),
        ("30min", 1800.0),
    ],
)
def test_a_duration_is_read_in_seconds_without_a_warning(text, seconds):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # pandas' FutureWarning for a lower-case "d" would fail here
        assert duration_seconds(text) == seconds


@pytest.mark.parametrize("text", ["0h", "-1d", "5", "abc", "1e400d", ""])
def test_what_is_not_a_positive_duration_with_a_unit_is_refused(text):
    with pytest.raises(ValueError):
        duration_seconds(text)


def test_a_warm_up_of_one_day_starts_scoring_a_day_in():
    t = np.arange(0.0, 3 * 86400.0, 300.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert warmup_end(t, "1d") == 86400.0
