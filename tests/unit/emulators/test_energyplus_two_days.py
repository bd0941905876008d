"""Issue 35's fast check in ``make test``: a two-day closed loop of the small office on EnergyPlus.

The slow acceptance tests (tests/acceptance/test_energyplus_control.py)
run 15-minute loops, the medium office and several zones.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("pyenergyplus")

from rczone.cli.main import main

ZONE = "Perimeter_ZN_1"


def test_a_two_day_small_office_loop_under_the_mpc(tmp_path):
    out = tmp_path / "loop.json"
    args = ["control-test", "--emulator", "energyplus", "--building", "office_small", "--zone", ZONE]
    args += ["--start", "01-17", "--days", "2", "--step", "15", "--price", "tou", "--forecast", "medium"]
    args += ["--controller", "mpc", "--model", "second-order", "--seed", "1", "--json", str(out)]
    assert main(args) == 0
    res = json.loads(out.read_text())
    assert res["emulator"] == "energyplus" and res["setup"]["days"] == 2
    # scored by EnergyPlus's meters: every HVAC kWh of the building belongs to one of its units
    assert 0 < res["energy_kWh"] < res["building_hvac_kWh"]
    assert abs(res["unattributed_kWh"]) < 1e-6 * res["building_hvac_kWh"]
    assert res["energy_kWh"] < res["cost"] < 3 * res["energy_kWh"]  # time-of-use: 1 to 3 per kWh
    assert res["constraint_violations"] == 0 and res["solve_time_s"]["mean"] > 0
    assert np.isfinite(res["prediction_rmse_K"]) and res["comfort_Kh"] < 2.0
