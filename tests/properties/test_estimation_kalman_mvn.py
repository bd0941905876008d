"""Oracle: the Kalman-filter -log L equals the dense multivariate-normal log-density.

On a tiny problem (2 states, 6 samples, irregular sampling, a flow that changes, a
missing sample) the joint Gaussian of all measurements is built by brute force: the
discrete matrices come from numerical quadrature of the continuous model (not from the
matrix-exponential kernels under test), the joint covariance from the explicit linear
map of (x0, w_0..w_4, v_0..v_5) to the measurements, and the density from
scipy.stats.multivariate_normal.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.linalg import expm
from scipy.stats import multivariate_normal

from rczone.errors import InputShapeError
from rczone.estimation.kalman import (
    FilterProblem,
    kalman_filter_arrays,
    kalman_nll,
    stochastic_matrices,
)
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from tests.oracles import kalman_filter_reference

NET = RCNetwork(
    "tiny",
    nodes=[Node("Ti", "Cr"), Node("Tw", "Cw")],
    boundaries=["To"],
    resistors=[Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "To", "R2")],
    heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    supply_air=[SupplyAir("Ti", "m", "Ts")],
    parameters=[
        Parameter("Cr", "capacitance", 2e5),
        Parameter("Cw", "capacitance", 3e6),
        Parameter("Rwin", "resistance", 0.02),
        Parameter("R1", "resistance", 0.005),
        Parameter("R2", "resistance", 0.01),
    ],
)
T = np.array([0.0, 600.0, 1500.0, 1800.0, 3000.0, 3300.0])  # irregular
U = np.array(
    [
        [5.0, 14.0, 100.0],
        [6.0, 15.0, 0.0],
        [4.0, 13.0, 300.0],
        [7.0, 16.0, 50.0],
        [5.5, 12.0, 0.0],
        [6.0, 14.0, 80.0],
    ]
)
MFLOW = np.array([[0.05], [0.05], [0.1], [0.0], [0.1], [0.1]])
SIG_W = np.array([2e-3, 5e-4])  # K/sqrt(s)
X0 = np.array([21.0, 18.0])
P0 = np.diag([0.3**2, 0.5**2])


def brute_force_logpdf(
    y: np.ndarray, C: np.ndarray, R: np.ndarray, hold: str, D: np.ndarray | None = None
) -> float:
    ss = NET.state_space()
    n, N = 2, T.size
    Phis, means = [], [X0]
    Qds = []
    for k in range(N - 1):
        A, B = ss.matrices(MFLOW[k])
        dt = T[k + 1] - T[k]

        def u_at(s: float, k: int = k, dt: float = dt) -> np.ndarray:
            return U[k] if hold == "zoh" else U[k] + (U[k + 1] - U[k]) * s / dt

        def integrand_b(s: float, A=A, B=B, dt=dt, u_at=u_at) -> np.ndarray:
            return expm(A * (dt - s)) @ B @ u_at(s)

        def integrand_q(s: float, A=A) -> np.ndarray:
            E = expm(A * s)
            return E @ np.diag(SIG_W**2) @ E.T

        b = quad_vec(integrand_b, 0.0, dt, epsabs=1e-13, epsrel=1e-12)[0]
        Q = quad_vec(integrand_q, 0.0, dt, epsabs=1e-16, epsrel=1e-12)[0]
        Phis.append(expm(A * dt))
        Qds.append(Q)
        means.append(Phis[-1] @ means[-1] + b)
    # x_k = Phi_{k-1}...Phi_0 e0 + sum_j Phi_{k-1}..Phi_{j+1} w_j
    L = np.zeros((N * n, N * n))
    for k in range(N):
        for j in range(k + 1):  # block j: e0 (j=0) or w_{j-1}
            M = np.eye(n)
            for i in range(j, k):
                M = Phis[i] @ M
            L[k * n : (k + 1) * n, j * n : (j + 1) * n] = M
    Sig = np.zeros((N * n, N * n))
    Sig[:n, :n] = P0
    for j in range(1, N):
        Sig[j * n : (j + 1) * n, j * n : (j + 1) * n] = Qds[j - 1]
    covX = L @ Sig @ L.T
    ny = C.shape[0]
    Cb = np.kron(np.eye(N), C)
    covY = Cb @ covX @ Cb.T + np.kron(np.eye(N), R)
    meanY = Cb @ np.concatenate(means) + (0.0 if D is None else (U @ D.T).reshape(-1))
    yv = y.reshape(-1)
    obs = np.isfinite(yv)
    assert obs.sum() < N * ny  # the case must include a missing measurement
    return float(multivariate_normal(meanY[obs], covY[np.ix_(obs, obs)]).logpdf(yv[obs]))


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_scalar_output_nll_equals_dense_mvn(hold: str) -> None:
    ss = NET.state_space()
    y = np.array([[21.2], [20.5], [np.nan], [19.0], [19.8], [20.1]])
    R = np.array([[0.05**2]])
    ref = -brute_force_logpdf(y, ss.C, R, hold)
    Phi, G0, G1, Qd, which = stochastic_matrices(ss, T, MFLOW, np.diag(SIG_W**2), hold)
    out = kalman_filter_arrays(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, ss.C, ss.D, R))
    assert out.n_obs == 5
    assert out.nll == pytest.approx(ref, abs=1e-10)
    fast = kalman_nll(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, ss.C, ss.D, R))
    assert fast == pytest.approx(ref, abs=1e-10)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_three_outputs_each_missing_on_its_own_equal_dense_mvn(hold: str) -> None:
    """Per-output measurement noise; an output missing at a sample is skipped alone, the others update."""
    ss = NET.state_space()
    C = np.array([[1.0, 0.0], [0.0, 1.0], [0.3, 0.7]])  # the third a mix (a surface sensor)
    D = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1e-3]])
    y = np.array(
        [
            [21.2, 18.1, 19.0],
            [20.5, np.nan, 19.2],
            [np.nan, np.nan, np.nan],
            [np.nan, 18.3, 18.9],
            [19.8, 18.2, np.nan],
            [20.1, 18.0, 18.8],
        ]
    )
    R = np.diag([0.05**2, 0.08**2, 0.2**2])
    ref = -brute_force_logpdf(y, C, R, hold, D)
    Phi, G0, G1, Qd, which = stochastic_matrices(ss, T, MFLOW, np.diag(SIG_W**2), hold)
    twin = kalman_filter_reference(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, C, D, R))
    compiled = kalman_filter_arrays(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, C, D, R))
    assert twin.n_obs == compiled.n_obs == 12
    assert twin.nll == pytest.approx(ref, abs=1e-10)
    assert compiled.nll == pytest.approx(ref, abs=1e-10)
    assert kalman_nll(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, C, D, R)) == pytest.approx(
        ref, abs=1e-10
    )
    for a, b in (
        (twin.innovations, compiled.innovations),
        (twin.S, compiled.S),
        (twin.x_filt, compiled.x_filt),
    ):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.isnan(compiled.innovations), np.isnan(y))


def test_correlated_measurement_noise_is_refused() -> None:
    ss = NET.state_space()
    Phi, G0, G1, Qd, which = stochastic_matrices(ss, T, MFLOW, np.diag(SIG_W**2), "zoh")
    R = np.array([[0.05**2, 0.0004], [0.0004, 0.08**2]])
    y = np.full((T.size, 2), 20.0)
    for f in (kalman_filter_reference, kalman_filter_arrays):
        with pytest.raises(InputShapeError, match="R must be diagonal"):
            f(FilterProblem(Phi, G0, G1, Qd, which, U, y, X0, P0, np.eye(2), np.zeros((2, 3)), R))


@pytest.mark.parametrize("dt", [1.0, 600.0, 3600.0])
def test_process_noise_covariance_is_accurate_for_stiff_models(dt: float) -> None:
    """Fast mode |lambda| = 0.36 1/s and slow mode 1e-6 1/s: |lambda| dt up to 1300.

    Plain Van Loan loses everything here (its block exponential holds e^{+|lambda| dt});
    the doubling scheme must match quadrature to 1e-12 relative.
    """
    from rczone.simulation.discretize import process_noise_covariance

    A = np.array([[-0.3636, 0.36], [0.36 * 27885 / 6e6, -0.36 * 27885 / 6e6 - 1e-6]])
    Qc = np.diag([1e-12, 4e-12])

    def integrand(s: float) -> np.ndarray:
        E = expm(A * s)
        return E @ Qc @ E.T

    # split the quadrature where the fast mode has decayed
    ref = sum(
        quad_vec(integrand, a, b, epsrel=1e-13, epsabs=0)[0]
        for a, b in [(0, min(dt, 50.0)), (min(dt, 50.0), dt)]
        if b > a
    )
    got = process_noise_covariance(A, Qc, dt)
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
