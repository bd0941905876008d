"""The virtual building behind the Plant protocol: the same run as the emulator, forecasts, actions."""

import math

import numpy as np
import pytest

from rczone.control.closedloop import run_loop
from rczone.control.controllers import ThermostatController
from rczone.control.plant import Controller, Plant
from rczone.control.virtualplant import FORECAST_BIAS_K, WARMUP, VirtualPlant
from rczone.errors import ParameterError
from rczone.virtual.building import build_building
from rczone.virtual.emulator import run


def test_the_plant_run_by_the_zones_thermostat_is_the_emulators_own_run():
    plant = VirtualPlant("winter", days=0.1, seed=3)
    assert isinstance(plant, Plant)
    box = ThermostatController(plant.configs["target"], t_start=-WARMUP)
    assert isinstance(box, Controller)
    log = run_loop(plant, box)
    ref = run(
        build_building(), "winter", np.random.default_rng(3), duration=0.1 * 86400, warmup=WARMUP, daily=True
    )
    got = plant.sim.result()
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.m, ref.m, rtol=0, atol=0)
    np.testing.assert_allclose(log.values["Ti_target"], ref.sensed["target"], atol=0)
    np.testing.assert_allclose(log.values["m_target"][1:], ref.flow("m_target"), atol=0)
    assert log.t[0] == -WARMUP and log.t[-1] == plant.end and math.isnan(log.values["m_target"][0])


def test_a_perfect_forecast_is_what_the_plant_then_measures_and_a_biased_one_is_off_by_its_bias():
    perfect, biased = (
        VirtualPlant("summer", days=0.05, seed=1, forecast="perfect"),
        VirtualPlant("summer", days=0.05, seed=1, forecast="biased"),
    )
    measured = VirtualPlant("summer", days=0.05, seed=1)
    fp, fb, fm = (p.forecast(1800.0, interval=600.0) for p in (perfect, biased, measured))
    assert fp["To"].shape == (4,) and fp["m_min_target"].shape == (3,)
    np.testing.assert_allclose(fb["To"], fm["To"] + FORECAST_BIAS_K)
    assert fm["To"][0] == perfect.measure()["To"]  # the measured forecast starts at the measurement
    seen = []
    cfg = perfect.configs["target"]
    box = ThermostatController(cfg, t_start=perfect.time)
    y = perfect.measure()
    while len(seen) < 31:
        seen.append((y["time"], y["To"], y["T_ahu"]))
        y = perfect.step(box.act(y["time"], y, {}))
    seen = np.array(seen)[::10]  # every 600 s
    np.testing.assert_allclose(fp["To"], seen[:, 1], atol=0)
    np.testing.assert_allclose(fp["T_ahu"], seen[:, 2], atol=0)
    assert not np.allclose(fm["To"], seen[:, 1])  # the measured forecast is only a forecast


@pytest.mark.parametrize(
    ("actions", "match"),
    [
        ({"m_target": 0.05}, "Ts_target"),
        ({"m_target": float("nan"), "Ts_target": 20.0}, "finite"),
        ({"m_target": 0.05, "Ts_target": 20.0, "m_trget": 0.1}, "m_trget"),
    ],
)
def test_bad_actions_are_one_line_errors(actions, match):
    plant = VirtualPlant("summer", days=0.01)
    with pytest.raises(ParameterError, match=match):
        plant.step(actions)


def test_the_coil_set_point_is_held_inside_what_the_coil_can_do():
    plant = VirtualPlant("winter", days=0.01, seed=2)
    y = plant.measure()
    for _ in range(30):
        y = plant.step({"m_target": 0.08, "Ts_target": 80.0})
    assert y["Ts_target"] <= plant.limits["target"].ts_max and y["Ts_target"] > 33.0
    y = plant.step({"m_target": 0.08, "Ts_target": -40.0})  # cannot cool below the AHU's air
    assert y["Ts_target"] > y["T_ahu"]
    while plant.time < plant.end:
        plant.step({"m_target": 0.5, "Ts_target": 20.0})
    assert plant.measure()["m_target"] == plant.limits["target"].flow_max  # the damper's travel
    with pytest.raises(ParameterError, match="ended"):
        plant.step({"m_target": 0.05, "Ts_target": 20.0})
