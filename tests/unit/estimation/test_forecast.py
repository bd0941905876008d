"""k-step and open-loop predictions with bands: against the filter, a loop, Monte Carlo and the truth."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import Dataset
from rczone.estimation.costs import filter_arrays, run_filter, simulate_output
from rczone.estimation.forecast import k_step_band, noise_band, parameter_sd
from tests.oracles import k_step_prediction_error, k_step_prediction_sd
from tests.unit.selection.synthetic import simulate_sde

from .nets import NET1, NET2, data2

THETA = {"Cr": 1e6, "R": 0.01}
NOISE = {"sigma_v": 0.03, "sigma_w_Ti": 2e-3, "sigma_x0_Ti": 0.1}


def noisy_data(n: int = 800, seed: int = 3) -> Dataset:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 600.0
    u = np.column_stack([5 + 3 * np.sin(2 * np.pi * t / 86400), 400.0 * (rng.random(n) < 0.3)])
    _, y = simulate_sde(NET1, THETA, t, u, {"Ti": 2e-3}, 0.03, rng, substeps=30)
    return Dataset(t, u, None, y, NET1.input_names, (), NET1.outputs)


def test_one_step_band_is_the_filters_prediction_and_innovation_variance():
    data = noisy_data(200)
    values = {**THETA, **NOISE}
    y_hat, sd = k_step_band(NET1, values, data, 1)
    out = run_filter(NET1, values, data)
    np.testing.assert_allclose(data.y[1:] - y_hat[1:], out.innovations[1:], rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(sd[1:, 0], np.sqrt(out.S[1:, 0, 0]), rtol=1e-9)
    assert np.isnan(y_hat[0]).all()


@pytest.mark.parametrize("k", [3, 12])
def test_k_step_prediction_equals_the_loop_implementation(k):
    data = noisy_data(150)
    values = {**THETA, **NOISE}
    y_hat, _ = k_step_band(NET1, values, data, k)
    ref = k_step_prediction_error(NET1, values, data, k=k)
    np.testing.assert_allclose(data.y - y_hat, ref, rtol=1e-9, atol=1e-10, equal_nan=True)


@pytest.mark.parametrize("k", [1, 4, 9])
def test_k_step_band_of_a_flow_varying_model_equals_the_loop_implementation(k):
    """Two states, the supply air's flow switching (two sets of matrices): mean and sd against loops."""
    data = data2(90, noise=0.02, rng=np.random.default_rng(4))
    noise = {"sigma_v": 0.02, "sigma_w_Ti": 3e-3, "sigma_w_Tw": 1e-3, "sigma_x0_Ti": 0.1, "sigma_x0_Tw": 0.5}
    values = {**NET2.values(), **noise}
    y_hat, sd = k_step_band(NET2, values, data, k)
    ref = k_step_prediction_error(NET2, values, data, k=k)
    np.testing.assert_allclose(data.y - y_hat, ref, rtol=1e-9, atol=1e-10, equal_nan=True)
    np.testing.assert_allclose(sd, k_step_prediction_sd(NET2, values, data, k=k), rtol=1e-9, equal_nan=True)
    assert np.isnan(sd[:k]).all() and np.isfinite(sd[k:]).all()


def test_k_step_bands_cover_the_truth_and_widen_towards_open_loop():
    """Data from the model itself: 95 % of the measurements inside the 2-sigma band at every horizon."""
    data = noisy_data(1500, seed=8)
    values = {**THETA, **NOISE}
    widths = []
    # errors k steps ahead are correlated over about the time constant (2.8 h): fewer independent
    # checks at long horizons, so a wider tolerance there
    for k, (lo, hi) in ((1, (0.93, 0.97)), (6, (0.92, 0.98)), (36, (0.87, 0.99))):
        y_hat, sd = k_step_band(NET1, values, data, k)
        e = np.abs(data.y - y_hat)[k:, 0]
        inside = np.mean(e <= 2 * sd[k:, 0])
        assert lo < inside < hi, (k, inside)
        widths.append(float(np.mean(sd[k:])))
    y_ol, sd_ol = noise_band(NET1, values, data)
    assert widths[0] < widths[1] < widths[2] <= float(np.mean(sd_ol[36:])) * 1.01
    np.testing.assert_allclose(y_ol, simulate_output(NET1, values, data)[1], atol=1e-9)


def test_filtered_covariance_equals_the_joseph_update():
    data = noisy_data(60)
    values = {**THETA, **NOISE}
    args = filter_arrays(NET1, values, data)
    C, R = args[9], args[11]
    out = run_filter(NET1, values, data)
    Pf = out.P_filt
    for k in (0, 10, 59):
        P = out.P_pred[k]
        K = P @ C.T @ np.linalg.inv(C @ P @ C.T + R)
        IKC = np.eye(P.shape[0]) - K @ C
        np.testing.assert_allclose(Pf[k], IKC @ P @ IKC.T + K @ R @ K.T, rtol=1e-10)


def test_parameter_sd_is_exact_for_a_linear_predictor_and_matches_monte_carlo():
    a = np.array([[2.0, -1.0], [0.5, 3.0]])  # two samples, prediction = a @ (x, y)
    cov = np.array([[0.04, 0.01], [0.01, 0.09]])

    def linear(v):
        return (a @ np.array([v["x"], v["y"]]))[:, None]

    sd = parameter_sd(linear, {"x": 1.0, "y": 2.0}, ["x", "y"], cov)
    np.testing.assert_allclose(sd[:, 0], np.sqrt(np.einsum("ki,ij,kj->k", a, cov, a)), rtol=1e-9)
    # an RC model: the spread of open-loop predictions over parameter draws
    data = noisy_data(300)
    se = np.array([0.03 * THETA["Cr"], 0.03 * THETA["R"]])
    cov = np.array([[1.0, -0.5], [-0.5, 1.0]]) * np.outer(se, se)

    def sim(v):
        return simulate_output(NET1, v, data)[1]

    sd = parameter_sd(sim, dict(THETA), ["Cr", "R"], cov)
    rng = np.random.default_rng(0)
    draws = rng.multivariate_normal([THETA["Cr"], THETA["R"]], cov, size=400)
    ys = np.array([sim({"Cr": c, "R": r})[:, 0] for c, r in draws])
    mc = ys.std(axis=0)
    late = slice(100, None)
    np.testing.assert_allclose(sd[late, 0], mc[late], rtol=0.15)


def test_parameter_sd_without_usable_variances_is_zero_and_bad_shapes_are_errors():
    def f(v):
        return np.ones((3, 1)) * v["x"]

    np.testing.assert_array_equal(parameter_sd(f, {"x": 1.0}, ["x"], np.array([[np.nan]])), 0.0)
    with pytest.raises(ParameterError, match=r"\(1, 1\)"):
        parameter_sd(f, {"x": 1.0}, ["x"], np.eye(2))
    with pytest.raises(ParameterError, match="positive integer"):
        k_step_band(NET1, {**THETA, **NOISE}, noisy_data(20), 0)
