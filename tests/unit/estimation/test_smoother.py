"""The Rauch-Tung-Striebel smoother against a textbook implementation and the joint Gaussian."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.estimation import Dataset
from rczone.estimation.costs import filter_arrays
from rczone.estimation.kalman import FilterProblem, input_drive, measurement_variances
from rczone.estimation.smoother import rts_smooth, smooth_states
from tests.unit.selection.synthetic import simulate_sde

from .nets import NET2, data2

THETA = {"Cr": 8e5, "Cw": 6e6, "Rwin": 0.05, "Rw": 0.01, "g": 1.0}
NOISE = {"sigma_v": 0.05, "sigma_w_Ti": 3e-3, "sigma_w_Tw": 1e-3, "sigma_x0_Ti": 0.2, "sigma_x0_Tw": 1.5}
VALUES = {**THETA, **NOISE}


def _data(n: int = 145, seed: int = 1, missing: bool = True) -> Dataset:
    """NET2's day with noise, irregular intervals and missing outputs."""
    rng = np.random.default_rng(seed)
    base = data2(n, noise=0.05, rng=rng)
    t = base.t + np.where(np.arange(n) % 7 == 3, 120.0, 0.0)  # some samples shifted: irregular steps
    y = base.y.copy()
    if missing:
        y[rng.random(n) < 0.15] = np.nan
    return Dataset(t, base.u, base.m, y, base.input_names, base.flow_names, base.output_names)


