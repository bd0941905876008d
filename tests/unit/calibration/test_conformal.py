"""Conformal bands: the split quantile, adaptive conformal inference and the interval score."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rczone.calibration.conformal import (
    ALPHA,
    ConformalSettings,
    adaptive_quantiles,
    conformal_band,
    conformal_quantile,
    interval_score,
)
from rczone.calibration.horizons import horizon_scores
from rczone.cli.main import main
from rczone.errors import ParameterError
from tests.unit.estimation.test_initial_state import NOON, _with_noise, zone  # noqa: F401 (fixture)


def test_the_split_quantile_of_gaussian_errors_is_the_true_quantile_within_sampling_error():
    rng = np.random.default_rng(1)
    n = 4000
    truth = stats.norm.ppf(1 - ALPHA / 2)  # |z| of a standard normal: 2.0 for a 2-sigma band
    # sampling standard deviation of an order statistic: sqrt(p (1 - p) / n) / density of |z| there
    se = math.sqrt(ALPHA * (1 - ALPHA) / n) / (2 * stats.norm.pdf(truth))
    sd = rng.uniform(0.1, 2.0, n)  # the model's own standard deviation varies; the scores do not
    got = [conformal_quantile(np.abs(sd * rng.standard_normal(n)) / sd, ALPHA) for _ in range(20)]
    assert abs(np.mean(got) - truth) < 4 * se / math.sqrt(20)
    assert all(abs(g - truth) < 4 * se for g in got)


def test_split_conformal_covers_a_new_exchangeable_score_with_its_finite_sample_probability():
    rng = np.random.default_rng(2)
    n, alpha, reps = 19, 0.1, 40000
    scores = rng.exponential(size=(reps, n + 1))  # any continuous law: the guarantee is distribution free
    q = np.array([conformal_quantile(row[:n], alpha) for row in scores])
    # rank ceil(20 * 0.9) = 18 of 19: a new score is below it with probability 18 / 20 exactly
    assert np.mean(scores[:, n] <= q) == pytest.approx(18 / 20, abs=4 * math.sqrt(0.09 / reps))


def test_the_quantile_is_infinite_beyond_what_the_scores_resolve():
    assert conformal_quantile(np.arange(10.0), 0.05) == math.inf  # ceil(11 * 0.95) = 11 > 10
    assert conformal_quantile(np.arange(10.0), 0.0) == math.inf
    assert conformal_quantile(np.arange(10.0), 1.0) == 0.0
    assert conformal_quantile(np.array([3.0, np.nan, 1.0, 2.0]), 0.5) == 2.0  # ceil(4 * 0.5) = 2nd of 3


def _shifted_stream(rng, n_cal, n, shift_at, scale):
    z = np.abs(rng.standard_normal(n_cal + n))
    z[n_cal + shift_at :] *= scale
    return z


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_aci_long_run_miscoverage_converges_to_alpha_on_a_shifted_stream(seed):
    rng = np.random.default_rng(seed)
    n_cal, T, gamma = 300, 10000, 0.01
    z = _shifted_stream(rng, n_cal, T, T // 4, 3.0)
    settings = ConformalSettings(3600.0, online=True, gamma=gamma)
    q = adaptive_quantiles(z, n_cal, 1, n_cal, settings).adaptive
    miss = np.mean(z[n_cal:] > q[n_cal:])
    bound = (max(ALPHA, 1 - ALPHA) + gamma) / (gamma * T)  # Gibbs & Candes (2021), Proposition 4.1
    assert abs(miss - ALPHA) <= bound
    fixed = conformal_quantile(z[:n_cal], ALPHA)
    assert np.mean(z[n_cal:] > fixed) > 0.3  # without the update: half of the shifted three quarters missed


def test_aci_with_a_delay_of_k_steps_uses_only_errors_known_at_the_origin():
    rng = np.random.default_rng(5)
    n_cal, T, k = 300, 10000, 12
    z = _shifted_stream(rng, n_cal, T, T // 4, 3.0)
    settings = ConformalSettings(3600.0, online=True)
    q = adaptive_quantiles(z, n_cal, k, n_cal, settings).adaptive
    assert abs(np.mean(z[n_cal:] > q[n_cal:]) - ALPHA) < 0.02
    z2 = z.copy()
    z2[n_cal + 3000 :] = 100.0  # a change at target t moves no band issued before t (targets < t + k)
    q2 = adaptive_quantiles(z2, n_cal, k, n_cal, settings).adaptive
    np.testing.assert_array_equal(q2[: n_cal + 3000 + k], q[: n_cal + 3000 + k])
    assert q2[n_cal + 3000 + k + 200] > q[n_cal + 3000 + k + 200]


def _brute_interval_score(y, lo, hi, alpha):
    out = []
    for a, low, u in zip(y, lo, hi):
        s = u - low
        if a < low:
            s += 2 / alpha * (low - a)
        if a > u:
            s += 2 / alpha * (a - u)
        out.append(s)
    return np.array(out)


def test_the_interval_score_matches_the_formula_written_out():
    rng = np.random.default_rng(3)
    y = rng.normal(size=500)
    centre = rng.normal(size=500)
    half = rng.uniform(0.1, 2.0, 500)
    got = interval_score(y, centre - half, centre + half, 0.1)
    np.testing.assert_allclose(got, _brute_interval_score(y, centre - half, centre + half, 0.1), rtol=1e-14)
    assert np.isnan(interval_score(np.array([np.nan]), np.array([0.0]), np.array([1.0]), 0.1)[0])


def test_the_band_needs_a_calibration_window():
    e = np.zeros((1, 50, 1))
    with pytest.raises(Exception, match="calibration window"):
        conformal_band(e, np.ones_like(e), (1,), 0, 10, ConformalSettings(3600.0))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"window_s": 0.0}, "positive duration"),
        ({"window_s": 3600.0, "alpha": 1.5}, "alpha"),
        ({"window_s": 3600.0, "gamma": 0.0}, "gamma"),
    ],
)
def test_bad_settings_are_refused(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        ConformalSettings(**kwargs)


def test_a_correct_model_keeps_its_coverage_with_a_conformal_band(zone):  # noqa: F811
    _, zm, frame, _, _ = zone
    zm = _with_noise(zm)
    settings = ConformalSettings(6 * 3600.0, online=True)
    scores = horizon_scores(
        zm, frame, horizons=[1, 12, None], start=NOON, parameters=False, conformal=settings
    )
    model = scores.table[scores.table.predictor == "model"]
    assert "conformal" in scores.band_source and "adaptive" in scores.band_source
    k = model[model.steps == 1].iloc[0]
    assert 0.85 <= k.coverage_2sigma <= 1.0 and math.isfinite(k.interval_score_K)
    q = scores.conformal.quantile
    assert np.isnan(q[2, 0]) and np.isfinite(q[:2]).all()  # open loop keeps the model's band


def test_predict_cli_writes_the_conformal_band_and_interval_scores(zone, tmp_path, capsys):  # noqa: F811
    d, zm, _, _, _ = zone
    _with_noise(zm).save(tmp_path / "noisy.json")
    out = tmp_path / "c.json"
    args = ["predict", str(tmp_path / "noisy.json"), str(d / "zone.csv"), "--warmup", "12h"]
    assert main([*args, "--conformal", "6h", "--horizons", "1,12", "--json", str(out)]) == 0
    printed = " ".join(capsys.readouterr().out.split())
    assert "split conformal" in printed and "interval" in printed
    res = json.loads(out.read_text())
    assert res["conformal"]["window_s"] == 21600.0 and "conformal" in res["band"]
    assert all(r["interval_score_K"] > 0 for r in res["scores"] if r["predictor"] == "model")
    assert main([*args, "--online"]) == 2
    assert "--conformal" in capsys.readouterr().err
    assert main([*args, "--conformal", "soon"]) == 2
