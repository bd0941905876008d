"""EnergyPlus as rczone's emulator: the trend holds what EnergyPlus computed, and it can be fitted.

A two-day small office in Chicago (15-minute steps): the zone temperatures and inlet flows the
emulator reads through the API are checked against EnergyPlus's own time-step report, the trend
against those true values (noise and quantization as documented), and ``rczone fit`` runs on the
export as it is. The forced test's set points must be followed by EnergyPlus's thermostat.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("pyenergyplus")

from rczone.cli.main import main
from rczone.emulators.bms import AIR_DENSITY, export, supply_points, zone_point
from rczone.emulators.energyplus import Actuator, EnergyPlusEmulator
from rczone.emulators.idf import IdfObject
from rczone.errors import EmulatorError

ZONE = "Perimeter_ZN_1"


@pytest.fixture(scope="module")
def run():
    em = EnergyPlusEmulator("office_small", "usa_il_chicago", start="01-17", days=2, step_minutes=15)
    return em.run(report=["Zone Mean Air Temperature", "System Node Mass Flow Rate"])


def test_the_readings_are_energyplus_own_output_variables(run):
    rep = run.reported
    assert len(rep) == len(run.frame) == 2 * 96
    for z in run.zones:
        mine = run.frame[f"Ti:{z}"].to_numpy()
        theirs = rep[f"{z.upper()}:Zone Mean Air Temperature [C](TimeStep)"].to_numpy()
        np.testing.assert_allclose(mine, theirs, atol=1e-6)
    for z in run.conditioned:
        for node in run.inlets[z]:
            theirs = rep[f"{node.upper()}:System Node Mass Flow Rate [kg/s](TimeStep)"].to_numpy()
            np.testing.assert_allclose(run.frame[f"m:{node}"].to_numpy(), theirs, atol=1e-6)
    assert run.frame[[f"m:{n}" for z in run.conditioned for n in run.inlets[z]]].to_numpy().max() > 0.05


def test_the_trend_is_the_truth_with_the_documented_sensor_errors(run):
    trend = pd.read_csv(pd.io.common.StringIO(export(run, seed=3).files["trend.csv"]))
    ti = (trend[zone_point(ZONE)].to_numpy() - 32) / 1.8 - run.frame[f"Ti:{ZONE}"].to_numpy()
    assert 0.02 < ti.std() < 0.08 and np.abs(ti).max() < 0.3  # 0.05 K noise, 0.1 F steps
    node = run.inlets[ZONE][0]
    m = trend[supply_points(node)[1]].to_numpy() * AIR_DENSITY / 1000 - run.frame[f"m:{node}"].to_numpy()
    assert np.abs(m).max() < 0.05  # 2 L/s + 3 % noise, 1 L/s steps
    again = export(run, seed=3).files["trend.csv"]
    assert again == export(run, seed=3).files["trend.csv"] != export(run, seed=4).files["trend.csv"]


def test_the_column_map_gives_the_paper_inputs_in_si(run, tmp_path):
    from rczone import load_data
    from rczone.emulators.bms import surroundings

    for name, text in export(run, seed=5).files.items():
        (tmp_path / name).write_text(text)
    data = load_data(tmp_path / "trend.csv", columns=tmp_path / f"{ZONE}.columns.toml", model="second-order")
    truth = run.frame
    node = run.inlets[ZONE][0]
    np.testing.assert_allclose(data["Ti"], truth[f"Ti:{ZONE}"], atol=0.3)
    np.testing.assert_allclose(data["To"], truth["To"], atol=0.3)
    np.testing.assert_allclose(data["Ts"], truth[f"Ts:{node}"], atol=0.3)
    np.testing.assert_allclose(data["m"], truth[f"m:{node}"], atol=0.05)  # L/s at 1.2 kg/m3 -> kg/s
    np.testing.assert_allclose(data["Q"], truth[f"Pel:{ZONE}"], rtol=0.05, atol=10.0)  # kW -> W
    weights = surroundings(run, ZONE)
    assert sum(weights.values()) == pytest.approx(1.0)
    tsd = sum(w * truth[f"Ti:{z}"] for z, w in weights.items())
    np.testing.assert_allclose(data["Tsd"], tsd, atol=0.3)


def test_rczone_fit_runs_on_the_export_as_it_is(run, tmp_path):
    for name, text in export(run, seed=0).files.items():
        (tmp_path / name).write_text(text)
    out = tmp_path / "fit.json"
    rc = main(
        [
            "fit",
            str(tmp_path / "trend.csv"),
            "--columns",
            str(tmp_path / f"{ZONE}.columns.toml"),
            "--model",
            "second-order",
            "--starts",
            "1",
            "--no-profiles",
            "--json",
            str(out),
        ]
    )
    assert rc in (0, 3)
    res = json.loads(out.read_text())
    assert res["open_loop_rmse_K"] < 2.0  # the zone swings 5 K between night setback and day


def test_the_forced_test_is_followed_by_the_thermostat(tmp_path):
    rc = main(
        [
            "emulate",
            "--building",
            "office_small",
            "--start",
            "07-10",
            "--days",
            "1",
            "--step",
            "15",
            "--test",
            "forced",
            "--zones",
            "perimeter_zn_1",
            "-o",
            str(tmp_path),
        ]
    )
    assert rc == 0
    trend = pd.read_csv(tmp_path / "trend.csv")
    sp = (trend[f"{ZONE} heating SP"] - 32) / 1.8
    ti = (trend[zone_point(ZONE)] - 32) / 1.8
    assert sp.min() == pytest.approx(18.0) and sp.max() == pytest.approx(25.0)
    # an hour after a change, the zone is warmer under the high set points than under the low ones
    settled = sp == sp.shift(4)
    high, low = ti[settled & (sp > 20)].mean(), ti[settled & (sp < 20)].mean()
    assert high - low > 2.0, (high, low)
    assert (tmp_path / f"{ZONE}.columns.toml").exists() and (tmp_path / "building.toml").exists()


@pytest.mark.parametrize(
    "args, match",
    [
        (["--building", "office_smal"], "did you mean 'office_small'"),
        (["--building", "office_small", "--weather", "chicago"], "usa_il_chicago"),
        (["--building", "office_small", "--start", "12-31", "--days", "2"], "outside the weather file"),
        (["--building", "office_small", "--test", "forced", "--zones", "core"], "did you mean 'Core_ZN'"),
        (["--building", "office_small", "--test", "forcd"], "did you mean 'forced'"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, match, tmp_path, capsys):
    assert main(["emulate", *args, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and match in err and err.startswith("error:")
    assert not (tmp_path / "out").exists()


def test_an_actuator_energyplus_refuses_is_one_line():
    em = EnergyPlusEmulator("office_small", "usa_il_chicago", start="01-17", days=1, step_minutes=60)
    act = {"x": Actuator("Zone Temperature Control", "Heating Setpoint", "NO_SUCH_ZONE")}
    with pytest.raises(EmulatorError, match="refuses the actuator Zone Temperature Control"):
        em.run(lambda t, r: {"x": 20.0}, act)


def test_a_failed_run_quotes_energyplus_severe_errors():
    em = EnergyPlusEmulator("office_small", "usa_il_chicago", start="01-17", days=1, step_minutes=60)
    em._objects = (*em._objects, IdfObject("Zone", ("Core_ZN",)))  # a second zone of that name
    with pytest.raises(EmulatorError, match=r"EnergyPlus failed \(office_small\): .*Core_ZN"):
        em.run()


def test_the_plant_steps_energyplus_and_its_set_points_are_followed():
    from rczone.emulators.plant import EnergyPlusPlant

    plant = EnergyPlusPlant(
        "office_small", "usa_il_chicago", zones=[ZONE], start="01-17", days=1, step_minutes=30
    )
    try:
        first = plant.measure()
        assert first["time"] == plant.dt and set(first) >= {"To", f"Ti_{ZONE}", f"m_{ZONE}", f"Ts_{ZONE}"}
        with pytest.raises(EmulatorError, match="do not follow flow"):
            plant.step({f"m_{ZONE}": 0.2})
        fc = plant.forecast(7200.0, interval=1800.0)
        assert fc["To"].shape == (5,) and abs(fc["To"][0] - first["To"]) < 1.5
        low = {f"heating_{ZONE}": 12.0, f"cooling_{ZONE}": 21.0}  # the lowest the limits allow
        ti = [plant.step(low if k < 12 else {f"Tset_{ZONE}": 25.0})[f"Ti_{ZONE}"] for k in range(24)]
        assert ti[-1] > 23.5 and ti[11] < 21.5 and ti[-1] - ti[11] > 2.0
        asked = plant.series(ZONE)["heating_asked"]
        assert asked[-1] == 24.0  # Tset 25 asks 24.5 for heating: clipped to the limit
        k = plant.kpis()
        assert k["energy_kWh"] > 0 and k["comfort_Kh"] >= 0 and k["peak_power_kW"] > 0
    finally:
        plant.close()
    with pytest.raises(EmulatorError, match="closed"):
        plant.measure()


@pytest.mark.slow
def test_the_inlet_flows_of_a_floor_add_up_to_its_air_handler_supply():
    """Mass balance of the medium office's VAV loops: each floor's splitter inlet (EnergyPlus's own
    report) carries the sum of the inlet-node flows the emulator read for that floor's zones.

    At 15-minute steps EnergyPlus takes one HVAC step per zone step here, so the two agree to
    rounding; at 60-minute steps it takes sub-steps, its report averages them and the emulator
    reads the last (as a BMS samples), and they differ by up to 1 % (measured).
    """
    em = EnergyPlusEmulator("office_medium", "usa_il_chicago", start="01-17", days=1, step_minutes=15)
    run = em.run(report=["System Node Mass Flow Rate"])
    for floor, tag in ((1, "BOT"), (2, "MID"), (3, "TOP")):
        zones = [z for z in run.conditioned if run.geometry.zone(z).floor == floor]
        assert len(zones) == 5
        mine = sum(run.frame[f"m:{n}"].to_numpy() for z in zones for n in run.inlets[z])
        ahu = run.reported[
            f"PACU_VAV_{tag} ZONE EQUIPMENT INLET NODE:System Node Mass Flow Rate [kg/s](TimeStep)"
        ]
        np.testing.assert_allclose(mine, ahu.to_numpy(), rtol=1e-9, atol=1e-12)
        assert ahu.max() > 1.0  # the AHU ran during the day


def test_a_file_in_place_of_the_folder_is_one_line_before_energyplus_runs(tmp_path, capsys):
    (tmp_path / "taken").write_text("x")
    assert main(["emulate", "--building", "office_small", "-o", str(tmp_path / "taken")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