def textbook_rts(problem: FilterProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Kalman filter (joint update of the observed outputs) and RTS pass with explicit inverses.

    Returns the filtered means and covariances and the smoothed means and covariances.
    """
    Phi, Qd, which, u, y, C, D = (
        problem.Phi,
        problem.Qd,
        problem.which,
        problem.u,
        problem.y,
        problem.C,
        problem.D,
    )
    R = np.diag(measurement_variances(problem.R))
    drive = input_drive(problem.G0, problem.G1, which, u)
    N, n = y.shape[0], problem.x0.shape[0]
    xp, Pp = np.empty((N, n)), np.empty((N, n, n))
    xf, Pf = np.empty((N, n)), np.empty((N, n, n))
    x, P = problem.x0.astype(float), problem.P0.astype(float)
    for k in range(N):
        xp[k], Pp[k] = x, P
        o = np.isfinite(y[k])
        if o.any():
            H = C[o]
            S = H @ P @ H.T + R[np.ix_(o, o)]
            K = P @ H.T @ np.linalg.inv(S)
            x = x + K @ (y[k, o] - H @ x - D[o] @ u[k])
            P = (np.eye(n) - K @ H) @ P
        xf[k], Pf[k] = x, P
        if k < N - 1:
            F = Phi[which[k]]
            x = F @ x + drive[k]
            P = F @ P @ F.T + Qd[which[k]]
    xs, Ps = xf.copy(), Pf.copy()
    for k in range(N - 2, -1, -1):
        F = Phi[which[k]]
        J = Pf[k] @ F.T @ np.linalg.inv(Pp[k + 1])
        xs[k] = xf[k] + J @ (xs[k + 1] - xp[k + 1])
        Ps[k] = Pf[k] + J @ (Ps[k + 1] - Pp[k + 1]) @ J.T
    return xf, Pf, xs, Ps


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_smoother_agrees_with_a_textbook_rts_to_1e_9(hold):
    data = _data()
    problem = filter_arrays(NET2, VALUES, data, hold)
    xf, Pf, xs, Ps = textbook_rts(problem)
    got = rts_smooth(problem)
    np.testing.assert_allclose(got.filtered.x_filt, xf, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(got.filtered.P_filt, Pf, rtol=0, atol=1e-9 * np.abs(Pf).max())
    np.testing.assert_allclose(got.x, xs, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(got.P, Ps, rtol=0, atol=1e-9 * np.abs(Ps).max())


def test_smoothed_last_state_is_the_filters_and_variances_never_exceed_the_filtered():
    data = _data(seed=4)
    got = smooth_states(NET2, VALUES, data)
    np.testing.assert_array_equal(got.x[-1], got.filtered.x_filt[-1])
    np.testing.assert_array_equal(got.P[-1], got.filtered.P_filt[-1])
    vs = np.diagonal(got.P, axis1=1, axis2=2)
    vf = np.diagonal(got.filtered.P_filt, axis1=1, axis2=2)
    assert np.all(vs <= vf * (1 + 1e-12))
    # the wall, never measured, is where the later data tell most
    assert np.mean(vs[:-1, 1] / vf[:-1, 1]) < 0.9
    np.testing.assert_allclose(got.sd, np.sqrt(vs))


def test_smoothed_states_are_the_conditional_means_of_the_joint_gaussian():
    """Truth by construction: ``E[x_k | y_0..y_N-1]`` and its covariance from the dense joint Gaussian."""
    data = _data(n=30, seed=7)
    problem = filter_arrays(NET2, VALUES, data, "zoh")
    Phi, Qd, which = problem.Phi, problem.Qd, problem.which
    drive = input_drive(problem.G0, problem.G1, which, problem.u)
    N, n = data.n_samples, 2
    # X = m + F z with z = (x0 - mean, w_0, ..., w_{N-2}), cov(z) = blockdiag(P0, Qd...)
    F = np.zeros((N * n, N * n))
    m = np.empty(N * n)
    x = problem.x0.astype(float)
    F[:n, :n] = np.eye(n)
    m[:n] = x
    for k in range(N - 1):
        A = Phi[which[k]]
        x = A @ x + drive[k]
        m[(k + 1) * n : (k + 2) * n] = x
        F[(k + 1) * n : (k + 2) * n] = A @ F[k * n : (k + 1) * n]
        F[(k + 1) * n : (k + 2) * n, (k + 1) * n : (k + 2) * n] += np.eye(n)
    Z = np.zeros((N * n, N * n))
    Z[:n, :n] = problem.P0
    for k in range(N - 1):
        Z[(k + 1) * n : (k + 2) * n, (k + 1) * n : (k + 2) * n] = Qd[which[k]]
    Sxx = F @ Z @ F.T
    rows = [(k, j) for k in range(N) for j in range(problem.y.shape[1]) if np.isfinite(problem.y[k, j])]
    H = np.zeros((len(rows), N * n))
    yv = np.empty(len(rows))
    r = measurement_variances(problem.R)
    for i, (k, j) in enumerate(rows):
        H[i, k * n : (k + 1) * n] = problem.C[j]
        yv[i] = problem.y[k, j] - problem.D[j] @ problem.u[k]
    Syy = H @ Sxx @ H.T + np.diag([r[j] for _, j in rows])
    G = np.linalg.solve(Syy, H @ Sxx).T
    mean = (m + G @ (yv - H @ m)).reshape(N, n)
    cov = Sxx - G @ H @ Sxx
    got = rts_smooth(problem)
    np.testing.assert_allclose(got.x, mean, rtol=1e-8, atol=1e-8)
    for k in range(N):
        block = cov[k * n : (k + 1) * n, k * n : (k + 1) * n]
        np.testing.assert_allclose(got.P[k], block, rtol=0, atol=1e-7 * np.abs(block).max())


def test_smoothed_states_of_data_from_the_model_are_closer_to_the_truth_and_inside_their_band():
    """Data from the stochastic model: smoothed closer to the true states than filtered, 2-sigma band holds."""
    rng = np.random.default_rng(11)
    base = data2(400)
    X, y = simulate_sde(NET2, THETA, base.t, base.u, {"Ti": 3e-3, "Tw": 1e-3}, 0.05, rng, substeps=20)
    # no supply air: the simulation above ignores the flow
    data = Dataset(base.t, base.u, 0 * base.m, y, base.input_names, base.flow_names, base.output_names)
    got = smooth_states(NET2, VALUES, data)
    err_s = got.x - X
    err_f = got.filtered.x_filt - X
    assert np.mean(err_s**2) < np.mean(err_f**2)
    inside = np.mean(np.abs(err_s) <= 2 * got.sd, axis=0)
    assert np.all((0.9 < inside) & (inside <= 1.0)), inside
