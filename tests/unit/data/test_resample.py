"""Resampling: exact on linear / piecewise-constant signals, never across long gaps."""

from __future__ import annotations

import numpy as np

from rczone.data.resample import hold_previous, interpolate_linear, uniform_grid


def test_grid_is_aligned_to_multiples_of_step():
    g = uniform_grid(1312322401.5, 1312323610.0, 300.0)
    np.testing.assert_array_equal(g, 300.0 * np.arange(4374409, 4374413))  # 1312322700 .. 1312323600
    np.testing.assert_array_equal(uniform_grid(0.0, 900.0, 300.0), [0.0, 300.0, 600.0, 900.0])


def test_linear_signal_sampled_irregularly_is_exact_on_the_grid():
    rng = np.random.default_rng(7)
    t0 = 1.3e9
    t = t0 + np.sort(rng.uniform(0.0, 86400.0, 400))
    a, b = 21.3, -2.5e-5
    x = a + b * (t - t0)
    grid = uniform_grid(t[0], t[-1], 300.0)
    y = interpolate_linear(t, x, grid, max_gap=3600.0)
    assert np.isfinite(y).all()
    np.testing.assert_allclose(y, a + b * (grid - t0), rtol=0, atol=1e-9)


def test_linear_is_nan_across_a_long_gap_and_outside_the_samples():
    t = np.array([0.0, 100.0, 200.0, 2000.0, 2100.0])
    x = 2.0 * t
    grid = np.arange(-100.0, 2300.0, 100.0)
    y = interpolate_linear(t, x, grid, max_gap=900.0)
    inside = (grid >= 0) & (grid <= 200) | (grid >= 2000) & (grid <= 2100)
    np.testing.assert_allclose(y[inside], 2.0 * grid[inside], rtol=0, atol=1e-12)
    assert np.isnan(y[~inside]).all()


def test_nan_samples_are_skipped_within_max_gap():
    t = np.array([0.0, 100.0, 200.0, 300.0])
    x = np.array([0.0, np.nan, 20.0, 30.0])
    np.testing.assert_allclose(interpolate_linear(t, x, np.array([50.0, 100.0]), 900.0), [5.0, 10.0])
    assert np.isnan(interpolate_linear(t, x, np.array([100.0]), 150.0)).all()


def test_hold_previous_on_a_command():
    t = np.array([0.0, 250.0, 700.0, 5000.0, 5100.0])
    m = np.array([0.12, 0.04, 0.08, 0.10, 0.10])
    grid = np.arange(0.0, 5400.0, 300.0)
    y = hold_previous(t, m, grid, max_gap=900.0)
    expected = np.full(grid.shape, np.nan)
    expected[grid < 250] = 0.12
    expected[(grid >= 250) & (grid < 700)] = 0.04
    expected[grid == 5100.0] = 0.10  # a grid time on a sample takes it
    # 700 -> 5000 is longer than max_gap: nothing held across it
    np.testing.assert_array_equal(y, expected)
    y = hold_previous(t, m, np.array([5000.0, 5050.0, 5100.0, 5200.0]), max_gap=900.0)
    np.testing.assert_array_equal(y, [0.10, 0.10, 0.10, np.nan])


def test_empty_channel_gives_nan():
    assert np.isnan(
        interpolate_linear(np.array([0.0, 1.0]), np.array([np.nan, np.nan]), np.array([0.5]), 9.0)
    ).all()
    assert np.isnan(
        hold_previous(np.array([0.0, 1.0]), np.array([np.nan, np.nan]), np.array([0.5]), 9.0)
    ).all()
