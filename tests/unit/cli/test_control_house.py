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
        (["--compare", "thermostat,mpc"], "run each controller alone"),
        # an option another emulator reads is refused, not silently ignored
        (["--band", "tight"], "--band is read by --emulator virtual only"),
        (["--scenario", "winter"], "--scenario is read by --emulator virtual only"),
        (["--building", "office_small"], "--building is read by --emulator energyplus only"),
        (["--emulator", "virtual", "--margin", "0.2"], "--margin is read by --emulator energyplus only"),
    ],
)
def test_house_mistakes_are_one_line_and_exit_2(tmp_path, capsys, extra, match):
    out = tmp_path / "scores.json"
    args = ["control-test", "--emulator", "house", "--model", "TiTh+heater", "--controller", "thermostat"]
    assert main([*args, *extra, "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err
    assert not out.exists()


def heater_record(path, days=4, seed=5):
    """A 10-min record of the house under random heater steps (hourly, 0 to 3 kW): a heater test."""
    plant = HousePlant(days=days, seed=seed)
    rng = np.random.default_rng(1)
    rows, level = [], 0.0
    while plant.time < plant.end - 1e-9:
        if plant.k % 60 == 0:
            level = float(rng.choice([0.0, 1000.0, 2000.0, 3000.0]))
        to = plant.measure()["To"]
        y = plant.step({"P_house": level})
        rows.append((y["time"], y["Ti_house"], to, level))
    t, ti, to, ph = np.array(rows[9::10]).T
    stamps = np.datetime64("2026-01-01T00:00") + ((t - t[0]) * 1e3).astype("timedelta64[ms]")
    lines = ["time,Ti,To,Ph"] + [f"{s},{a:.4f},{b:.4f},{c:.1f}" for s, a, b, c in zip(stamps, ti, to, ph)]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.slow
def test_a_model_fitted_on_a_heater_record_runs_the_house_from_the_cli(tmp_path, plants):
    # the user's path: a heater test, `rczone fit` of the TiTe+heater family, then the closed loop
    heater_record(tmp_path / "heater.csv")
    fitted = tmp_path / "fitted.json"
    fit = ["fit", str(tmp_path / "heater.csv"), "--model", "TiTe+heater", "--save-model", str(fitted)]
    assert main([*fit, "--no-profiles", "--quiet"]) in (0, 3)  # 3: Te collapses (a 1-state house)
    out = tmp_path / "mpc.json"
    args = ["control-test", "--emulator", "house", "--model", str(fitted), "--controller", "mpc"]
    assert main([*args, "--days", "1", "--heat-limit", str(LIMIT), "--json", str(out)]) == 0
    held_to_the_limit(plants[-1])
    thermostat = run(tmp_path, "thermostat", 0, 1)
    assert json.loads(out.read_text())["comfort_Kh"] <= thermostat["comfort_Kh"]
