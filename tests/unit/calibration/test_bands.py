"""The band calibrated per horizon: exact invariances, data from the model itself, and bad saved values."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.calibration.bands import BandScale, calibrate_band, quantile_scale
from rczone.errors import DataError
from rczone.estimation.forecast import k_step_band, k_step_bands
from tests.unit.estimation.nets import NET1
from tests.unit.estimation.test_forecast import NOISE, THETA, noisy_data


def test_one_filter_pass_gives_every_horizon_of_the_single_horizon_predictor():
    data = noisy_data(300)
    values = {**THETA, **NOISE}
    bands = k_step_bands(NET1, values, data, [12, 1, 5])
    for k in (1, 5, 12):
        y_hat, sd = k_step_band(NET1, values, data, k)
        np.testing.assert_array_equal(bands[k].y_hat, y_hat)
        np.testing.assert_array_equal(bands[k].sd, sd)


def test_predictions_from_a_subset_of_origins_are_those_of_every_origin():
    data = noisy_data(300)
    values = {**THETA, **NOISE}
    origins = np.array([0, 7, 100, 250, 295])
    full = k_step_bands(NET1, values, data, [1, 6])
    some = k_step_bands(NET1, values, data, [1, 6], origins=origins)
    for k in (1, 6):
        targets = origins[origins + k < 300] + k
        np.testing.assert_array_equal(some[k].y_hat[targets], full[k].y_hat[targets])
        np.testing.assert_array_equal(some[k].sd[targets], full[k].sd[targets])
        assert np.isfinite(some[k].y_hat).sum() == len(targets)


def test_the_factors_of_a_model_that_knows_its_noise_are_near_one():
    """Data simulated from the stochastic model itself: its band is right, the factors stay near 1."""
    data = noisy_data(1500, seed=8)
    scale = calibrate_band(NET1, {**THETA, **NOISE}, data)
    steps = np.round(np.array(scale.horizon_s) / 600.0).astype(int)
    assert list(steps) == [1, 2, 3, 6, 12, 24, 48, 72, 144, 288][: len(steps)]
    short = np.array(scale.scale)[steps <= 24]  # errors correlated over ~3 h: few checks beyond
    assert np.all((short > 0.85) & (short < 1.2)), short


def test_noise_levels_three_times_too_small_give_factors_three_times_larger():
    """Scaling every noise level by c scales the filter's covariances by c^2 and leaves its gain and
    predictions unchanged, so the standardized errors scale by exactly 1/c (Saerkkae 2013, ch. 4)."""
    data = noisy_data(600, seed=4)
    true = calibrate_band(NET1, {**THETA, **NOISE}, data)
    small = calibrate_band(NET1, {**THETA, **{k: v / 3 for k, v in NOISE.items()}}, data)
    np.testing.assert_allclose(small.scale, 3 * np.array(true.scale), rtol=1e-6)
    assert small.open_loop == pytest.approx(3 * true.open_loop, rel=1e-6)


def test_the_quantile_factor_puts_the_nominal_share_inside_two_sigma():
    rng = np.random.default_rng(0)
    e = rng.standard_t(3, 4000)  # heavy tails: a variance-based factor would not do
    f = quantile_scale(e, np.ones_like(e))
    assert np.mean(np.abs(e) <= 2 * f) == pytest.approx(0.9545, abs=1e-3)
    assert quantile_scale(e[:10], np.ones(10)) is None


def test_factors_between_and_beyond_the_calibrated_horizons():
    s = BandScale((300.0, 3600.0), (1.0, 2.0), open_loop=3.0)
    assert s.at(300.0) == 1.0 and s.at(3600.0) == 2.0
    assert s.at(np.sqrt(300.0 * 3600.0)) == pytest.approx(1.5)  # linear in log-horizon
    assert s.at(60.0) == 1.0 and s.at(86400.0) == 2.0 and s.at(None) == 3.0
    assert BandScale.from_dict(s.to_dict()) == s


@pytest.mark.parametrize(
    "saved",
    [
        {"horizon_s": [300, 60], "scale": [1, 2]},
        {"horizon_s": [300], "scale": [-1]},
        {"horizon_s": [300], "scale": [1, 2]},
        {"horizon_s": "x", "scale": [1]},
        {"scale": [1]},
        {"horizon_s": [300], "scale": [1], "open_loop": "nan"},
        [1, 2],
    ],
)
def test_a_malformed_saved_calibration_is_a_data_error(saved):
    with pytest.raises(DataError, match="band_scale"):
        BandScale.from_dict(saved)
