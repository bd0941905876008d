"""``rczone control-test --emulator house``: the MPC and the thermostat on a house with an electric heater.

Both are held to the heater's limit (``--heat-limit``), checked against every command the plant
recorded; the MPC keeps the comfort band at least as well as the commissioned thermostat.
"""

import json

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.control.house import HousePlant
from rczone.emulators import registry

LIMIT = 2000.0


@pytest.fixture
def plants(monkeypatch):
    """The plants the CLI makes under the name ``house``, kept for their recorded commands."""
    made = []

    def house(**options):
        made.append(HousePlant(**options))
        return made[-1]

    monkeypatch.setitem(registry._BUILTINS, "house", house)
    return made


def run(tmp_path, controller, seed, days):
    out = tmp_path / f"{controller}{seed}.json"
    args = ["control-test", "--emulator", "house", "--model", "TiTh+heater", "--controller", controller]
    extra = ["--days", str(days), "--seed", str(seed), "--heat-limit", str(LIMIT), "--json", str(out)]
    assert main([*args, *extra]) == 0
    return json.loads(out.read_text())


def held_to_the_limit(plant):
    cmd = plant.command[: plant.k]
    assert plant.k == plant.command.size and np.all((cmd >= 0.0) & (cmd <= LIMIT))
    assert np.array_equal(cmd, plant.power[: plant.k])  # nothing was clipped by the heater


@pytest.mark.parametrize("controller", ["thermostat", "mpc"])
def test_both_controllers_run_the_house_within_the_heater_limit(tmp_path, capsys, plants, controller):
    doc = run(tmp_path, controller, 0, 0.25)
    held_to_the_limit(plants[0])
    assert doc["constraint_violations"] == 0 and doc["peak_power_kW"] <= LIMIT / 1e3
    assert doc["setup"]["constraints"]["house"]["heat_max_W"] == LIMIT
    assert "heater's limits" in capsys.readouterr().out


@pytest.mark.slow
def test_the_mpc_keeps_the_band_at_least_as_well_as_the_thermostat_over_two_seeds(tmp_path, plants):
    comfort = {"mpc": 0.0, "thermostat": 0.0}
    for seed in (0, 1):
        for controller in comfort:
            doc = run(tmp_path, controller, seed, 1)
            held_to_the_limit(plants[-1])
            assert plants[-1].power.max() == pytest.approx(LIMIT)  # the limit binds (the recovery)
            comfort[controller] += doc["comfort_Kh"]
    assert comfort["mpc"] <= comfort["thermostat"]


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--heat-limit", "-5"], "heat_limit"),
        (["--heat-limit", "nan"], "heat_limit"),
        (["--days", "0"], "days"),
        (["--price", "free"], "free"),
        (["--controller", "oracle"], "oracle"),
        (["--controller", "mpc", "--model", "second-order"], "heater input"),
        (["--emulator", "virtual", "--heat-limit", "100"], "--heat-limit"),
    ],
)
def test_house_mistakes_are_one_line_and_exit_2(tmp_path, capsys, extra, match):
    out = tmp_path / "scores.json"
    args = ["control-test", "--emulator", "house", "--model", "TiTh+heater", "--controller", "thermostat"]
    assert main([*args, *extra, "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err
    assert not out.exists()
