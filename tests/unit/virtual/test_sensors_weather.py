"""BMS sensor models and outdoor weather profiles."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.virtual.sensors import quantize_f, sense_flow, sense_temperature
from rczone.virtual.weather import outdoor_temperature


def test_quantization_grid_is_a_tenth_of_a_fahrenheit():
    x = np.linspace(15, 30, 1001)
    q = quantize_f(x)
    f = q * 1.8 + 32
    np.testing.assert_allclose(f * 10, np.round(f * 10), atol=1e-9)
    assert np.max(np.abs(q - x)) <= 0.05 / 1.8 + 1e-12
    assert quantize_f(np.array([0.0]))[0] == 0.0  # 32.0 F is on the grid


def test_temperature_noise_level():
    rng = np.random.default_rng(0)
    err = sense_temperature(np.full(20000, 22.0), rng) - 22.0
    # 0.05 K noise plus uniform quantization (step 1/18 K): sd = sqrt(0.05^2 + step^2/12)
    assert np.std(err) == pytest.approx(np.sqrt(0.05**2 + (1 / 18) ** 2 / 12), rel=0.05)
    assert abs(np.mean(err)) < 0.003


def test_flow_sensor_clipped_and_quantized():
    rng = np.random.default_rng(1)
    r = sense_flow(np.full(5000, 0.001), rng)
    assert r.min() >= 0.0
    np.testing.assert_allclose(r * 1000, np.round(r * 1000), atol=1e-9)
    r2 = sense_flow(np.full(5000, 0.05), rng)
    assert np.std(r2) == pytest.approx(0.002, rel=0.1)


@pytest.mark.parametrize(("season", "lo", "hi"), [("summer", 22, 31), ("winter", -1, 15), ("autumn", 9, 23)])
def test_night_ranges(season, lo, hi):
    t = 60.0 * np.arange(720)
    for seed in range(5):
        to = outdoor_temperature(season, t, np.random.default_rng(seed))
        assert lo <= to.min() and to.max() <= hi
        assert to[0] > to[-200]  # cools through the night
        assert np.max(np.abs(np.diff(to))) < 0.5  # smooth: no jumps between minutes


def test_weather_seeded():
    t = 60.0 * np.arange(100)
    a = outdoor_temperature("winter", t, np.random.default_rng(3))
    b = outdoor_temperature("winter", t, np.random.default_rng(3))
    c = outdoor_temperature("winter", t, np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_unknown_season():
    with pytest.raises(ParameterError, match="did you mean 'winter'"):
        outdoor_temperature("wintre", np.arange(3.0), np.random.default_rng(0))
