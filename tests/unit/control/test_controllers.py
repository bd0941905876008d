"""The built-in controllers: the commissioned thermostat's set points and early start, the oracle's truth."""

import numpy as np
import pytest

from rczone.control.controllers import (
    MAX_LEAD,
    SETPOINT_MARGIN_K,
    CommissionedThermostat,
    commissioned,
)
from rczone.control.registry import make_controller
from rczone.control.signals import tighten
from rczone.control.virtualplant import VirtualPlant
from rczone.virtual.building import build_building
from rczone.virtual.control import FLOW_LEVELS
from rczone.virtual.emulator import DAY_GAIN, thermostat_configs

H = 3600.0


@pytest.fixture(scope="module")
def cfg():
    return thermostat_configs(build_building(), "winter", np.random.default_rng(4), daily=True)["target"]


def test_commissioned_set_points_sit_inside_the_band_with_the_staging_threshold_below_its_top(cfg):
    c = commissioned(cfg)
    assert c.heat_occ == pytest.approx(cfg.heat_occ + SETPOINT_MARGIN_K)
    assert c.cool_occ + c.band_up == pytest.approx(cfg.cool_occ - SETPOINT_MARGIN_K)
    assert (c.heat_unocc, c.cool_unocc, c.unocc_end) == (cfg.heat_unocc, cfg.cool_unocc, cfg.unocc_end)
    narrow = commissioned(tighten(cfg, 0.3))  # too narrow for the margins: the deadband is kept
    assert narrow.cool_occ - narrow.heat_occ == pytest.approx(0.2)


def forecast(hours_to_occupancy, n=181):
    occ = (np.arange(n) * 60.0 >= hours_to_occupancy * H).astype(float)
    return {"occupied_target": occ}


@pytest.mark.parametrize(
    ("below", "hours", "early"),
    [
        (4.0, 1.0, True),  # 4 K below the set point: lead 3 h (capped) > 1 h to go
        (4.0, 3.2, False),  # beyond the longest lead
        (-0.1, 1.0, False),  # at the set point: lead 30 min < 1 h to go
        (-0.1, 0.4, True),
        (1.0, 1.4, True),  # 1 K below: lead 1.5 h
        (1.0, 1.6, False),
    ],
)
def test_the_optimal_start_switches_to_occupied_mode_when_the_lead_reaches_occupancy(
    cfg, below, hours, early
):
    box = CommissionedThermostat(cfg, t_start=-6 * H)
    ti = commissioned(cfg).heat_occ - below
    t = cfg.unocc_start + 2 * H  # deep in the unoccupied period
    a = box.act(t, {"Ti_target": ti, "T_ahu": 15.0}, forecast(hours))
    assert box.box.early is early
    assert a["m_target"] == (FLOW_LEVELS[1] if early else FLOW_LEVELS[0])
    assert box.lead(ti) <= MAX_LEAD


def test_the_oracle_reads_the_true_temperature_and_the_true_gains():
    plant = VirtualPlant("summer", days=0.02, seed=3)
    ctrl = make_controller("oracle", plant)
    y = plant.measure()
    fc = plant.true_forecast(ctrl.horizon, interval=ctrl.interval)
    mf = ctrl.model_forecast(y, fc)
    t = fc["time"]
    day = (t % 86400.0 >= 14 * H) & (t % 86400.0 < 23 * H)  # 8 am to 5 pm: the full daytime gain
    np.testing.assert_allclose(mf.inputs["Q"][day], 50.0 + DAY_GAIN["target"])
    assert plant.true_temperature() != y["Ti_target"]  # the sensor's noise and resolution
    a = ctrl.act(y["time"], y, plant.forecast(0.0))
    assert a["m_target"] >= fc["m_min_target"][0] - 1e-9
