"""Drift: a virtual zone whose envelope or sensor changes on day 4 is flagged within a day; one that does not, never.

Truth by construction: the zone is simulated here from its heat balance (exact discretization by
``scipy.linalg.expm``, process noise by Van Loan's integral), and the model handed to ``predict`` is
the true one before the change, with the true noise levels.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import expm

from rczone.calibration.conformal import ConformalSettings
from rczone.calibration.drift import (
    CUSUM_ARL0,
    CUSUM_H,
    CUSUM_K,
    _cusum,
    check_drift,
    decision_interval,
    self_starting_scores,
    siegmund_arl,
)
from rczone.calibration.horizons import horizon_scores
from rczone.cli.main import main
from rczone.models import read_model_file
from tests.unit.estimation.test_initial_state import MODEL

DAY = 86400.0
DT = 300.0
SIGMA_W, SIGMA_V = 1e-3, 0.02  # K/sqrt(s), K
TRUTH = {"ci": 2.0e6, "ce": 40.0e6, "rie": 2.0e-3, "rea": 10.0e-3}


def _matrices(ci, ce, rie, rea):
    a = np.array([[-1 / (rie * ci), 1 / (rie * ci)], [1 / (rie * ce), -(1 / rie + 1 / rea) / ce]])
    b = np.array([[0.0, 1 / ci], [1 / (rea * ce), 0.0]])  # inputs To, Ph
    aug = np.zeros((4, 4))
    aug[:2, :2], aug[:2, 2:] = a, b
    e = expm(aug * DT)
    q = np.diag([SIGMA_W**2, 0.0])
    van = expm(np.block([[-a, q], [np.zeros((2, 2)), a.T]]) * DT)  # Van Loan (1978)
    phi = van[2:, 2:].T
    return e[:2, :2], e[:2, 2:], phi @ van[:2, 2:], a, b


def virtual_zone(
    seed: int, days: float = 13.0, *, rea_factor: float = 1.0, bias_K: float = 0.0
) -> pd.DataFrame:
    """The zone's measured room temperature; from day 4 its envelope resistance times ``rea_factor``, its sensor off by ``bias_K``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, days * DAY, DT)
    to = 5 + 3 * np.sin(2 * np.pi * t / DAY) + np.repeat(rng.normal(0, 1.0, t.size // 288 + 1), 288)[: t.size]
    ph = np.repeat(rng.choice([0.0, 1500.0], t.size // 12 + 1), 12)[: t.size]
    before = _matrices(**TRUTH)
    after = _matrices(**{**TRUTH, "rea": TRUTH["rea"] * rea_factor})
    u = np.column_stack([to, ph])
    a, b = before[3], before[4]
    x = np.empty((t.size, 2))
    x[0] = np.linalg.solve(a, -b @ u[0])
    for k in range(t.size - 1):
        phi, gam, qd, _, _ = after if t[k] >= 4 * DAY else before
        x[k + 1] = phi @ x[k] + gam @ u[k] + rng.multivariate_normal(np.zeros(2), qd + 1e-30 * np.eye(2))
    y = x[:, 0] + rng.normal(0, SIGMA_V, t.size) + np.where(t >= 4 * DAY, bias_K, 0.0)
    return pd.DataFrame({"time": t, "Ti": y, "To": to, "Ph": ph})


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    d = tmp_path_factory.mktemp("drift")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    return zm.with_values(zm.theta, {"sigma_v": SIGMA_V, "sigma_w_Ti": SIGMA_W, "sigma_x0_Te": 2.0})


def _check(model, frame):
    settings = ConformalSettings(DAY, online=True)
    return horizon_scores(
        model, frame, horizons=[1, 12], start=3 * DAY, parameters=False, baselines=False, conformal=settings
    )


@pytest.mark.parametrize(
    ("change", "kwargs"),
    [("envelope resistance halved", {"rea_factor": 0.5}), ("sensor bias of 1 K", {"bias_K": 1.0})],
)
def test_a_change_on_day_4_is_flagged_within_a_day(model, change, kwargs):
    scores = _check(model, virtual_zone(11, days=7.0, **kwargs))
    drift = scores.drift
    assert drift.drifted, change
    assert 4 * DAY <= drift.detected_s <= 5 * DAY, (change, drift.detected_s / DAY)
    assert 3.5 * DAY <= drift.since_s <= drift.detected_s  # dated near the change, never after the alarm
    assert "DRIFTED" in drift.describe()


# seeds 201 and 328: the undrifted records on which the fixed-reference CUSUM (h = 12) raised its
# false alarms (docs/validation.md); the self-starting one must not
@pytest.mark.parametrize("seed", [1, 2, 3, 201, 328])
def test_ten_undrifted_days_raise_no_alarm(model, seed):
    scores = _check(model, virtual_zone(seed))
    assert not scores.drift.drifted, scores.drift.describe()
    assert "Ti" in scores.drift.traces


@pytest.mark.slow
def test_false_alarms_over_ten_seeds_of_ten_undrifted_days(model):
    alarms = [_check(model, virtual_zone(100 + s)).drift.drifted for s in range(10)]
    assert sum(alarms) == 0, f"{sum(alarms)} of 10 undrifted zones flagged"


def test_page_cusum_against_its_recursion_written_out():
    rng = np.random.default_rng(4)
    x = np.concatenate([rng.normal(size=30), rng.normal(3.0, 1.0, size=30)])
    s, alarm, start = _cusum(x, 1.0)
    level, brute, last_zero = 0.0, [], 0
    for i, v in enumerate(x):
        level = max(0.0, level + v - CUSUM_K)
        brute.append(level)
        if level == 0.0:
            last_zero = i + 1
        if level > CUSUM_H:
            break
    assert alarm == len(brute) - 1 and start == last_zero
    np.testing.assert_allclose(s[: alarm + 1], brute, rtol=1e-14)
    assert 30 <= alarm <= 38  # a shift of 3 found in (h + 1.166) / (3 - k) blocks or so


def test_self_starting_scores_against_the_t_statistic_written_out():
    from scipy import stats

    rng = np.random.default_rng(5)
    x = rng.normal(3.0, 2.0, size=40)
    scores = self_starting_scores(x[:8], x[8:])
    brute = []
    for n in range(8, 40):
        prev = x[:n]
        t = (x[n] - prev.mean()) / (prev.std(ddof=1) * np.sqrt(1 + 1 / n))
        brute.append(stats.norm.ppf(stats.t.cdf(t, n - 1)))
    np.testing.assert_allclose(scores, brute, rtol=1e-9, atol=1e-12)
    far = [self_starting_scores(x[:8], np.array([v]))[0] for v in (1e6, -1e6)]
    assert far[0] > 5 and far[1] < -5 and np.isfinite(far).all()  # a far block keeps its sign, finite


def test_self_starting_scores_are_independent_standard_normals_unlike_a_fixed_reference():
    # 4000 records of 8 reference blocks and 11 scored ones, each with its own mean and spread
    rng = np.random.default_rng(6)
    n, b = 4000, 8
    x = rng.normal(size=(n, b + 11)) * rng.uniform(0.1, 10, size=(n, 1)) + rng.normal(0, 50, size=(n, 1))
    u = np.array([self_starting_scores(r[:b], r[b:])[[0, 10]] for r in x])
    ref = x[:, :b]
    fixed = (x[:, [b, b + 10]] - ref.mean(1, keepdims=True)) / ref.std(1, ddof=1, keepdims=True)
    se = 1 / np.sqrt(n)
    assert abs(u.mean()) < 4 * se and abs(u.var() - 1) < 6 * np.sqrt(2) * se
    assert abs(np.corrcoef(u.T)[0, 1]) < 4 * se
    # a reference held fixed: wider than N(0, 1) and the same error in every later block
    assert fixed.var() > 1.15 and np.corrcoef(fixed.T)[0, 1] > 0.08


def test_siegmund_decision_interval_against_a_monte_carlo_run_length():
    assert siegmund_arl(CUSUM_H, CUSUM_K) == pytest.approx(CUSUM_ARL0, rel=1e-9)
    h = decision_interval(300.0, 0.5)
    rng = np.random.default_rng(7)
    level, length = np.zeros(4000), np.zeros(4000)
    alive = np.ones(4000, bool)
    step = 0
    while alive.any():  # Page's CUSUM of N(0, 1), all runs at once until each alarms
        step += 1
        level[alive] = np.maximum(0.0, level[alive] + rng.normal(size=alive.sum()) - 0.5)
        done = alive & (level > h)
        length[done], alive = step, alive & ~done
    assert length.mean() == pytest.approx(300.0, rel=0.08)  # its standard error is 1.6 %


@pytest.mark.parametrize(("arl0", "k"), [(1.0, 0.5), (1e6, 0.0), (float("nan"), 0.5), (1e6, float("inf"))])
def test_a_decision_interval_for_an_impossible_run_length_is_one_line(arl0, k):
    from rczone.errors import ParameterError

    with pytest.raises(ParameterError, match="arl0 > 1") as info:
        decision_interval(arl0, k)
    assert "\n" not in str(info.value)


def test_too_short_a_window_is_said_not_tested():
    t = np.arange(0.0, 2 * DAY, DT)
    z = np.random.default_rng(0).normal(size=(t.size, 1))
    check = check_drift(z, t, 300, 12, ("Ti",))
    assert not check.drifted and "no CUSUM" in check.notes[0] and "online" in check.notes[1]


def test_predict_cli_says_the_model_drifted_and_from_when(model, tmp_path, capsys):
    virtual_zone(11, days=6.0, rea_factor=0.5).to_csv(tmp_path / "zone.csv", index=False)
    model.save(tmp_path / "m.json")
    out, rep = tmp_path / "p.json", tmp_path / "rep"
    args = ["predict", str(tmp_path / "m.json"), str(tmp_path / "zone.csv"), "--warmup", "3d"]
    extra = ["--conformal", "1d", "--online", "--horizons", "1,12", "--json", str(out), "--report", str(rep)]
    assert main([*args, *extra]) == 0
    printed = " ".join(capsys.readouterr().out.split())
    assert "DRIFTED since about" in printed
    res = json.loads(out.read_text())
    assert res["drift"]["drifted"] and 3.5 * DAY <= res["drift"]["since_s"] <= 5 * DAY
    settings = res["drift"]["settings"]
    assert settings["cusum_reference"] == "self-starting" and settings["cusum_arl0"] == CUSUM_ARL0
    assert siegmund_arl(settings["cusum_h"], settings["cusum_k"]) == pytest.approx(CUSUM_ARL0)
    assert "CUSUM statistics" in (rep / "report.html").read_text()
