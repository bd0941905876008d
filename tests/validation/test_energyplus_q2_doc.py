"""docs/energyplus.md's Q2 tables are the ones validation/energyplus_q2.py makes from its recorded fits."""

from __future__ import annotations

import json

import pytest

from tests.validation.scripts import ROOT, load_script


def test_the_docs_tables_are_the_scripts_tables_of_the_recorded_fits() -> None:
    mod = load_script("energyplus_q2")
    runs = json.loads((ROOT / "validation" / "energyplus_q2.json").read_text())
    assert len({r["climate"] for r in runs}) >= 2 and len({r["season"] for r in runs}) >= 2
    assert {r["training"] for r in runs} == {"calibration", "forced"}
    assert mod.in_doc((ROOT / "docs" / "energyplus.md").read_text()) == mod.table(runs)


def _fit(training: str, open_rmse: float, r1: float, r1_se: float | None, *, bound: bool = False) -> dict:
    est = {
        p: {"estimate": 1.0, "std_error": 0.1, "robust_std_error": 0.2, "at_bound": False}
        for p in ("Cr", "Cw", "Rwin", "R2")
    }
    est["R1"] = {"estimate": r1, "std_error": r1_se, "robust_std_error": None, "at_bound": bound}
    scores = {
        h: {"model": open_rmse, "persistence": 1.0, "arx": None, "coverage": 0.9}
        for h in ("15 min", "1 h", "6 h", "open")
    }
    ref = {"floor_area_m2": 10.0, "Rwin": 0.5, "R1+R2": 2.0, "Cr_air": 1.0}
    return {
        "reference": ref,
        "climate": "c", "season": "winter", "training": training, "days": 3, "exit_code": 3,
        "reasons": ["x"], "estimates": est, "heldout": scores, "heldout_failed": ["innovations"],
        "on_forced": {"6 h": 2 * open_rmse, "open": 3 * open_rmse},
    }  # fmt: skip


@pytest.mark.parametrize(
    ("estimate", "se", "bound", "expected"),
    [(1.0, 0.5, False, True), (1.0, 1.0, False, False), (1.0, None, False, False), (1.0, 0.1, True, False)],
)
def test_an_estimate_is_determined_off_its_bounds_with_a_standard_error_below_its_value(
    estimate, se, bound, expected
):
    mod = load_script("energyplus_q2")
    e = {"estimate": estimate, "std_error": se, "robust_std_error": None, "at_bound": bound}
    assert mod.determined(e) is expected


def test_the_robust_standard_error_is_read_before_the_hessians() -> None:
    mod = load_script("energyplus_q2")
    assert not mod.determined({"estimate": 1.0, "std_error": 0.1, "robust_std_error": 1.5, "at_bound": False})


def test_the_comparison_line_follows_the_numbers() -> None:
    mod = load_script("energyplus_q2")
    normal, forced = _fit("calibration", 2.0, 1.0, 2.0), _fit("forced", 1.0, 3.0, 0.3)
    line = mod.compare(normal, forced)
    assert "the forced fit predicts better" in line
    assert "determined 4 of 5 vs 5 of 5" in line
    assert "R1 x3" in line and "Cr" not in line.split("factor 2:")[1]
    assert "forced test's last 2 days: 6.00 K open loop (the forced fit on its own data: 3.00 K)" in line
    assert "| 6.00 |" in mod.table([normal]) and "| 3.00 (own data) |" in mod.table([forced])
    assert "the normal fit predicts better" in mod.compare(_fit("calibration", 0.5, 1.0, 0.1), forced)
    text = mod.table([normal, forced])
    assert text.count("\n| c | winter |") == 5 and "unstable" in text and "(bound)" not in text
    assert "| c | winter | EnergyPlus constructions |" in text  # once per case, before its fits
    assert "Rwin x2 vs x2; R1 + R2 x1 vs x2" in line  # Rwin 1 against 0.5; R1 + R2 1 + 1, 3 + 1 against 2
    assert "1 (bound)" in mod.table([_fit("calibration", 1.0, 1.0, 0.1, bound=True)])


def test_the_reference_values_are_read_from_the_building_file() -> None:
    mod = load_script("energyplus_q2")
    zone = {"name": mod.ZONE, "floor_area": 20.0, "exterior_ua": 50.0, "volume": 60.0}
    other = {"name": "B", "floor_area": 1.0, "exterior_ua": 1.0, "volume": 1.0}
    pairs = [
        {"a": "B", "b": mod.ZONE, "ua": 300.0},
        {"a": mod.ZONE, "b": "C", "ua": 100.0},
        {"a": "B", "b": "C", "ua": 7.0},
    ]
    ref = mod.reference({"zones": [other, zone], "adjacency": pairs})
    assert ref["Rwin"] == pytest.approx(1 / 50) and ref["R1+R2"] == pytest.approx(1 / 400)
    assert ref["Cr_air"] == pytest.approx(60 * 1.2 * 1005) and ref["floor_area_m2"] == 20.0


def test_the_doc_markers_are_required_once() -> None:
    mod = load_script("energyplus_q2")
    with pytest.raises(ValueError, match="one line"):
        mod.in_doc("no markers here")
    assert mod.in_doc(f"a\n{mod.BEGIN}\n| t |\n{mod.END}\nb") == "| t |\n"


def test_the_replicates_add_a_table_of_their_spread_and_leave_the_detailed_tables_to_the_first() -> None:
    mod = load_script("energyplus_q2")
    first = [_fit("calibration", 2.0, 1.0, 2.0), _fit("forced", 1.0, 3.0, 0.3)]
    again = [
        {**_fit("calibration", 3.0, 1.0, 0.1), "replicate": 1},
        {**first[1], "replicate": 1, "exit_code": 0},
    ]
    assert "| replicates |" not in mod.table(first)
    text = mod.table(first + again)
    assert text.startswith(mod.table(first))  # the first replicate's tables, then the spread
    assert "| c | winter | calibration | 2 | 0 | 2.00 to 3.00 | 2.00 to 3.00 | 4 to 5 | 2 | 1 |" in text
    assert "| c | winter | forced | 2 | 1 | 1.00 | 1.00 | 5 | 2 | 2 |" in text
