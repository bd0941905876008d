"""Held-out bands on the Bacher & Madsen PRBS house (issue 22, defect 4): coverage per horizon.

The data stay outside the project (see their PROVENANCE.md); the test reads them from the shared
folder through :func:`tests.shared_data.require` (skips without them, fails under ``CI=true``). The
default ML fit of TiTe on the first four days, then ``rczone predict --horizons`` on the last two
with the calibration days as warm-up, through the command line; and the honest workflow with a
better model: ``rczone select --forward --holdout`` chooses from the whole family on the
calibration days alone, then ``rczone predict`` scores its saved fit the same way.
docs/validation.md has the tables.
"""

from __future__ import annotations

import json

import pytest

from rczone.calibration.horizons import horizon_scores
from rczone.cli.main import main
from rczone.models import load_model
from rczone.workflow.reader import read_model_frame
from tests.shared_data import SHARED, require

from .scripts import assert_on_page, load_script

DATA = SHARED / "data" / "bacher_madsen_prbs" / "inputPRBS1.csv"
MAP = """
[time]
column = "TimeDate"
timezone = "Europe/Copenhagen"
{window}
[columns]
Ti = "yTi"
To = "Ta"
Ph = {{ column = "Ph", unit = "kW" }}
Ps = {{ column = "Ps", unit = "kW/m2" }}
"""
SPLIT = "2009-02-09T12:00"
HORIZONS = "1,3,12,72,open"
#: 5 min, 15 min, 1 h, 3 h, 6 h, 12 h and open loop.
ALL_HORIZONS = "1,3,12,36,72,144,open"


def _steps(value) -> int | None:
    """A table's ``steps`` (None or NaN for open loop) as an int or None."""
    return None if value is None or value != value else int(value)


@pytest.fixture(scope="module")
def scored(tmp_path_factory):
    require(DATA, what="shared real data (Bacher & Madsen PRBS)")
    d = tmp_path_factory.mktemp("bands")
    (d / "cal.toml").write_text(MAP.format(window=f'end = "{SPLIT}"'))
    (d / "all.toml").write_text(MAP.format(window=""))
    fit = ["fit", str(DATA), "--columns", str(d / "cal.toml"), "--model", "TiTe+heater+solar"]
    assert main([*fit, "--save-model", str(d / "tite.json")]) == 0
    args = ["predict", str(d / "tite.json"), str(DATA), "--columns", str(d / "all.toml"), "--warmup", SPLIT]
    assert main([*args, "--horizons", HORIZONS, "--baselines", "--json", str(d / "h.json")]) == 0
    rows = json.loads((d / "h.json").read_text())["scores"]
    calibrated = {r["steps"]: r for r in rows if r["predictor"] == "model"}
    # the same fit without its saved factors: the band from the noise levels alone
    zm = load_model(d / "tite.json")
    raw_model = zm.with_values(zm.theta, band_scale=None)
    frame = read_model_frame(DATA, d / "all.toml", zm)
    start = frame["time"].to_numpy()[json.loads((d / "h.json").read_text())["warmup_samples"]]
    raw = horizon_scores(raw_model, frame, horizons=[1, 3, 12, 72, None], start=start, baselines=False)
    uncalibrated = {_steps(r.steps): r for r in raw.table.itertuples()}
    return calibrated, uncalibrated, rows


@pytest.mark.slow
def test_coverage_is_reported_per_horizon_and_the_calibration_widens_the_long_bands(scored):
    calibrated, uncalibrated, rows = scored
    assert set(calibrated) == {1, 3, 12, 72, None}
    # as issue 22 measured: overconfident beyond one step without the factors
    assert uncalibrated[12].coverage_2sigma < 0.8 and uncalibrated[72].coverage_2sigma < 0.6
    for k in (3, 12, 72, None):
        assert calibrated[k]["coverage_2sigma"] > uncalibrated[k].coverage_2sigma + 0.05
    assert 0.9 <= calibrated[3]["coverage_2sigma"] <= 0.98
    # the model beats both baselines from 15 min on
    for k in (3, 12, 72, None):
        best = min(r["rmse_K"] for r in rows if r["steps"] == k and r["predictor"] != "model")
        assert calibrated[k]["rmse_K"] < best


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="issue 22 target not reached: the held-out days' 1 h and 6 h errors are twice the calibration"
    " days' (docs/validation.md), so factors calibrated on the fit's own errors leave the coverage at"
    " about 84 % and 68 %; rolling-origin, blocked and jackknife calibrations inside the calibration days"
    " do not reach it at every horizon either, swing with the folds, or over-widen other data"
    " (validation/holdout_bands.py)",
)
def test_two_sigma_coverage_lies_within_90_to_98_percent_at_1_h_and_6_h(scored):
    calibrated, _, _ = scored
    for k in (12, 72):
        assert 0.9 <= calibrated[k]["coverage_2sigma"] <= 0.98


