"""docs/energyplus.md's "Q2 in closed loop" tables are the ones validation/energyplus_q2_closed_loop.py
makes from its recorded runs, and its pairs are by seed, normal-operation fit minus forced-test fit."""

from __future__ import annotations

import argparse
import json

import pytest

from tests.validation.scripts import ROOT, load_script


def test_the_docs_tables_are_the_scripts_tables_of_the_recorded_runs() -> None:
    mod = load_script("energyplus_q2_closed_loop")
    store = json.loads((ROOT / "validation" / "energyplus_q2_closed_loop.json").read_text())
    assert {f["fit"] for f in store["fits"]} == {"calibration", "forced"}
    assert {r["fit"] for r in store["runs"]} == {None, "calibration", "forced"}
    page = (ROOT / "docs" / "energyplus.md").read_text()
    assert mod.eq2.in_doc(page, markers=(mod.BEGIN, mod.END)) == mod.table(store)


def test_the_recorded_models_are_the_ones_of_the_q2_tables() -> None:
    mod = load_script("energyplus_q2_closed_loop")
    store = json.loads((ROOT / "validation" / "energyplus_q2_closed_loop.json").read_text())
    q2 = json.loads((ROOT / "validation" / "energyplus_q2.json").read_text())
    for f in store["fits"]:
        row = mod.q2_row(q2, f["climate"], f["season"], f["fit"])
        assert mod.check_model(f["estimates"], row) == f["estimates"]
        assert f["heldout"]["open"] == row["heldout"]["open"]["model"]


def _run(fit: str | None, seed: int, cost: float, comfort_kh: float, *, climate: str = "c") -> dict:
    return {
        "climate": climate, "season": "summer", "controller": "mpc" if fit else "baseline", "fit": fit,
        "seed": seed, "days": 2, "margin": 0.0 if fit else None, "cost": cost, "energy_kWh": cost / 2,
        "comfort_Kh": comfort_kh, "prediction_rmse_K": 0.3, "prediction_1h_rmse_K": 0.6,
        "open_loop_rmse_K": 1.2 if fit == "forced" else 0.9, "wall_s": 5.0, "cpu_s": 3.0, "load_1min": 2.0,
        "date": "2026-12-02",
    }  # fmt: skip


def test_the_pairs_are_normal_fit_minus_forced_fit_by_seed() -> None:
    mod = load_script("energyplus_q2_closed_loop")
    # costs by hand: forced 200, 210, 220 and normal 190, 202, 209 -> differences -10, -8, -11,
    # mean -29/3, sample s.d. sqrt(7/3), s.e. sqrt(7/9); beyond 2 s.e. (1.76) and 1 % of 210 (2.1)
    forced = [_run("forced", s, c, 1.0) for s, c in enumerate((200.0, 210.0, 220.0))]
    normal = [_run("calibration", s, c, 3.0) for s, c in enumerate((190.0, 202.0, 209.0))]
    stray = [_run("calibration", 7, 0.0, 0.0), _run("calibration", 0, 0.0, 0.0, climate="d")]
    runs = [_run(None, 0, 205.0, 0.4), *forced, *normal]
    p = mod.eq1.paired(runs + stray, ("c", "summer"), 0.0, "cost", False, fits=mod.FITS)
    assert p["seeds"] == [0, 1, 2] and p["verdict"] == "better"
    assert p["mean"] == pytest.approx(-29 / 3) and p["se"] == pytest.approx((7 / 9) ** 0.5)
    assert p["one"] == pytest.approx(601 / 3) and p["two"] == pytest.approx(210.0)
    # comfort per zone-day: 1.5 against 0.5 on every seed, no spread -> worse for the normal fit
    c = mod.eq1.paired(runs, ("c", "summer"), 0.0, "comfort_Kh", True, fits=mod.FITS)
    assert c["mean"] == pytest.approx(1.0) and c["verdict"] == "worse"
    text = mod.eq1.loop_table(runs, fits=mod.FITS, short=mod.SHORT, names=mod.NAMES)
    assert "| MPC, normal-fit | MPC, forced-fit | normal-fit − forced-fit (mean ± s.e.) |" in text
    assert (
        "| c | summer | 0 | HVAC cost | 205.000 | 200.333 | 210.000 | -9.667 ± 0.882 | better | 3 |" in text
    )
    assert "| c | summer | 0 | open-loop RMSE K |  | 0.900 | 1.200 | -0.300 ± 0.000 | better | 3 |" in text
    # against the baseline (cost 205, comfort 0.2 K h per zone-day): the normal fit's MPC is cheaper on
    # seeds 0 and 1 only and +1.3 K h per zone-day; the forced fit's dearer on seeds 1 and 2
    lines = [line for line in text.splitlines() if line.startswith("- c, summer")]
    assert lines[0].startswith(
        "- c, summer, margin 0 K, normal-fit MPC: cost 200.33 against the baseline's 205.00"
    )
    assert "(-2.3 %), comfort +1.30 K h per zone-day" in lines[0] and lines[0].endswith("every seed: no")
    assert lines[1].startswith("- c, summer, margin 0 K, forced-fit MPC: cost 210.00") and len(lines) == 2


