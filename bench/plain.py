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


def discretize_foh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """FOH ``(Phi, G0, G1)`` from the exponential of ``[[A, B, 0], [0, 0, I/dt], [0, 0, 0]] dt``."""
    n, p = B.shape
    blk = np.zeros((n + 2 * p, n + 2 * p))
    blk[:n, :n] = A * dt
    blk[:n, n : n + p] = B * dt
    blk[n : n + p, n + p :] = np.eye(p)
    E = expm(blk)
    return E[:n, :n], E[:n, n : n + p] - E[:n, n + p :], E[:n, n + p :]


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
    hold: str = "zoh",
) -> float:
    """``-log L`` of the measurements by a Python-loop Kalman filter (joint update of the observed outputs).

    One ``expm`` per sample for the hold matrices and one for Van Loan's ``Qd``; the observed
    outputs of a sample are updated together (``S = C P C' + R``, gain by ``solve``, Joseph form).
    """
    x = np.array(x0, dtype=float)
    P = np.array(P0, dtype=float)
    n = ss.n_states
    eye = np.eye(n)
    nll = 0.0
    for k in range(t.size):
        yk = y[k] - ss.D @ u[k]
        obs = ~np.isnan(yk)
        if obs.any():
            C = ss.C[obs]
            Rk = R[np.ix_(obs, obs)]
            S = C @ P @ C.T + Rk
            e = yk[obs] - C @ x
            K = np.linalg.solve(S, C @ P).T
            x = x + K @ e
            IKC = eye - K @ C
            P = IKC @ P @ IKC.T + K @ Rk @ K.T
            P = 0.5 * (P + P.T)
            _, logdet = np.linalg.slogdet(S)
            nll += 0.5 * (obs.sum() * np.log(2 * np.pi) + logdet + e @ np.linalg.solve(S, e))
        if k < t.size - 1:
            A = ss.A + np.tensordot(m[k], ss.N, axes=1)
            B = ss.B + np.tensordot(m[k], ss.M, axes=1)
            dt = t[k + 1] - t[k]
            if hold == "foh":
                Phi, G0, G1 = discretize_foh(A, B, dt)
                x = Phi @ x + G0 @ u[k] + G1 @ u[k + 1]
            else:
                Phi, Gam = discretize(A, B, dt)
                x = Phi @ x + Gam @ u[k]
            P = Phi @ P @ Phi.T + van_loan(A, Qc, dt)
    return float(nll)


def initial_state(ss, u0: np.ndarray, m0: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """Measured states (outputs that are a state) at the first measurement, the others in steady state given them."""
    A = ss.A + np.tensordot(m0, ss.N, axes=1)
    B = ss.B + np.tensordot(m0, ss.M, axes=1)
    y0 = np.atleast_1d(y0)
    meas = [int(np.argmax(ss.C[j])) for j in range(ss.C.shape[0])]
    rest = [i for i in range(ss.n_states) if i not in meas]
    x = np.empty(ss.n_states)
    x[meas] = y0
    x[rest] = np.linalg.solve(A[np.ix_(rest, rest)], -(A[np.ix_(rest, meas)] @ y0 + B[rest] @ u0))
    return x


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
        x0 = initial_state(ss, u[0], m[0], y[0])
        R = np.array([[v["sigma_v"] ** 2]])
        return kalman_nll(ss, t, m, u, y, x0, np.diag(sx**2), np.diag(sw**2), R)

    res = minimize(cost, start, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-6, "maxfev": 2000})
    return np.exp(res.x), int(res.nfev)


def fit_ml_lbfgs(
    network, names: list[str], start: dict[str, float], fixed: dict[str, float], data, hold: str
):
    """L-BFGS-B on ``log`` of the positive parameters (``x0_*`` as they are) with a forward-difference gradient.

    The plain way to fit a gradient-free likelihood: scipy's default finite-difference gradient
    (``d + 1`` likelihoods per gradient) on :func:`kalman_nll`. Returns the estimates (in
    ``names`` order) and the number of likelihood evaluations.
    """
    states = network.state_names
    log = np.array([not n.startswith("x0_") for n in names])
    x_start = np.array([np.log(start[n]) if lg else start[n] for n, lg in zip(names, log)])
    n_evals = [0]

    def cost(x: np.ndarray) -> float:
        n_evals[0] += 1
        v = {**fixed, **{n: (np.exp(xi) if lg else xi) for n, xi, lg in zip(names, x, log)}}
        ss = network.state_space({n: v[n] for n in network.free_parameter_names if n in v})
        sw = np.array([v[f"sigma_w_{s}"] for s in states])
        sx = np.array([v[f"sigma_x0_{s}"] for s in states])
        x0 = initial_state(ss, data.u[0], data.m[0], data.y[0])
        for i, s in enumerate(states):
            if f"x0_{s}" in v:
                x0[i] = v[f"x0_{s}"]
        outs = network.outputs
        sv = np.array([v["sigma_v"]] if len(outs) == 1 else [v[f"sigma_v_{o}"] for o in outs])
        return kalman_nll(
            ss, data.t, data.m, data.u, data.y, x0, np.diag(sx**2), np.diag(sw**2), np.diag(sv**2), hold
        )

    res = minimize(cost, x_start, method="L-BFGS-B")
    return np.where(log, np.exp(res.x), res.x), n_evals[0]
