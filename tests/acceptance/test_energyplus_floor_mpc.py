"""The floor MPC on EnergyPlus: ``control-test --zones Z1,...,Z5 --model floor1.toml --controller mpc``.

The small office's one floor (five zones, the attic above as the measured boundary) under one
centralized MPC with the joint floor model ``rczone models generate --from building.toml --floor 1``
writes (its values from the building's constructions, not fitted: the test is of the loop, not of
an identification), one day at 30-minute steps from a weekday in January: every zone's thermostat
got set points inside the limits every controller has, the zones stayed near their band, and the
MPC's set points are not the building's own.
"""

from __future__ import annotations

import json

import pytest

pytest.importorskip("pyenergyplus")

from rczone.cli.main import main

pytestmark = pytest.mark.slow  # 64 s on 2 busy cores, load 5 (2026-12-02)

ZONES = ["Core_ZN", "Perimeter_ZN_1", "Perimeter_ZN_2", "Perimeter_ZN_3", "Perimeter_ZN_4"]
RUN = ["--building", "office_small", "--start", "01-17", "--days", "1", "--step", "30"]


def test_one_floor_mpc_runs_the_small_offices_five_zones(tmp_path):
    assert main(["emulate", *RUN, "--seed", "1", "-o", str(tmp_path / "trend"), "--quiet"]) == 0
    floor = tmp_path / "floor1.toml"
    assert (
        main(
            [
                "models",
                "generate",
                "--from",
                str(tmp_path / "trend" / "building.toml"),
                "--floor",
                "1",
                "-o",
                str(floor),
            ]
        )
        == 0
    )
    loops = {}
    for controller in ("mpc", "baseline"):
        out = tmp_path / f"{controller}.json"
        args = [
            "control-test",
            "--emulator",
            "energyplus",
            *RUN,
            "--zones",
            ",".join(ZONES),
            "--model",
            str(floor),
        ]
        assert main([*args, "--controller", controller, "--price", "tou", "--json", str(out)]) == 0
        loops[controller] = json.loads(out.read_text())
    mpc, base = loops["mpc"], loops["baseline"]
    assert mpc["emulator"] == "energyplus" and mpc["setup"]["zones"] == ZONES
    assert mpc["setup"]["model"] == "floor1.toml" and mpc["constraint_violations"] == 0
    assert 0 < mpc["energy_kWh"] <= mpc["building_hvac_kWh"] and mpc["solve_time_s"]["mean"] > 0
    for z in ZONES:  # every zone near its band (0.5 K h a zone-day more than the building's own control)
        assert mpc[f"comfort_Kh_{z}"] <= base[f"comfort_Kh_{z}"] + 0.5, z
    assert mpc["cost"] != base["cost"]  # the MPC's set points, not the schedules, ran the building
    # the joint model's prediction in the loop, all zones together, scored per zone
    for z in ZONES:
        assert 0 < mpc[f"prediction_rmse_K_{z}"] < 2.0 and 0 < mpc[f"open_loop_rmse_K_{z}"] < 10.0, z
    assert mpc["prediction_rmse_K"] > 0