def test_a_saved_model_that_is_not_q2s_stops_the_script() -> None:
    mod = load_script("energyplus_q2_closed_loop")
    est = {p: {"estimate": 1.0 + i} for i, p in enumerate(mod.eq2.PARAMS)}
    row = {"climate": "c", "season": "winter", "training": "forced", "estimates": est}
    theta = {p: e["estimate"] for p, e in est.items()}
    assert mod.check_model(theta, row) == theta
    with pytest.raises(SystemExit, match="R1 differ"):
        mod.check_model({**theta, "R1": theta["R1"] * (1 + 1e-2)}, row)
    assert mod.check_model({**theta, "R1": theta["R1"] * (1 + 1e-5)}, row) == theta  # the tables' digits
    with pytest.raises(SystemExit, match="no fit of c, summer, forced"):
        mod.q2_row([{**row, "replicate": 0}], "c", "summer", "forced")
    assert mod.q2_row([{**row, "replicate": 1}, row], "c", "winter", "forced") is row


def test_the_models_table_names_the_fits_and_gives_q2s_held_out_errors() -> None:
    mod = load_script("energyplus_q2_closed_loop")
    est = dict.fromkeys(mod.eq2.PARAMS, 0.00123)
    fits = [
        {"climate": "c", "season": "winter", "fit": f, "exit_code": e, "estimates": est,
         "heldout": {"1 h": 0.5, "6 h": None, "open": 1.234}}
        for f, e in (("forced", 0), ("calibration", 3))
    ]  # fmt: skip
    rows = mod.models_table(fits).splitlines()[2:]
    assert (
        rows[0]
        == "| c | winter | normal-fit | 3 | 0.00123 | 0.00123 | 0.00123 | 0.00123 | 0.00123 | 0.50 / unstable / 1.23 |"
    )
    assert rows[1].startswith("| c | winter | forced-fit | 0 |")


def test_the_loop_runs_the_baseline_once_then_both_fits_per_seed_and_skips_what_is_stored(
    monkeypatch, tmp_path
) -> None:
    mod = load_script("energyplus_q2_closed_loop")
    calls = []

    def run(folder, season, fit, seed, days, model, margin, *, weather):
        calls.append((fit, seed, margin, model.name))
        return {"season": season, "fit": fit, "seed": seed, "days": days, "margin": margin if fit else None}

    monkeypatch.setattr(mod.eq1.eks, "run", run)
    a = argparse.Namespace(margins="0,0.25", seeds=2, days=2)
    stored = {"climate": "c", "season": "winter", "fit": "forced", "seed": 1, "days": 2, "margin": 0.25}
    store, saves = {"runs": [stored]}, []
    paths = {"calibration": tmp_path / "n.json", "forced": tmp_path / "f.json"}
    mod.eq1.run_loop(tmp_path, store, ("c", "winter"), a, paths, lambda: saves.append(1))
    assert calls[0] == (None, 0, 0.0, "f.json")  # the baseline first, once; it reads no model
    assert calls[1:5] == [
        ("calibration", 0, 0.0, "n.json"), ("forced", 0, 0.0, "f.json"),
        ("calibration", 1, 0.0, "n.json"), ("forced", 1, 0.0, "f.json"),
    ]  # fmt: skip
    assert ("forced", 1, 0.25, "f.json") not in calls and len(calls) == 8 == len(saves)
    assert all(r["climate"] == "c" for r in store["runs"]) and len(store["runs"]) == 9


def test_outside_band_counts_the_occupied_kelvin_hours_on_each_side_and_the_raised_cooling_set_point() -> (
    None
):
    import pandas as pd

    mod = load_script("energyplus_q2_closed_loop")
    frame = pd.DataFrame(
        {
            "Ti": [25.0, 20.0, 26.0, 22.0],
            "lower": [21.0] * 4,
            "upper": [24.0] * 4,
            "occupied": [1, 1, 0, 1],
            "cooling_sp": [25.0, 24.0, 30.0, 24.5],
        }
    )
    # occupied steps 0, 1, 3 of a quarter hour: 1 K above, 1 K below; step 2 (26 degC) is unoccupied
    got = mod.outside_band(frame, 0.25)
    assert got["above_Kh"] == pytest.approx(0.25) and got["below_Kh"] == pytest.approx(0.25)
    assert got["cooling_sp_above_band_h"] == pytest.approx(
        0.5
    )  # 25 and 24.5 degC, not 24 or the unoccupied 30
    assert got["cooling_sp_mean_degC"] == pytest.approx(73.5 / 3) and got["cooling_sp_max_degC"] == 25.0
