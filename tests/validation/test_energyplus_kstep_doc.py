"""docs/energyplus.md's k-step closed-loop table is the one its script makes from the runs it recorded."""

from __future__ import annotations

import json

from tests.validation.scripts import ROOT, load_script


def test_the_docs_table_is_the_scripts_table_of_the_recorded_runs() -> None:
    mod = load_script("energyplus_kstep")
    store = json.loads((ROOT / "validation" / "energyplus_kstep.json").read_text())
    assert {r["fit"] for r in store["runs"]} >= {"ml", "kstep"}
    page = (ROOT / "docs" / "energyplus.md").read_text()
    assert mod.table(store["runs"]) in page
    assert mod.fits_table(store["fits"]) in page


def _row(fit: str | None, seed: int, cost: float, comfort_kh: float) -> dict:
    return {
        "season": "winter",
        "controller": "mpc" if fit else "baseline",
        "fit": fit,
        "seed": seed,
        "days": 2,
        "margin": 0.1 if fit else None,
        "cost": cost,
        "energy_kWh": cost / 2,
        "comfort_Kh": comfort_kh,
        "peak_power_kW": 1.0,
        "prediction_rmse_K": 0.2,
        "prediction_1h_rmse_K": 0.5,
        "open_loop_rmse_K": 1.0,
        "solve_ms": 5.0 if fit else None,
        "wall_s": 60.0,
        "cpu_s": 30.0,
        "load_1min": 4.0,
        "date": "2026-12-02",
    }


def test_the_pairs_are_by_seed_and_the_verdict_follows_the_numbers() -> None:
    mod = load_script("energyplus_kstep")
    ml = [_row("ml", s, c, 1.0) for s, c in enumerate((100.0, 110.0, 120.0))]
    # k-step 5 % cheaper on every seed (paired differences -5, -5.5, -6): beyond 2 s.e. and 1 %
    cheaper = [_row("kstep", s, 0.95 * c, 1.0 + 0.01 * s) for s, c in enumerate((100.0, 110.0, 120.0))]
    p = mod.paired(ml + cheaper, "winter", 0.1, "cost", False)
    assert p["seeds"] == [0, 1, 2]
    assert abs(p["mean"] + 5.5) < 1e-9 and abs(p["se"] - 0.5 / 3**0.5) < 1e-9
    assert p["verdict"] == "better"
    # comfort is per zone-day: the differences 0, 0.005, 0.01 K h per day, under 1 % of 0.5: no difference
    c = mod.paired(ml + cheaper, "winter", 0.1, "comfort_Kh", True)
    assert abs(c["ml"] - 0.5) < 1e-12 and c["verdict"] == "no difference"
    # a k-step run without its ML partner is left out of the pairs
    assert mod.paired(ml[:2] + cheaper, "winter", 0.1, "cost", False)["seeds"] == [0, 1]
    text = mod.table([_row(None, 0, 105.0, 2.0), *ml, *cheaper])
    assert "| winter | 0.1 | HVAC cost | 105.000 | 110.000 | 104.500 | -5.500 ± 0.289 | better | 3 |" in text
    assert "| winter | 0.1 | comfort K h per zone-day | 1.000 |" in text
    # runs at another margin are paired among themselves, not with these
    other = [{**r, "margin": 0.0, "cost": r["cost"] + 50} for r in ml[:1] + cheaper[:2]]
    assert mod.paired(ml + cheaper + other, "winter", 0.1, "cost", False)["mean"] == p["mean"]
    assert mod.paired(ml + cheaper + other, "winter", 0.0, "cost", False)["seeds"] == [0]


def test_the_recorded_kstep_fits_lowered_their_criterion() -> None:
    """The criterion recomputed from each saved k-step model is its fit's objective (to 1 %), and below the ML fit's."""
    fits = json.loads((ROOT / "validation" / "energyplus_kstep.json").read_text())["fits"]
    for season in fits.values():
        kstep, ml = season["kstep"], season["ml"]
        assert abs(kstep["criterion_K2"] / kstep["objective_value"] - 1) < 1e-2  # summer: 0.09 %
        assert kstep["criterion_K2"] < ml["criterion_K2"]
