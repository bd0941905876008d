"""The plants' forecasts share one time axis and one refusal (control.plant.forecast_times)."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.control.house import HousePlant
from rczone.control.plant import forecast_times
from rczone.control.virtualplant import VirtualPlant
from rczone.errors import ParameterError


def test_the_axis_starts_now_and_covers_the_horizon():
    t, iv = forecast_times(100.0, 60.0, 3600.0, None)
    np.testing.assert_array_equal(t, 100.0 + 60.0 * np.arange(61))
    assert iv == 60.0
    t, iv = forecast_times(0.0, 60.0, 3600.0, 600.0)
    assert iv == 600.0 and t[-1] == 3600.0 and t.size == 7


@pytest.mark.parametrize(
    ("horizon", "interval"), [(-1.0, None), (np.inf, None), (3600.0, 0.0), (3600.0, np.nan)]
)
def test_every_plant_refuses_a_bad_horizon_or_interval(horizon, interval):
    for plant in (VirtualPlant("winter", days=0.1, seed=0), HousePlant(days=0.01)):
        with pytest.raises(ParameterError, match="a forecast needs horizon >= 0 and interval > 0 s"):
            plant.forecast(horizon, interval=interval)
