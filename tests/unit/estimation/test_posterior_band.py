"""The posterior predictive band against the normal quantiles it must reproduce, and bad draws."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from rczone.errors import ParameterError
from rczone.estimation.forecast import TWO_SIGMA, posterior_band


def test_band_of_a_known_predictive_is_its_quantiles() -> None:
    # draws of a level a ~ N(1, 0.3^2), noise sd 0.4: the predictive is N(1, 0.5^2) at every sample
    rng = np.random.default_rng(0)
    draws = rng.normal(1.0, 0.3, size=(20000, 1))

    def band(v):
        return np.full((3, 1), v["a"]), np.full((3, 1), 0.4)

    lo, hi, sd_par = posterior_band(band, {}, ["a"], draws, np.random.default_rng(1))
    z = stats.norm.ppf((1 + TWO_SIGMA) / 2)
    assert z == pytest.approx(2.0, rel=1e-12)
    np.testing.assert_allclose(lo, 1.0 - 2.0 * 0.5, atol=0.02)
    np.testing.assert_allclose(hi, 1.0 + 2.0 * 0.5, atol=0.02)
    np.testing.assert_allclose(sd_par, 0.3, rtol=0.02)


def test_nan_noise_counts_as_none() -> None:
    draws = np.array([[1.0], [2.0], [3.0]])
    lo, hi, _ = posterior_band(
        lambda v: (np.full((2, 1), v["a"]), np.full((2, 1), math.nan)),
        {},
        ["a"],
        draws,
        np.random.default_rng(0),
    )
    assert np.all(lo >= 1.0) and np.all(hi <= 3.0)


@pytest.mark.parametrize("draws", [np.ones((1, 1)), np.ones((5, 2)), np.ones(5)])
def test_draws_of_the_wrong_shape_are_refused(draws) -> None:
    with pytest.raises(ParameterError, match="draws must be"):
        posterior_band(
            lambda v: (np.zeros((2, 1)), np.zeros((2, 1))), {}, ["a"], draws, np.random.default_rng(0)
        )
