"""docs/energyplus.md's Q1 tables are the ones validation/energyplus_q1.py makes from its recorded fits and runs."""

from __future__ import annotations

import json

import pytest

from tests.validation.scripts import ROOT, load_script


def test_the_docs_tables_are_the_scripts_tables_of_the_recorded_runs() -> None:
    mod = load_script("energyplus_q1")
    store = json.loads((ROOT / "validation" / "energyplus_q1.json").read_text())
    assert {f["model"] for f in store["fits"]} == {"first-order", "second-order"}
    assert {r["fit"] for r in store["runs"]} == {None, "first-order", "second-order"}
    page = (ROOT / "docs" / "energyplus.md").read_text()
    assert mod.eq2.in_doc(page, markers=(mod.BEGIN, mod.END)) == mod.table(store)


def _run(fit: str | None, seed: int, cost: float, comfort_kh: float, climate: str = "c") -> dict:
    return {
        "climate": climate,
        "season": "winter",
        "controller": "mpc" if fit else "baseline",
        "fit": fit,
        "seed": seed,
        "days": 2,
        "margin": 0.0 if fit else None,
        "cost": cost,
        "energy_kWh": cost / 2,
        "comfort_Kh": comfort_kh,
        "prediction_rmse_K": 0.2,
        "prediction_1h_rmse_K": 0.5,
        "open_loop_rmse_K": 1.0,
        "wall_s": 12.0,
        "cpu_s": 4.0,
        "load_1min": 3.0,
        "date": "2026-12-02",
    }


def test_the_pairs_are_by_seed_within_a_case_and_the_verdict_follows_the_numbers() -> None:
    mod = load_script("energyplus_q1")
    two = [_run("second-order", s, c, 1.0) for s, c in enumerate((100.0, 110.0, 120.0))]
    # the 1-state MPC 10 % dearer on every seed: differences +10, +11, +12, beyond 2 s.e. and 1 %
    one = [_run("first-order", s, 1.1 * c, 1.0) for s, c in enumerate((100.0, 110.0, 120.0))]
    other = [_run("first-order", s, 0.0, 0.0, climate="d") for s in range(3)]  # another climate: not paired
    p = mod.paired(two + one + other, ("c", "winter"), 0.0, "cost", False)
    assert p["seeds"] == [0, 1, 2] and p["verdict"] == "worse"
    assert p["mean"] == pytest.approx(11.0) and p["se"] == pytest.approx(1 / 3**0.5)
    assert p["one"] == pytest.approx(121.0) and p["two"] == pytest.approx(110.0)
    # comfort per zone-day, equal: no difference; a 1-state run without its partner is left out
    assert mod.paired(two + one, ("c", "winter"), 0.0, "comfort_Kh", True)["verdict"] == "no difference"
    assert mod.paired(two[:2] + one, ("c", "winter"), 0.0, "cost", False)["seeds"] == [0, 1]
    assert mod.paired(two + one, ("d", "winter"), 0.0, "cost", False) is None
    # runs at another margin are paired among themselves
    aside = [{**r, "margin": 0.2, "cost": r["cost"] - 50} for r in two[:1] + one[:2]]
    assert mod.paired(two + one + aside, ("c", "winter"), 0.0, "cost", False)["mean"] == p["mean"]
    assert mod.paired(two + one + aside, ("c", "winter"), 0.2, "cost", False)["seeds"] == [0]
    text = mod.loop_table([_run(None, 0, 105.0, 3.0), *two, *one])
    assert (
        "| c | winter | 0 | HVAC cost | 105.000 | 121.000 | 110.000 | +11.000 ± 0.577 | worse | 3 |" in text
    )
    comfort = "| c | winter | 0 | comfort K h per zone-day | 1.500 | 0.500 | 0.500 | +0.000 ± 0.000 | no difference | 3 |"
    assert comfort in text


def test_the_line_against_the_baseline_asks_lower_cost_and_at_most_half_a_kelvin_hour_more_per_zone_day() -> (
    None
):
    mod = load_script("energyplus_q1")
    base = _run(None, 0, 100.0, 1.0)
    # 2 days: comfort 1.0 -> 1.9 K h is +0.45 K h per zone-day, 1.0 -> 2.2 is +0.6
    cheaper = [_run("second-order", s, 90.0, 1.9) for s in range(2)]
    warmer = [_run("first-order", 0, 90.0, 1.9), _run("first-order", 1, 90.0, 2.2)]
    lines = mod.against_baseline([base, *cheaper, *warmer])
    assert len(lines) == 2 and lines[0].startswith("- c, winter, margin 0 K, first-order MPC: cost 90.00")
    assert lines[0].endswith("every seed: no") and lines[1].endswith("every seed: yes")
    assert "(-10.0 %), comfort +0.45 K h per zone-day" in lines[1]


def _fit(model: str, exit_code: int) -> dict:
    est = {"estimate": 2.0, "std_error": 0.1, "robust_std_error": 0.5, "at_bound": False}
    names = ("Cr", "Rwin", "Rw") if model == "first-order" else ("Cr", "Cw", "Rwin", "R1", "R2")
    scores = {h: {"model": 1.0, "persistence": 2.0, "coverage": 0.95} for h in ("1 h", "6 h", "open")}
    return {
        "climate": "c", "season": "summer", "model": model, "exit_code": exit_code, "reasons": ["why"],
        "one_step_rmse_K": 0.5, "open_loop_rmse_K": 1.5, "heldout_failed": [],
        "estimates": {n: est | {"at_bound": n == "Rw"} for n in names} | {"x0_Ti": est}, "heldout": scores,
    }  # fmt: skip


def test_the_fits_table_gives_each_models_verdict_and_estimates() -> None:
    mod = load_script("energyplus_q1")
    text = mod.fits_table([_fit("second-order", 0), _fit("first-order", 3)])
    rows = text.splitlines()[2:]
    first = "| c | summer | first-order | flagged (3), 1 reasons | Cr 2 ±25 %, Rwin 2 ±25 %, Rw 2 (bound) | 2 of 3 |"
    assert rows[0].startswith(first)
    assert rows[1].startswith("| c | summer | second-order | trustworthy (0) |") and "x0_Ti" not in rows[1]
    assert rows[1].endswith(
        "| 5 of 5 | 0.50 / 1.50 | 1.00 / 2.00 | 1.00 / 2.00 | 1.00 / 2.00 | 95 % | none |"
    )
