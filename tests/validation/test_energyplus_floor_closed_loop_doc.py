"""docs/energyplus.md's floor-in-closed-loop tables are the ones validation/energyplus_floor_closed_loop.py makes."""

from __future__ import annotations

import json

import pytest

from tests.validation.scripts import ROOT, load_script


def test_the_docs_tables_are_the_scripts_tables_of_the_recorded_runs() -> None:
    mod = load_script("energyplus_floor_closed_loop")
    store = json.loads((ROOT / "validation" / "energyplus_floor_closed_loop.json").read_text())
    assert {"floor", "zones", None} <= {r["fit"] for r in store["runs"]}
    for r in store["runs"]:  # comfort per zone: the five zones' sum over their number
        assert len(r["zones"]) == 5
        assert r["comfort_Kh"] == pytest.approx(sum(r["comfort_Kh_zone"].values()) / 5)
    page = (ROOT / "docs" / "energyplus.md").read_text()
    assert mod.eq1.eq2.in_doc(page, markers=(mod.BEGIN, mod.END)) == mod.table(store)


def _run(fit: str | None, seed: int, cost: float, per_zone: tuple[float, ...]) -> dict:
    zones = [f"Z{i}" for i in range(len(per_zone))]
    return {
        "climate": "c", "season": "winter", "fit": fit, "seed": seed, "days": 2,
        "margin": 0.0 if fit else None, "zones": zones, "cost": cost, "energy_kWh": cost / 2,
        "comfort_Kh": sum(per_zone) / len(zones), "comfort_Kh_zone": dict(zip(zones, per_zone, strict=True)),
        "peak_power_kW": 10.0, "solve_ms": 100.0 if fit else None, "wall_s": 20.0, "load_1min": 3.0,
        "date": "2026-12-02",
    }  # fmt: skip


def test_the_floor_mpc_is_paired_with_the_zone_mpcs_by_seed_and_comfort_is_per_zone_day() -> None:
    mod = load_script("energyplus_floor_closed_loop")
    base = _run(None, 0, 100.0, (1.0, 0.0))
    zones = [_run("zones", s, c, (0.0, 2.0)) for s, c in enumerate((90.0, 92.0, 94.0))]
    # the floor MPC 10 dearer on every seed but for a spread: +9, +10, +11
    floor = [_run("floor", s, c + 10 + (s - 1), (0.0, 0.0)) for s, c in enumerate((90.0, 92.0, 94.0))]
    text = mod.table({"runs": [base, *zones, *floor]})
    # zone MPCs: 2 K h over two zones and two days = 0.5 per zone-day; baseline 1 over 2 zones, 2 days
    row = "| c | winter | floor MPC, joint model fitted | comfort K h per zone-day | 0.250 | 0.500 | 0.000 | -0.500 ± 0.000 | better | 3 |"
    assert row in text
    assert "| HVAC cost | 100.000 | 92.000 | 102.000 | +10.000 ± 0.577 | worse | 3 |" in text
    # against the baseline: the floor MPC cost 102 > 100, the zone MPCs 92 with +0.25 K h per zone-day
    lines = [x for x in text.splitlines() if x.startswith("- c, winter")]
    assert lines[0].startswith("- c, winter, margin 0 K, floor MPC, joint model fitted: cost 102.00")
    assert lines[0].endswith("every seed: no") and lines[1].endswith("every seed: yes")
    assert "| c | winter | zone MPCs, single-zone models fitted | 0.00 | 1.00 | 10.0 | 100 |" in text


@pytest.mark.parametrize("fit", [None, "floor", "zones", "floor_prior"])
def test_each_run_is_the_control_test_the_page_describes(fit) -> None:
    mod = load_script("energyplus_floor_closed_loop")
    model = {"A": "a.json", "B": "b.json"} if fit == "zones" else "floor.json"
    args = mod.command("usa_il_chicago", "winter", fit, 2, 2, ["A", "B"], model)
    text = " ".join(args)
    assert "--start 01-24 --days 2 --step 15 --price tou --forecast medium --seed 2" in text
    if fit is None:
        assert text.endswith("--zones A,B --controller baseline")
    elif fit == "zones":
        assert text.endswith("--zones A=a.json,B=b.json --controller mpc --margin 0")
    else:
        assert text.endswith("--zones A,B --model floor.json --controller mpc --margin 0")
