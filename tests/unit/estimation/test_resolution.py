"""The measurement-noise floor follows the data's resolution."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rczone.estimation.resolution import QUANTIZATION_FRACTION, noise_floor, resolution


def test_a_trend_logged_at_a_tenth_of_a_degree_f_has_that_resolution_in_degc() -> None:
    rng = np.random.default_rng(0)
    f = np.round((68 + np.cumsum(rng.normal(0, 0.05, 2000))) / 0.1) * 0.1
    c = (f - 32) / 1.8
    assert resolution(c) == pytest.approx(0.1 / 1.8, rel=1e-6)
    assert noise_floor(c) == pytest.approx(QUANTIZATION_FRACTION * 0.1 / 1.8 / math.sqrt(12), rel=1e-6)
    c[::7] = np.nan  # gaps do not matter
    assert resolution(c) == pytest.approx(0.1 / 1.8, rel=1e-6)


def test_an_unquantized_series_has_no_grid_and_a_floor_from_its_changes() -> None:
    rng = np.random.default_rng(1)
    y = 20 + np.cumsum(rng.normal(0, 0.01, 1000))
    assert resolution(y) is None
    med = float(np.median(np.abs(np.diff(y))))
    assert noise_floor(y) == pytest.approx(1e-3 * med, rel=1e-9)
    assert noise_floor(np.full(10, 20.0)) == 1e-6  # constant: the absolute floor
    assert resolution(np.array([1.0, 2.0])) is None  # too few distinct values to tell
