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
