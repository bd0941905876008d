"""The baseline: a plain, straightforward implementation of the same computations.

This is what a careful user would write without rczone: one ``scipy.linalg.expm`` per
sample for the discretization (ZOH block exponential, Van Loan for the process noise), a
Python loop for the simulation and for the Kalman filter, and ``scipy.optimize.minimize``
for the fit. It is deliberately not tuned; the benchmarks report rczone's time relative to
it, on the same data in the same process. It is not used by rczone itself.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.optimize import minimize


def discretize(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """ZOH ``(Phi, Gamma)`` from the exponential of ``[[A, B], [0, 0]] dt``."""
    n, p = B.shape
    blk = np.zeros((n + p, n + p))
    blk[:n, :n] = A * dt
    blk[:n, n:] = B * dt
    E = expm(blk)
    return E[:n, :n], E[:n, n:]


def van_loan(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """``Qd`` from the exponential of ``[[-A, Qc], [0, A']] dt``."""
    n = A.shape[0]
    blk = np.zeros((2 * n, 2 * n))
    blk[:n, :n] = -A * dt
    blk[:n, n:] = Qc * dt
    blk[n:, n:] = A.T * dt
    E = expm(blk)
    return E[n:, n:].T @ E[:n, n:]


def discretize_all(ss, t: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One ZOH discretization per interval, shapes ``(N-1, n, n)`` and ``(N-1, n, p)``."""
    Phi = np.empty((t.size - 1, ss.n_states, ss.n_states))
    Gam = np.empty((t.size - 1, ss.n_states, ss.n_inputs))
    for k in range(t.size - 1):
        A = ss.A + np.tensordot(m[k], ss.N, axes=1)
        B = ss.B + np.tensordot(m[k], ss.M, axes=1)
        Phi[k], Gam[k] = discretize(A, B, t[k + 1] - t[k])
    return Phi, Gam


def simulate(ss, t: np.ndarray, u: np.ndarray, m: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """Outputs ``y`` (N, ny) of the bilinear model, ZOH inputs, flows held per interval."""
    x = np.array(x0, dtype=float)
    y = np.empty((t.size, ss.C.shape[0]))
    y[0] = ss.C @ x + ss.D @ u[0]
    for k in range(t.size - 1):
        A = ss.A + np.tensordot(m[k], ss.N, axes=1)
        B = ss.B + np.tensordot(m[k], ss.M, axes=1)
        Phi, Gam = discretize(A, B, t[k + 1] - t[k])
        x = Phi @ x + Gam @ u[k]
        y[k + 1] = ss.C @ x + ss.D @ u[k + 1]
    return y


def kalman_nll(
    ss,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    Qc: np.ndarray,
    R: np.ndarray,
) -> float:
    """``-log L`` of the one-output measurements by a Python-loop Kalman filter (Joseph form)."""
    x = np.array(x0, dtype=float)
    P = np.array(P0, dtype=float)
    c = ss.C[0]
    r = float(R[0, 0])
    eye = np.eye(ss.n_states)
    nll = 0.0
    n_obs = 0
    for k in range(t.size):
        yk = y[k, 0] - ss.D[0] @ u[k]
        if not np.isnan(yk):
            Pc = P @ c
            s = c @ Pc + r
            e = yk - c @ x
            K = Pc / s
            x = x + K * e
            IKC = eye - np.outer(K, c)
            P = IKC @ P @ IKC.T + r * np.outer(K, K)
            P = 0.5 * (P + P.T)
            nll += 0.5 * (np.log(2 * np.pi * s) + e * e / s)
            n_obs += 1
        if k < t.size - 1:
            A = ss.A + np.tensordot(m[k], ss.N, axes=1)
            B = ss.B + np.tensordot(m[k], ss.M, axes=1)
            dt = t[k + 1] - t[k]
            Phi, Gam = discretize(A, B, dt)
            x = Phi @ x + Gam @ u[k]
            P = Phi @ P @ Phi.T + van_loan(A, Qc, dt)
    return float(nll)


def initial_state(ss, u0: np.ndarray, m0: np.ndarray, y0: float) -> np.ndarray:
    """State 0 at the first measurement, the other states in steady state given it."""
    A = ss.A + np.tensordot(m0, ss.N, axes=1)
    B = ss.B + np.tensordot(m0, ss.M, axes=1)
    rest = np.linalg.solve(A[1:, 1:], -(A[1:, 0] * y0 + B[1:] @ u0))
    return np.concatenate([[y0], rest])


def fit_ml(
    network, free: list[str], noise_free: dict[str, float], noise_fixed: dict[str, float], t, m, u, y
) -> tuple[np.ndarray, int]:
    """Nelder-Mead on ``log`` of the free network parameters and the free noise std devs.

    ``noise_free`` gives the start values of the estimated noise parameters (``sigma_v``,
    ``sigma_w_<state>``), ``noise_fixed`` the others (also ``sigma_x0_<state>``). The initial
    state is re-derived at every evaluation (:func:`initial_state`). Returns the optimum
    ``theta`` (network parameters, then noise) and the number of evaluations.
    """
    states = network.state_names
    names = list(free) + list(noise_free)
    start = np.log([network.values()[n] for n in free] + list(noise_free.values()))
    sx = np.array([noise_fixed[f"sigma_x0_{s}"] for s in states])

    def cost(eta: np.ndarray) -> float:
        v = {**noise_fixed, **dict(zip(names, np.exp(eta)))}
        ss = network.state_space({n: v[n] for n in free})
        sw = np.array([v[f"sigma_w_{s}"] for s in states])
        x0 = initial_state(ss, u[0], m[0], y[0, 0])
        R = np.array([[v["sigma_v"] ** 2]])
        return kalman_nll(ss, t, m, u, y, x0, np.diag(sx**2), np.diag(sw**2), R)

    res = minimize(cost, start, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-6, "maxfev": 2000})
    return np.exp(res.x), int(res.nfev)
