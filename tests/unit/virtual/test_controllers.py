"""Any controller can run a zone of the virtual building (the ZoneController protocol)."""

from __future__ import annotations

import numpy as np

from rczone.virtual.building import build_building
from rczone.virtual.control import ObservingController, VAVController, ZoneController
from rczone.virtual.emulator import DAY, ForcedController, day_gain_share, run, thermostat_configs
from rczone.virtual.scenarios import forced_schedule


def test_a_callers_controller_reproduces_the_built_in_forced_run():
    bld = build_building()
    cmds = forced_schedule(np.random.default_rng(1))
    ref = run(
        bld, "autumn", np.random.default_rng(3), duration=4 * 3600.0, warmup=3600.0, forced={"target": cmds}
    )
    cfg = thermostat_configs(bld, "autumn", np.random.default_rng(3), warmup=3600.0)["target"]
    mine = ForcedController(cmds, VAVController(cfg, -3600.0))
    assert isinstance(mine, ZoneController) and not isinstance(mine, ObservingController)
    got = run(
        bld,
        "autumn",
        np.random.default_rng(3),
        duration=4 * 3600.0,
        warmup=3600.0,
        controllers={"target": mine},
    )
    np.testing.assert_array_equal(got.x, ref.x)
    np.testing.assert_array_equal(got.u, ref.u)


class Recorder:
    """A constant-flow controller that records what the building shows it."""

    def __init__(self) -> None:
        self.seen: list[dict] = []

    def observe(self, t, readings):
        self.seen.append({"t": t, **readings})

    def step(self, t, t_sensed, t_ahu):
        return 0.05, t_ahu + 2.0


def test_an_observing_controller_reads_every_sensor_before_each_step():
    bld = build_building()
    rec = Recorder()
    assert isinstance(rec, ObservingController)
    r = run(
        bld, "summer", np.random.default_rng(0), duration=1800.0, warmup=600.0, controllers={"target": rec}
    )
    assert len(rec.seen) == len(r.u)
    assert set(rec.seen[0]) == {"t", "To", *bld.air_nodes.values()}
    np.testing.assert_array_equal([s["Ti"] for s in rec.seen], r.sensed["target"][:-1])
    np.testing.assert_array_equal([s["To"] for s in rec.seen], r.t_out)
    np.testing.assert_array_equal(r.flow("m_target"), 0.05)
    np.testing.assert_allclose(r.input("Ts_target"), r.t_ahu + 2.0)


def test_daily_runs_repeat_the_schedule_and_the_daytime_gains():
    cfg = thermostat_configs(build_building(), "summer", np.random.default_rng(0), daily=True)["target"]
    for t in (2 * 3600.0, 6 * 3600.0, 10 * 3600.0):
        assert cfg.unoccupied(t) and cfg.unoccupied(t + DAY) and cfg.unoccupied(t + 2 * DAY)
    assert not cfg.unoccupied(20 * 3600.0) and not cfg.unoccupied(20 * 3600.0 + DAY)
    assert day_gain_share(20 * 3600.0, True) == 1.0 and day_gain_share(3 * 3600.0, True) == 0.0
    assert day_gain_share(20 * 3600.0, False) == 0.0 and day_gain_share(-2 * 3600.0, False) == 1.0
    assert day_gain_share(DAY - 1800.0, True) == 0.5
