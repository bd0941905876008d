"""The zone's limits: the ventilation minimum follows the thermostat's schedule, per step as the tightest."""

import numpy as np
import pytest

from rczone.control.constraints import ZoneConstraints
from rczone.errors import ParameterError
from rczone.virtual.building import build_building
from rczone.virtual.control import FLOW_LEVELS, VAVController
from rczone.virtual.emulator import thermostat_configs


@pytest.fixture(scope="module")
def cfg():
    return thermostat_configs(build_building(), "summer", np.random.default_rng(4), daily=True)["target"]


def test_the_ventilation_minimum_is_the_flow_the_thermostat_keeps_in_a_cold_room(cfg):
    # a room far below its cooling set point: the thermostat sits at its mode's minimum level
    box = VAVController(cfg, -6 * 3600.0)
    t = -6 * 3600.0 + 60.0 * np.arange(2 * 24 * 60)
    m = np.array([box.step(float(tk), 15.0, 13.0)[0] for tk in t])
    c = ZoneConstraints.from_config(cfg)
    np.testing.assert_array_equal(c.flow_min(t), m)
    assert set(m) == {FLOW_LEVELS[0], FLOW_LEVELS[1]}
    assert c.violations(t, m, np.full(t.size, 20.0)) == 0
    assert (
        c.violations(t, np.full(t.size, FLOW_LEVELS[0]), np.full(t.size, 20.0)) == (m > FLOW_LEVELS[0]).sum()
    )


def test_step_bounds_are_the_tightest_plant_minimum_inside_each_step(cfg):
    c = ZoneConstraints.from_config(cfg)
    t0 = cfg.unocc_end - 3600.0 - 17 * 60.0  # the switch to occupied mode falls inside a step
    b = c.steps(t0, 600.0, 12)
    brute = [max(c.flow_min(np.array([t0 + 600.0 * k + 60.0 * j]))[0] for j in range(10)) for k in range(12)]
    np.testing.assert_array_equal(b.m_min, brute)
    assert b.m_min[0] == FLOW_LEVELS[0] and b.m_min[-1] == FLOW_LEVELS[1]
    np.testing.assert_array_equal(b.ts_max, np.full(12, cfg.ts_max))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"flow_min_occupied": 0.2}, "flow_max"),
        ({"ts_max": float("nan")}, "ts_max"),
        ({"flow_max": 0.0}, "flow"),
    ],
)
def test_impossible_limits_are_refused(cfg, kwargs, match):
    base = ZoneConstraints.from_config(cfg).to_dict()
    with pytest.raises(ParameterError, match=match):
        ZoneConstraints(**{**base, **kwargs})
