"""Persistence and the ARX baseline: truth by construction and a loop written out here."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import DataError
from rczone.estimation.baselines import ARX, arx_rollout, fit_arx, k_step_baselines, open_loop_baselines

#: y_t = 1.5 y_{t-1} - 0.56 y_{t-2} + 0.02 u1_{t-1} + 0.01 u1_{t-2} - 0.03 u2_{t-1} + 0.0 u2_{t-2} + 0.4
A = (1.5, -0.56)
B = ((0.02, -0.03), (0.01, 0.0))
C = 0.4


def _arx_series(n: int = 400, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = np.column_stack([rng.normal(10, 5, n), rng.choice([0.0, 20.0], n)])
    y = np.zeros((n, 1))
    y[:2] = 20.0
    for t in range(2, n):
        y[t] = A[0] * y[t - 1] + A[1] * y[t - 2] + np.dot(B[0], u[t - 1]) + np.dot(B[1], u[t - 2]) + C
    return y, u


def _loop_prediction(y, u, origin, k):
    """The ARX recursion written out: measured outputs up to ``origin``, its own predictions after."""
    hist = list(y[: origin + 1, 0])
    for t in range(origin + 1, origin + k + 1):
        hist.append(A[0] * hist[-1] + A[1] * hist[-2] + np.dot(B[0], u[t - 1]) + np.dot(B[1], u[t - 2]) + C)
    return hist[-1]


def test_least_squares_recovers_the_coefficients_of_noise_free_data():
    y, u = _arx_series()
    arx = fit_arx(y, u)
    # regressors [y_{t-1}, y_{t-2}, u_{t-1} (2), u_{t-2} (2), 1]
    expected = [A[0], A[1], *B[0], *B[1], C]
    np.testing.assert_allclose(arx.coef[:, 0], expected, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("k", [1, 5, 30])
def test_k_step_prediction_equals_the_recursion_written_out(k):
    y, u = _arx_series(120)
    noisy = y + np.random.default_rng(2).normal(0, 0.05, y.shape)
    arx = ARX(2, 2, np.array([[A[0]], [A[1]], [B[0][0]], [B[0][1]], [B[1][0]], [B[1][1]], [C]]))
    pred = k_step_baselines(noisy, u, [k], arx)[k]
    for j in (k + 1, 60, 119):
        assert pred.arx[j, 0] == pytest.approx(_loop_prediction(noisy, u, j - k, k), rel=1e-12)
        assert pred.persistence[j, 0] == noisy[j - k, 0]
    assert np.isnan(pred.persistence[:k]).all()


def test_open_loop_baselines_start_from_the_last_known_sample():
    y, u = _arx_series(100)
    arx = fit_arx(y, u)
    y_gap = y.copy()
    y_gap[39] = np.nan  # the last warm-up sample missing: persistence holds the one before
    ol = open_loop_baselines(y_gap, u, 40, arx)
    assert np.isnan(ol.persistence[:40]).all() and (ol.persistence[40:] == y[38, 0]).all()
    assert np.isnan(ol.arx[40:]).all()  # its history has a gap: no ARX start
    ol = open_loop_baselines(y, u, 40, arx)
    np.testing.assert_allclose(ol.arx[40:], y[40:], rtol=1e-6)  # noise-free: the simulation is exact
    y_moved = y.copy()
    y_moved[40:] += 5.0
    np.testing.assert_array_equal(open_loop_baselines(y_moved, u, 40, arx).arx, ol.arx)  # no future data


def test_rollout_refuses_coefficients_of_other_signals_and_fit_refuses_too_few_samples():
    y, u = _arx_series(50)
    arx = fit_arx(y, u)
    with pytest.raises(DataError, match="fitted to other signals"):
        arx_rollout(arx, y, u[:, :1], np.array([5]), 3)
    with pytest.raises(DataError, match="too few complete samples"):
        fit_arx(y[:6], u[:6])
    with pytest.raises(DataError, match="ARX baseline is malformed"):
        ARX.from_dict({"na": 2, "nb": 2, "coef": [[1.0], ["x"]]})


def test_poles_are_the_roots_of_the_characteristic_polynomial():
    # y_t = 1.5 y_{t-1} - 0.56 y_{t-2}: z^2 - 1.5 z + 0.56 = (z - 0.8)(z - 0.7)
    arx = ARX(2, 2, np.array([[A[0]], [A[1]], [0.0], [0.0], [0.0], [0.0], [C]]))
    np.testing.assert_allclose(np.sort(np.abs(arx.poles())), np.sort(np.abs(np.roots([1, -A[0], -A[1]]))))
    assert arx.stable and arx.largest_pole() == pytest.approx(0.8)


def test_a_pole_outside_the_unit_circle_makes_the_arx_unstable_and_its_rollout_grows():
    # two outputs, the second coupled to the first; the oracle is the rollout itself growing
    coef = np.zeros((2 * 2 + 2 * 1 + 1, 2))
    coef[0, 0], coef[0, 1], coef[1, 1] = 1.006, 0.3, 0.5  # y1_t = 1.006 y1_{t-1}; y2_t = 0.3 y1 + 0.5 y2
    arx = ARX(2, 2, coef)
    assert not arx.stable and arx.largest_pole() == pytest.approx(1.006)
    y, u = np.ones((3000, 2)), np.zeros((3000, 1))
    roll = arx_rollout(arx, y, u, np.array([1]), 2990)[0]
    assert roll[-1, 0] > 1e7  # 1.006 ** 2990


def test_an_unstable_saved_arx_is_marked_and_not_scored(tmp_path):
    import dataclasses

    from rczone.calibration.horizons import horizon_scores
    from tests.unit.selection.synthetic import prbs_zone

    frame = prbs_zone(days=1, seed=3)
    from rczone.models import load_model

    zm = load_model("Ti+heater")
    n_in = len(zm.network.input_names)
    coef = np.zeros((2 + 2 * n_in + 1, 1))
    coef[0, 0] = 1.006
    zm = dataclasses.replace(
        zm,
        provenance={
            **zm.provenance,
            "baselines": {
                "arx": {
                    "na": 2,
                    "nb": 2,
                    "coef": coef.tolist(),
                    "inputs": list(zm.network.input_names),
                    "dt_s": 300.0,
                }
            },
        },
    )
    scores = horizon_scores(zm, frame, horizons=[None], start=float(frame["time"].iloc[100]))
    arx_rows = scores.table[scores.table.predictor == "arx"]
    assert not arx_rows.stable.any() and scores.table[scores.table.predictor != "arx"].stable.all()
    assert scores.unstable["arx"] == pytest.approx(1.006)
    row = next(r for r in scores.to_dict()["scores"] if r["predictor"] == "arx")
    assert row["rmse_K"] is None and not row["stable"]
    text = " ".join(str(x) for x in scores.summary_lines())
    assert "arx is unstable" in text
    # the same through the CLI: the saved model's unstable ARX is marked in the table and the JSON
    import json

    from rczone.cli.main import main

    zm.save(tmp_path / "unstable.json")
    frame.to_csv(tmp_path / "zone.csv", index=False)
    out = tmp_path / "p.json"
    args = ["predict", str(tmp_path / "unstable.json"), str(tmp_path / "zone.csv"), "--horizons", "open"]
    assert main([*args, "--baselines", "--warmup", "6h", "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["scores"]
    assert [r["rmse_K"] for r in rows if r["predictor"] == "arx"] == [None]
