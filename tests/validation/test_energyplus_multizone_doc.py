"""docs/energyplus.md's multi-zone tables are the ones validation/energyplus_multizone.py makes from its fits."""

from __future__ import annotations

import json

import pytest

from tests.validation.scripts import ROOT, load_script


def test_the_docs_tables_are_the_scripts_tables_of_the_recorded_fits() -> None:
    mod = load_script("energyplus_multizone")
    runs = json.loads((ROOT / "validation" / "energyplus_multizone.json").read_text())
    assert {r["model"] for r in runs} == {"joint", "single"}
    joint = [r for r in runs if r["model"] == "joint"]
    assert len({(r["climate"], r["season"]) for r in joint}) >= 4  # two climates, two seasons

    def case(r: dict) -> tuple:
        return r.get("building"), r.get("floor"), r["climate"], r["season"]

    for j in joint:  # every zone of a case scored by both, on the same held-out days
        zones = {r["zone"] for r in runs if r["model"] == "single" and case(r) == case(j)}
        assert zones == set(j["heldout"]) and len(zones) >= 5
    assert mod.in_doc((ROOT / "docs" / "energyplus.md").read_text()) == mod.table(runs)


def _scores(model: float | None, persistence: float) -> dict:
    return {h: {"model": model, "persistence": persistence, "coverage": 0.5} for h in ("1 h", "6 h", "open")}


def _record(kind: str, zone: str | None, heldout: dict, code: int = 3) -> dict:
    return {
        "climate": "c", "season": "winter", "model": kind, "zone": zone, "exit_code": code,
        "reasons": ["x"] * (code == 3), "n_free": 7, "at_bound": 1, "one_step_rmse_K": 0.1,
        "open_loop_rmse_K": 0.5, "heldout": heldout, "fit_time": {"cpu_s": 2.0, "wall_s": 3.0},
    }  # fmt: skip


def test_the_comparison_line_follows_the_numbers() -> None:
    mod = load_script("energyplus_multizone")
    joint = _record("joint", None, {"A": _scores(1.0, 2.0), "B": _scores(3.0, 2.0)})
    single = {
        "A": _record("single", "A", {"A": _scores(2.0, 2.0)}, code=0),
        "B": _record("single", "B", {"B": _scores(1.0, 4.0)}),
    }
    line = mod.compare("c", "winter", joint, single)
    # means over the zones computed here: joint (1 + 3) / 2, single (2 + 1) / 2, persistence (2 + 4) / 2
    assert "open 2.00 / 1.50 / 3.00" in line
    assert "better than the single zone in 1 at 1 h, 1 at 6 h, 1 at open of 2 zones" in line
    assert "joint no, single 1 of 2" in line
    text = mod.table([joint, *single.values()])
    assert (
        "| c | winter | A | 1.00 / 2.00 / 2.00 |" in text
        and "| c | winter | B | 3.00 / 1.00 / 4.00 |" in text
    )
    assert "| c | winter | office_small floor 1, joint | flagged (3), 1 reasons |" in text
    assert "| c | winter | A, second-order | trustworthy (0) |" in text


def test_an_unstable_prediction_is_never_counted_better() -> None:
    mod = load_script("energyplus_multizone")
    joint = _record("joint", None, {"A": _scores(None, 2.0)})
    line = mod.compare("c", "winter", joint, {"A": _record("single", "A", {"A": _scores(2.0, 2.0)})})
    assert "open unstable / 2.00 / 2.00" in line and "in 0 at 1 h" in line


def test_the_floors_zones_are_the_conditioned_ones_of_the_floor() -> None:
    mod = load_script("energyplus_multizone")
    zones = [
        {"name": "A", "floor": 1, "conditioned": True},
        {"name": "Attic", "floor": 1, "conditioned": False},
        {"name": "C", "floor": 2, "conditioned": True},
    ]
    assert [z["name"] for z in mod.floor_zones({"zones": zones})] == ["A"]


def test_the_doc_markers_are_required_once() -> None:
    mod = load_script("energyplus_multizone")
    with pytest.raises(ValueError, match="one line"):
        mod.in_doc("no markers here")
    assert mod.in_doc(f"a\n{mod.BEGIN}\n| t |\n{mod.END}\nb") == "| t |\n"
