"""Options of closed-loop operation: defaults unchanged, each option does what it says."""

from __future__ import annotations

from functools import cache

import numpy as np
import pandas as pd
import pytest

from rczone.errors import ParameterError
from rczone.virtual.building import build_building
from rczone.virtual.control import FLOW_LEVELS
from rczone.virtual.emulator import run
from rczone.virtual.operation import DIFFUSER_MIX, SCHEDULE_GAIN, TIGHT_FLOW, Operation, sensor_reading
from rczone.virtual.scenarios import generate_night
from rczone.virtual.sensors import TEMP_NOISE

WARMUP = 1800.0


@cache
def _run(op: Operation, season: str = "summer", seed: int = 3):
    bld = build_building()
    return bld, run(bld, season, np.random.default_rng(seed), warmup=WARMUP, operation=op)


def test_default_operation_is_the_shipped_one():
    a = generate_night("summer", seed=4, warmup=WARMUP)
    b = generate_night("summer", seed=4, warmup=WARMUP, operation=Operation())
    pd.testing.assert_frame_equal(a, b)
    assert Operation().is_default and Operation().label() == "as shipped"
    assert Operation(loop="tight").label() == "loop=tight"


def test_tight_loop_holds_constant_flow_and_pins_the_room():
    bld, r = _run(Operation(loop="tight"))
    night = (r.t[:-1] >= 3 * 3600.0) & (r.t[:-1] < 10 * 3600.0)  # unoccupied mode, one setpoint
    for z in bld.zones:
        np.testing.assert_array_equal(r.flow(bld.flow_name(z)), TIGHT_FLOW)
    ti = r.state("Ti")[1:][night]
    ts = r.input(bld.supply_name("target"))[night]
    assert np.std(ti) < 0.1 and np.ptp(ts) > 10 * np.std(ti)


def test_scheduled_gains_are_added_only_in_occupied_mode_and_not_reported():
    bld = build_building()
    g = bld.gain_name("target")
    _, base = _run(Operation())
    _, sched = _run(Operation(gains="schedule"))
    extra = sched.input(g) - base.input(g)
    assert set(np.round(np.unique(extra), 9)) <= {0.0, SCHEDULE_GAIN}
    t = sched.t[:-1]
    assert np.all(extra[(t > 2 * 3600) & (t < 10 * 3600)] == 0.0)  # unoccupied in the middle of the night
    assert np.all(extra[(t > -1000) & (t < 0)] == SCHEDULE_GAIN)  # occupied before 6 pm
    df = generate_night("summer", seed=3, warmup=WARMUP, operation=Operation(gains="schedule"))
    np.testing.assert_allclose(df["Q"], 50.0)


def test_sensor_reading_by_hand():
    np.testing.assert_allclose(
        sensor_reading(np.array([22.0]), np.array([13.0]), np.array([0.06]), "room"), 22.0
    )
    got = sensor_reading(np.array([22.0]), np.array([13.0]), np.array([0.06]), "diffuser", mix=0.2)
    np.testing.assert_allclose(got, 22.0 + 0.2 * 0.5 * (13.0 - 22.0))


def test_diffuser_sensor_reads_supply_air_in_proportion_to_flow():
    bld, r = _run(Operation(sensor="diffuser"))
    ti, ts, m = r.state("Ti")[1:], r.input(bld.supply_name("target")), r.flow(bld.flow_name("target"))
    expected = ti + DIFFUSER_MIX * m / FLOW_LEVELS[-1] * (ts - ti)
    resid = r.sensed["target"][1:] - expected
    assert abs(np.mean(resid)) < 0.02 and np.std(resid) < 2 * TEMP_NOISE


def test_trend_resolution_and_deadband():
    df = generate_night("summer", seed=3, warmup=WARMUP, operation=Operation(trend_quantum_F=1.0))
    for c in ("Ti", "Ts", "To", "Tn1"):
        f = df[c].to_numpy() * 1.8 + 32.0
        np.testing.assert_allclose(f, np.round(f), atol=1e-6)
    _, r = _run(Operation(deadband_K=0.5), season="winter")
    _, wide = _run(Operation(), season="winter")
    night = (r.t >= 3 * 3600.0) & (r.t < 10 * 3600.0)
    # a narrow night band keeps the loop working: the room moves less than in the season's wide band
    assert np.ptp(r.state("Ti")[night]) < np.ptp(wide.state("Ti")[night])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"loop": "tite"}, "did you mean 'tight'"),
        ({"gains": "scheduled"}, "did you mean 'schedule'"),
        ({"sensor": "difuser"}, "did you mean 'diffuser'"),
        ({"deadband_K": 0.0}, "deadband_K"),
        ({"trend_quantum_F": -1.0}, "trend_quantum_F"),
        ({"diffuser_mix": 1.0}, "diffuser_mix"),
    ],
)
def test_bad_options(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Operation(**kwargs)
