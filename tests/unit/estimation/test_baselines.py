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