def test_on_a_zone_with_known_truth_the_calibration_keeps_the_right_band():
    """Data from the default fit's own structure (noise on the room node only): the raw band is right.

    Truth by construction (``validation/holdout_bands.py``'s synthetic zone, an Euler-Maruyama
    simulation independent of rczone's filter): the calibrated factors stay near 1 and the held-out
    coverage of the calibrated band near the nominal 95 %, never above 98 %.
    """
    bands = load_script("holdout_bands")
    case = bands.Case(*bands.synthetic(None))
    n = case.cal.n_samples
    factor = bands.factors([case.errors(case.values, case.cal, 0, n)], case.horizons)
    assert all(0.85 < f < 1.2 for f in factor.values()), factor
    raw = bands.coverage(case, dict.fromkeys(case.horizons, 1.0))
    calibrated = bands.coverage(case, factor)
    assert all(0.85 < c <= 0.98 for c in raw.values()), raw
    assert all(c <= 0.98 for c in calibrated.values()) and min(calibrated[k] for k in case.steps) >= 0.9


@pytest.fixture(scope="module")
def selected(tmp_path_factory):
    """Forward selection on the calibration days (``select``'s default fit), then its held-out scores."""
    require(DATA, what="shared real data (Bacher & Madsen PRBS)")
    d = tmp_path_factory.mktemp("selected")
    (d / "all.toml").write_text(MAP.format(window=""))
    columns = ["--columns", str(d / "all.toml")]
    chosen = [
        "select",
        str(DATA),
        *columns,
        "--forward",
        "--holdout",
        SPLIT,
        "--save-model",
        str(d / "sel.json"),
    ]
    assert main([*chosen, "--json", str(d / "select.json")]) == 0
    args = [
        "predict",
        str(d / "sel.json"),
        str(DATA),
        *columns,
        "--warmup",
        SPLIT,
        "--horizons",
        ALL_HORIZONS,
    ]
    assert main([*args, "--baselines", "--json", str(d / "h.json")]) == 0
    rows = json.loads((d / "h.json").read_text())["scores"]
    by = {(r["predictor"], r["steps"]): r for r in rows}
    return load_model(d / "sel.json"), json.loads((d / "select.json").read_text()), by


@pytest.mark.slow
def test_the_model_selected_on_the_calibration_days_is_richer_and_sound(selected):
    zm, table, _ = selected
    assert len(zm.network.node_state_names) >= 4  # beyond TiTeTh
    assert table["selected"] == zm.network.name and table["models"][zm.network.name]["trustworthy"]
    # no R, C or solar aperture at (or within a factor 1.01 of) a bound of its box
    for p in zm.network.parameters.values():
        if p.is_tied or p.fixed:
            continue
        lo, hi = p.bounds
        value = zm.theta[p.name]
        assert (value > lo * 1.01 if lo > 0 else value > 1e-3 * hi) and value < hi / 1.01, (p.name, value)


@pytest.mark.slow
def test_the_selected_model_beats_tite_and_the_baselines_and_its_bands_are_not_overconfident(
    selected, scored
):
    _, _, by = selected
    tite, _, _ = scored
    for k in (1, 3, 12, 36, 72, 144, None):
        model = by[("model", k)]
        assert model["coverage_2sigma"] >= 0.9, (k, model["coverage_2sigma"])
        assert model["rmse_K"] < min(by[(b, k)]["rmse_K"] for b in ("persistence", "arx")), k
        if k in tite:
            assert model["rmse_K"] < tite[k]["rmse_K"], k


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="issue 22 target not reached from the other side: the held-out days are calmer for the model"
    " selected on the calibration days than the calibration days are (fewer heater switches; 1-step RMSE"
    " 0.006 K against 0.017 K), so every band calibrated on the calibration days holds 99-100 %"
    " (docs/validation.md)",
)
def test_the_selected_models_two_sigma_coverage_is_at_most_98_percent(selected):
    _, _, by = selected
    for k in (1, 3, 12, 36, 72, 144, None):
        assert by[("model", k)]["coverage_2sigma"] <= 0.98


@pytest.mark.slow
def test_the_members_tables_on_the_page_are_a_fresh_runs(tmp_path):
    """``validation/holdout_bands.py --only members``: coverage, RMSE and each fit's verdict as on the page."""
    require(DATA, what="shared real data (Bacher & Madsen PRBS)")
    mod = load_script("holdout_bands")
    assert mod.main(["--shared", str(SHARED), "--out", str(tmp_path), "--only", "members"]) == 0
    rows = json.loads((tmp_path / "holdout_bands.json").read_text())["members"]
    # every member's verdict is rczone's, never left out (the selected one's from select --holdout)
    assert all(r["verdict"] is not None for r in rows.values())
    assert_on_page(mod.members_markdown(rows), after="### A better model instead of a wider band")
