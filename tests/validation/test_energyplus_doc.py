"""docs/energyplus.md's closed-loop table is the one its script makes from the runs it recorded."""

from __future__ import annotations

import json

from tests.validation.scripts import ROOT, load_script


def test_the_docs_table_is_the_scripts_table_of_the_recorded_runs() -> None:
    mod = load_script("energyplus_closed_loop")
    runs = json.loads((ROOT / "validation" / "energyplus_closed_loop.json").read_text())
    assert {r["season"] for r in runs} == set(mod.SEASONS)
    assert mod.table(runs) in (ROOT / "docs" / "energyplus.md").read_text()


def test_the_verdict_line_follows_the_numbers() -> None:
    mod = load_script("energyplus_closed_loop")
    base = {"season": "winter", "controller": "baseline", "seed": 0, "days": 2, "margin": None, "cost": 10.0}
    base |= {
        "energy_kWh": 5.0,
        "comfort_Kh": 1.0,
        "peak_power_kW": 1.0,
        "prediction_rmse_K": 0.1,
        "solve_ms": None,
    }
    cheaper = {**base, "controller": "mpc", "margin": 0.1, "cost": 9.0, "comfort_Kh": 1.9, "solve_ms": 5.0}
    warmer = {**cheaper, "seed": 1, "comfort_Kh": 2.2}  # +0.6 K h per zone-day
    assert "every seed: yes" in mod.table([base, cheaper])
    assert "every seed: no" in mod.table([base, cheaper, warmer])


def test_the_forced_trend_is_made_once_in_the_climate_asked_and_the_model_fitted_from_it(tmp_path) -> None:
    mod = load_script("energyplus_closed_loop")
    calls = []

    def fake(args: list[str]) -> int:  # what the CLI would do: write the trend, the model
        calls.append(args)
        if args[0] == "emulate":
            folder = tmp_path / args[args.index("-o") + 1]
            folder.mkdir(parents=True)
            (folder / "trend.csv").write_text("t\n")
        return 0

    mod.rczone = fake
    trend = mod.forced_trend(tmp_path / "hot", "summer", weather="usa_az_phoenix")
    assert trend == tmp_path / "hot" / "trend.csv" and trend.exists()
    emulate = calls[0]
    assert emulate[emulate.index("--weather") + 1] == "usa_az_phoenix"
    assert emulate[emulate.index("--start") + 1] == mod.SEASONS["summer"][0]
    mod.forced_trend(tmp_path / "hot", "summer", weather="usa_az_phoenix")
    assert len(calls) == 1  # the trend is reused
    model = mod._model(tmp_path, "winter")  # the closed-loop section's: Chicago, second-order
    emulate, fit = calls[1], calls[2]
    assert emulate[emulate.index("--weather") + 1] == mod.WEATHER == "usa_il_chicago"
    assert fit[0] == "fit" and fit[fit.index("--model") + 1] == "second-order"
    assert fit[fit.index("--save-model") + 1] == str(model) == str(tmp_path / "zone_winter.json")
