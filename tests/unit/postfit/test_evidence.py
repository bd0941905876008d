"""The held-out evidence of ``--holdout``: coverage per horizon, the baselines, the innovations.

Scores are built by construction (errors of a known law, bands of a known width), so each check's
outcome is known before it runs; the CLI test fits a model that is wrong for its data.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from rczone.calibration.horizons import HorizonScores, horizon_label
from rczone.postfit.evidence import (
    COVERAGE_MIN,
    FAILED,
    NOT_JUDGED,
    PASSED,
    baseline_check,
    coverage_check,
    held_out_evidence,
    innovation_check,
)
from rczone.results.verdict import verdict_of

DT = 300.0


def _scores(errors: dict, sd: float, rmse: dict, unstable=None) -> HorizonScores:
    """Scores of one output: ``errors`` horizon -> model error series; ``rmse`` (horizon, predictor) -> RMSE."""
    horizons = tuple(errors)
    n = len(next(iter(errors.values())))
    measured = np.zeros((n, 1))
    pred = np.stack([-np.asarray(errors[h])[:, None] for h in horizons])
    rows = []
    for h in horizons:
        e = np.asarray(errors[h])
        for name in ("model", "persistence", "arx"):
            r = rmse.get((h, name), float(np.sqrt(np.mean(e**2))) if name == "model" else 9.0)
            rows.append(
                {
                    "horizon": horizon_label(h, DT),
                    "steps": h,
                    "horizon_s": None if h is None else h * DT,
                    "predictor": name,
                    "output": "Ti",
                    "n": n,
                    "rmse_K": r,
                    "mae_K": r,
                    "bias_K": 0.0,
                    "coverage_2sigma": float(np.mean(np.abs(e) <= 2 * sd))
                    if name == "model" and np.isfinite(sd)
                    else np.nan,
                    "stable": name not in (unstable or {}),
                }
            )
    return HorizonScores(
        pd.DataFrame(rows),
        np.arange(n) * DT,
        measured,
        {"model": pred},
        np.full(pred.shape, sd),
        horizons,
        ("Ti",),
        "band",
        "start",
        "arx",
        unstable=dict(unstable or {}),
    )


def test_a_band_covering_68_percent_at_6_h_fails_and_names_the_horizon():
    rng = np.random.default_rng(0)
    good, bad = rng.normal(0, 0.1, 600), rng.normal(0, 0.1 * 2 / 1.0, 600)  # sd 0.2 vs band 2*0.1: ~68 %
    check = coverage_check(_scores({1: good, 72: bad}, 0.1, {}))
    assert check.outcome == FAILED and "at 72 steps (6 h)" in check.detail and "1 step" not in check.detail
    share = float(np.mean(np.abs(bad) <= 0.2))
    assert 0.6 < share < COVERAGE_MIN and f"{share:.0%}" in check.detail


def test_an_honest_band_passes_and_a_bandless_model_is_not_judged():
    e = np.random.default_rng(1).normal(0, 0.1, 600)
    assert coverage_check(_scores({1: e, None: e}, 0.1, {})).outcome == PASSED
    assert coverage_check(_scores({1: e}, np.nan, {})).outcome == NOT_JUDGED


def test_a_stable_baseline_beating_the_model_by_more_than_the_margin_fails_it():
    e = np.random.default_rng(2).normal(0, 0.5, 600)
    rmse = float(np.sqrt(np.mean(e**2)))
    beaten = baseline_check(_scores({12: e}, 0.5, {(12, "persistence"): 0.8 * rmse}))
    assert beaten.outcome == FAILED and "persistence at 12 steps (1 h)" in beaten.detail
    close = baseline_check(_scores({12: e}, 0.5, {(12, "persistence"): 0.95 * rmse}))
    assert close.outcome == PASSED  # within the 10 % margin


def test_an_unstable_arx_is_never_ranked():
    e = np.random.default_rng(3).normal(0, 0.5, 600)
    check = baseline_check(_scores({None: e}, 0.5, {(None, "arx"): 1e-3}, unstable={"arx": 1.006}))
    assert check.outcome == PASSED and "not ranked (unstable): arx" in check.detail


def test_correlated_one_step_errors_fail_the_innovations_and_white_ones_pass():
    rng = np.random.default_rng(4)
    white = rng.normal(0, 0.1, 2000)
    ar = np.zeros(2000)
    for k in range(1, 2000):  # AR(1) with coefficient 0.5: autocorrelation 0.5 at lag 1
        ar[k] = 0.5 * ar[k - 1] + white[k]
    assert innovation_check(_scores({1: white}, 0.1, {})).outcome == PASSED
    failed = innovation_check(_scores({1: ar}, 0.1, {}))
    lag1 = np.corrcoef(ar[1:], ar[:-1])[0, 1]  # the largest autocorrelation, by construction near 0.5
    found = float(re.search(r"largest autocorrelation ([0-9.]+)", failed.detail).group(1))
    assert failed.outcome == FAILED and found == pytest.approx(lag1, abs=0.01)
    assert innovation_check(_scores({None: ar}, 0.1, {})).outcome == NOT_JUDGED  # open loop only, no fit


def test_the_verdict_carries_each_failed_check():
    rng = np.random.default_rng(5)
    e = rng.normal(0, 0.3, 800)
    ev = held_out_evidence(_scores({1: e}, 0.1, {(1, "arx"): 0.1}))
    assert ev.failed == ("coverage", "baselines")

    class Fit:  # a fit with nothing of its own to flag
        flags, parameters, issues = (), {}, ()

    v = verdict_of(Fit(), evidence=ev)
    assert not v.trustworthy and "held-out data" in v.checked
    assert (
        v.held_out["failed"] == ["coverage", "baselines"] and v.held_out["innovations"]["outcome"] == PASSED
    )
    assert any(r.startswith("held out, coverage failed") for r in v.reasons)


@pytest.fixture(scope="module")
def wrong_model_files(tmp_path_factory):
    from tests.unit.selection.synthetic import prbs_zone

    d = tmp_path_factory.mktemp("evidence")
    prbs_zone(days=2, seed=2).to_csv(d / "zone.csv", index=False)
    return d


@pytest.mark.slow
def test_fit_holdout_of_a_wrong_model_exits_3_and_says_which_check_failed(wrong_model_files, capsys):
    d = wrong_model_files
    out = d / "fit.json"
    args = ["fit", str(d / "zone.csv"), "--model", "Ti+heater", "--starts", "1", "--holdout", "0.3"]
    from rczone.cli.main import main

    assert main([*args, "--json", str(out), "--no-profiles"]) == 3
    text = capsys.readouterr().out
    res = json.loads(out.read_text())
    held = res["verdict"]["held_out"]
    assert held["failed"] and res["exit_code"] == 3 and not res["trustworthy"]
    assert "verdict: flagged" in text and all(name in text for name in held["failed"])
    # the robust errors beside the Hessian's, and the verdict reads them when the innovations are not white
    robust = res["robust_std_errors"]
    assert set(robust) == set(res["parameters"]) and "robust (sandwich) standard errors" in text
    white = res["innovations"]["white"]
    assert res["verdict"]["standard_errors"] == ("hessian" if white else "robust")
