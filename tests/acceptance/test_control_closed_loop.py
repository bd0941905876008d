"""Issue 21's done-when: the MPC with the 2-state model fitted on night C beats the thermostat.

On the summer and the winter scenario, over two days of the full virtual building, the
reference MPC (with its disturbance estimate) must use at least 10 % less energy than the
building's own thermostat with no more discomfort, and never leave its input bounds.
"""

import numpy as np
import pytest

from rczone import datasets
from rczone.calibration import calibrate
from rczone.control.closedloop import closed_loop_test
from rczone.control.mpc import MPCSettings

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def fitted_on_c():
    return calibrate(
        "second-order-paper", datasets.load("C"), method="ml", n_starts=1, uncertainty=False
    ).model


@pytest.mark.parametrize("season", ["summer", "winter"])
def test_mpc_with_the_model_fitted_on_c_saves_ten_percent_without_more_discomfort(fitted_on_c, season):
    settings = MPCSettings()
    mpc = closed_loop_test(fitted_on_c, season=season, days=2, seed=11, controller="mpc", settings=settings)
    thermostat = closed_loop_test(fitted_on_c, season=season, days=2, seed=11, controller="thermostat")
    assert mpc.scores["energy_kWh"] <= 0.9 * thermostat.scores["energy_kWh"]
    assert mpc.scores["comfort_Kh"] <= thermostat.scores["comfort_Kh"]
    m, ts = mpc.series["m"], mpc.series["Ts"]
    assert np.all((m >= settings.flow_min) & (m <= settings.flow_max)) and np.all(ts <= settings.ts_max)
