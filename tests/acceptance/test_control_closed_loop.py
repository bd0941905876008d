"""The MPC against the thermostat under the same limits, with the 2-state model fitted on night C.

Issue 33: the MPC's flow floor was once 0.02 kg/s at every hour while the thermostat kept the
occupied ventilation minimum of 0.05 kg/s, and the "saving" was that difference. Both are now
held to the zone's constraints (the ventilation minimum by the schedule), the results record
them, and a comparison refuses runs with different ones. Over two days of the full virtual
building (seed 11) the reference MPC with its disturbance estimate stays much closer to the band
than the building's own (naive) thermostat for about the thermostat's energy (measured +1 % in summer, +11 % in winter),
and neither leaves the zone's limits.
"""

import numpy as np
import pytest

from rczone import datasets
from rczone.calibration import calibrate
from rczone.control.closedloop import check_comparable, closed_loop_test
from rczone.control.constraints import ZoneConstraints
from rczone.control.mpc import MPCSettings
from rczone.control.virtualplant import VirtualPlant

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def fitted_on_c():
    return calibrate(
        "second-order-paper", datasets.load("C"), method="ml", n_starts=1, uncertainty=False
    ).model


@pytest.mark.parametrize("season", ["summer", "winter"])
def test_under_equal_limits_the_mpc_buys_comfort_not_energy(fitted_on_c, season):
    settings = MPCSettings()
    mpc = closed_loop_test(VirtualPlant(season, days=2, seed=11), "mpc", model=fitted_on_c, settings=settings)
    thermostat = closed_loop_test(VirtualPlant(season, days=2, seed=11), "naive", model=fitted_on_c)
    check_comparable(mpc, thermostat)
    assert mpc.scores["comfort_Kh"] <= 0.5 * thermostat.scores["comfort_Kh"]
    assert mpc.scores["energy_kWh"] <= 1.2 * thermostat.scores["energy_kWh"]
    limits = ZoneConstraints(**mpc.setup["constraints"]["target"])
    m, ts = mpc.series["m"], mpc.series["Ts"]
    assert (
        np.all(m >= limits.flow_min(mpc.t))
        and np.all(m <= settings.flow_max)
        and np.all(ts <= settings.ts_max)
    )
    assert mpc.scores["constraint_violations"] == thermostat.scores["constraint_violations"] == 0
