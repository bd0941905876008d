"""BOPTEST's AR(1) forecast error: the paths have the mean and spread the recursion implies."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.emulators.forecasts import SCENARIOS, forecast_error, scenario
from rczone.errors import ParameterError


@pytest.mark.parametrize("name", ["low", "medium", "high"])
def test_the_error_paths_have_the_moments_of_the_ar1_recursion(name):
    """Mean and variance at lead tau: F^(tau-1) F0 + mu sum F^j and F^(2(tau-1)) K0^2 + K^2 sum F^(2j)."""
    p = SCENARIOS[name]
    rng = np.random.default_rng(7)
    paths = np.array([p.path(24, rng) for _ in range(6000)])
    for tau in (1, 6, 24):
        j = np.arange(tau - 1)
        mean = p.F ** (tau - 1) * p.F0 + p.mu * np.sum(p.F**j)
        var = p.F ** (2 * (tau - 1)) * p.K0**2 + p.K**2 * np.sum(p.F ** (2 * j))
        sd = np.sqrt(var)
        assert paths[:, tau - 1].mean() == pytest.approx(mean, abs=4 * sd / np.sqrt(6000))
        assert paths[:, tau - 1].std() == pytest.approx(sd, rel=0.05)


def test_the_error_grows_with_the_scenario_and_is_zero_now_and_for_none():
    offsets = np.arange(0, 12 * 3600 + 1, 900.0)
    spread = {}
    for name in ("none", "low", "medium", "high"):
        rng = np.random.default_rng(1)
        e = np.array([forecast_error(scenario(name), offsets, rng) for _ in range(500)])
        assert np.all(e[:, 0] == 0.0)
        spread[name] = e[:, -1].std()
    assert spread["none"] == 0.0 < spread["low"] < spread["medium"] < spread["high"]


def test_an_unknown_scenario_is_one_line_with_the_close_name():
    with pytest.raises(ParameterError, match="did you mean 'medium'"):
        scenario("meduim")
