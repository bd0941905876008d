"""Kalman-filter likelihood of a continuous-discrete stochastic RC model.

The model (Madsen & Holst 1995) is the bilinear RC network driven by white noise and
observed at discrete, possibly irregular, times:

.. math::

    dx = \\big(A(m)\\,x + B(m)\\,u\\big)\\,dt + \\sigma\\,dW, \\qquad
    y_k = C x_k + D u_k + v_k, \\quad v_k \\sim N(0, R)

The flows ``m`` are known and held constant over each interval, so each interval is
LTI and is discretized exactly: ``Phi = e^{A dt}``, the ZOH or FOH input matrices, and
``Qd = int_0^dt e^{As} Q_c e^{A's} ds`` with ``Q_c = sigma sigma'`` (Van Loan). The
discretizations are computed once per distinct ``(dt, m)`` (the scheme of
:func:`rczone.simulation.simulate.transition_matrices`).

The filter loop is a pure function over arrays (:func:`kalman_filter_arrays`) so that a
compiled version can replace it; this plain-NumPy version is the reference.

References
----------
.. [1] H. Madsen, J. Holst, "Estimation of continuous-time models for the heat dynamics
   of a building", Energy and Buildings 22 (1995) 67-79.
.. [2] A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman
   Filter*, Cambridge University Press, 1989, section 3.4 (prediction-error
   decomposition of the likelihood).
.. [3] R. S. Bucy, P. D. Joseph, *Filtering for Stochastic Processes with Applications
   to Guidance*, 1968 (the Joseph-form covariance update).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from rczone.errors import InputShapeError
from rczone.network.statespace import BilinearStateSpace
from rczone.simulation.discretize import (
    foh,
    spectral_decomposition,
    spectral_noise_covariance,
    spectral_transition,
    symmetrizing_scale,
    van_loan,
    zoh,
)
from rczone.simulation.intervals import interval_keys, unique_rows
from rczone.simulation.simulate import HOLDS

_LOG_2PI = float(np.log(2.0 * np.pi))


def process_noise_covariance(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """``Qd = int_0^dt e^{As} Qc e^{A's} ds`` by Van Loan on a short step and doubling.

    Van Loan's block exponential contains ``e^{-A dt}``; for a stiff model over a long
    interval (``|lambda| dt`` of hundreds) it overflows into cancellation and returns
    garbage. Here the interval is halved ``s`` times until ``||A|| h <= 1/2``, Van Loan is
    applied on ``h``, and the exact doubling ``Qd(2h) = Qd(h) + Phi(h) Qd(h) Phi(h)'``,
    ``Phi(2h) = Phi(h)^2`` recovers ``dt``. Every step adds positive semidefinite terms,
    so no cancellation occurs.

    Parameters
    ----------
    A : ndarray, shape (n, n), 1/s
    Qc : ndarray, shape (n, n), K^2/s
    dt : float, s

    Returns
    -------
    ndarray, shape (n, n), symmetric
    """
    norm = float(np.linalg.norm(A, 1)) * dt
    s = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    h = dt / 2.0**s
    Q = van_loan(A, Qc, h)
    Phi = expm(A * h)
    for _ in range(s):
        Q = Q + Phi @ Q @ Phi.T
        Phi = Phi @ Phi
    return 0.5 * (Q + Q.T)


def stochastic_matrices(
    ss: BilinearStateSpace, t: np.ndarray, m: np.ndarray, Qc: np.ndarray, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact per-interval discretization of the stochastic model.

    Parameters
    ----------
    ss : BilinearStateSpace
    t : ndarray, shape (N,)
        Sample times, s.
    m : ndarray, shape (N, n_flows)
        Flows held constant from ``t[k]`` to ``t[k+1]``.
    Qc : ndarray, shape (n, n)
        Continuous process-noise intensity, K^2/s.
    hold : {"zoh", "foh"}

    Returns
    -------
    Phi : ndarray, shape (K, n, n)
    G0, G1 : ndarray, shape (K, n, p)
    Qd : ndarray, shape (K, n, n)
    which : ndarray of int, shape (N-1,)
        Index of the discretization used on each interval.
    """
    if hold not in HOLDS:
        raise InputShapeError(f"hold must be one of {HOLDS}, got {hold!r}")
    uniq, _, which = unique_rows(interval_keys(t, m))
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    if scale is not None:
        # RC network: every matrix in closed form from one symmetric eigen-decomposition per key
        A = ss.A + np.tensordot(uniq[:, 1:], ss.N, axes=1)
        B = ss.B + np.tensordot(uniq[:, 1:], ss.M, axes=1)
        lam, V = spectral_decomposition(A, scale)
        Phi, G0, G1 = spectral_transition(lam, V, scale, B, uniq[:, 0], hold)
        Qd = spectral_noise_covariance(lam, V, scale, np.asarray(Qc, dtype=float), uniq[:, 0])
        return Phi, G0, G1, Qd, which.reshape(-1)
    n, p, K = ss.n_states, ss.n_inputs, uniq.shape[0]
    Phi = np.empty((K, n, n))
    G0 = np.empty((K, n, p))
    G1 = np.zeros((K, n, p))
    Qd = np.zeros((K, n, n))
    noisy = bool(np.any(Qc))
    for k in range(K):
        A, B = ss.matrices(uniq[k, 1:]) if ss.n_flows else (ss.A, ss.B)
        dt = float(uniq[k, 0])
        if hold == "zoh":
            Phi[k], G0[k] = zoh(A, B, dt)
        else:
            Phi[k], G0[k], G1[k] = foh(A, B, dt)
        if noisy:
            Qd[k] = process_noise_covariance(A, Qc, dt)
    return Phi, G0, G1, Qd, which.reshape(-1)


def input_drive(G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Deterministic input contribution ``G0[w] u[k] + G1[w] u[k+1]`` per interval, shape (N-1, n)."""
    out = np.empty((u.shape[0] - 1, G0.shape[1]))
    for w in np.unique(which):
        sel = which == w
        out[sel] = u[:-1][sel] @ G0[w].T + u[1:][sel] @ G1[w].T
    return out


@dataclass(frozen=True, eq=False)
class FilterOutput:
    """Everything the filter computes, time-first.

    Attributes
    ----------
    nll : float
        ``-log L`` including ``0.5 n log(2 pi)`` (n = number of observed scalars).
    innovations : ndarray, shape (N, ny)
        ``y_k - y_k|k-1``; NaN where ``y`` is missing.
    S : ndarray, shape (N, ny, ny)
        Innovation covariances (also where ``y`` is missing).
    x_pred, x_filt : ndarray, shape (N, n)
        One-step predicted and filtered states.
    P_pred : ndarray, shape (N, n, n)
    n_obs : int
        Number of observed scalars.
    """

    nll: float
    innovations: np.ndarray
    S: np.ndarray
    x_pred: np.ndarray
    x_filt: np.ndarray
    P_pred: np.ndarray
    n_obs: int


def kalman_filter_arrays(
    Phi: np.ndarray,
    Gamma0: np.ndarray,
    Gamma1: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    C: np.ndarray,
    D: np.ndarray,
    R: np.ndarray,
) -> FilterOutput:
    """Run the Kalman filter over all samples; the reference implementation.

    ``x0, P0`` are the prior of the state at the first sample (the first measurement
    is used in the likelihood). Missing measurements (NaN in ``y``) skip the update;
    with several outputs only the observed components are used. The covariance update
    is the Joseph form, symmetrized.

    Parameters
    ----------
    Phi, Gamma0, Gamma1, Qd, which
        From :func:`stochastic_matrices`.
    u : ndarray, shape (N, p)
    y : ndarray, shape (N, ny)
    x0 : ndarray, shape (n,)
    P0 : ndarray, shape (n, n)
    C : ndarray, shape (ny, n)
    D : ndarray, shape (ny, p)
    R : ndarray, shape (ny, ny)
        Measurement-noise covariance, K^2.

    Returns
    -------
    FilterOutput
    """
    N, n = y.shape[0], x0.shape[0]
    ny = y.shape[1]
    drive = input_drive(Gamma0, Gamma1, which, u)
    yd = y - u @ D.T
    eye = np.eye(n)
    e_all = np.full((N, ny), np.nan)
    S_all = np.empty((N, ny, ny))
    xp_all = np.empty((N, n))
    xf_all = np.empty((N, n))
    Pp_all = np.empty((N, n, n))
    x = np.array(x0, dtype=float)
    P = np.array(P0, dtype=float)
    nll = 0.0
    n_obs = 0
    for k in range(N):
        xp_all[k] = x
        Pp_all[k] = P
        S_full = C @ P @ C.T + R
        S_all[k] = S_full
        obs = ~np.isnan(yd[k])
        if obs.all() and ny == 1:
            # scalar fast path: no matrix inverse
            Pc = P @ C[0]
            s = float(C[0] @ Pc) + R[0, 0]
            e = yd[k, 0] - float(C[0] @ x)
            K = Pc / s
            x = x + K * e
            IKC = eye - np.outer(K, C[0])
            P = IKC @ P @ IKC.T + R[0, 0] * np.outer(K, K)
            nll += 0.5 * (np.log(s) + e * e / s)
            e_all[k, 0] = e
            n_obs += 1
        elif obs.any():
            Co, Ro = C[obs], R[np.ix_(obs, obs)]
            So = S_full[np.ix_(obs, obs)]
            e = yd[k, obs] - Co @ x
            L = np.linalg.cholesky(So)
            PCt = P @ Co.T
            K = np.linalg.solve(So, PCt.T).T
            x = x + K @ e
            IKC = eye - K @ Co
            P = IKC @ P @ IKC.T + K @ Ro @ K.T
            w = np.linalg.solve(L, e)
            nll += float(np.sum(np.log(np.diag(L)))) + 0.5 * float(w @ w)
            e_all[k, obs] = e
            n_obs += int(obs.sum())
        P = 0.5 * (P + P.T)
        xf_all[k] = x
        if k < N - 1:
            wk = which[k]
            x = Phi[wk] @ x + drive[k]
            P = Phi[wk] @ P @ Phi[wk].T + Qd[wk]
    nll += 0.5 * n_obs * _LOG_2PI
    return FilterOutput(float(nll), e_all, S_all, xp_all, xf_all, Pp_all, n_obs)


def kalman_nll(
    Phi: np.ndarray,
    Gamma0: np.ndarray,
    Gamma1: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    C: np.ndarray,
    D: np.ndarray,
    R: np.ndarray,
) -> float:
    """``-log L`` (including ``0.5 n log 2 pi``) of the measurements; see :func:`kalman_filter_arrays`."""
    return kalman_filter_arrays(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R).nll


def _nll_scalar_loop(
    Phi: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    drive: np.ndarray,
    yd: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    c: np.ndarray,
    r: float,
    e_out: np.ndarray,
) -> float:
    """Scalar-output filter loop with explicit loops, compiled by numba.

    Same recursion as :func:`kalman_filter_arrays` (Joseph form, symmetrized) for one
    output; ``yd = y - D u`` with NaN for missing samples. Returns ``-log L`` without
    the ``0.5 n log 2 pi`` term, and the number of observations. The innovations are
    written into ``e_out`` when it has one entry per sample (pass an empty array to skip).
    """
    keep = e_out.shape[0] == yd.shape[0]
    n = x0.shape[0]
    N = yd.shape[0]
    x = x0.copy()
    P = P0.copy()
    Pc = np.empty(n)
    K = np.empty(n)
    T = np.empty((n, n))
    IKC = np.empty((n, n))
    xn = np.empty(n)
    nll = 0.0
    n_obs = 0
    for k in range(N):
        if not np.isnan(yd[k]):
            s = r
            e = yd[k]
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += P[i, j] * c[j]
                Pc[i] = acc
                s += c[i] * acc
                e -= c[i] * x[i]
            for i in range(n):
                K[i] = Pc[i] / s
                x[i] += K[i] * e
            for i in range(n):
                for j in range(n):
                    IKC[i, j] = (1.0 if i == j else 0.0) - K[i] * c[j]
            for i in range(n):
                for j in range(n):
                    acc = 0.0
                    for a in range(n):
                        acc += IKC[i, a] * P[a, j]
                    T[i, j] = acc
            for i in range(n):
                for j in range(i, n):
                    acc = 0.0
                    for a in range(n):
                        acc += T[i, a] * IKC[j, a]
                    acc += r * K[i] * K[j]
                    P[i, j] = acc
                    P[j, i] = acc
            nll += 0.5 * (np.log(s) + e * e / s)
            n_obs += 1
            if keep:
                e_out[k] = e
        if k < N - 1:
            w = which[k]
            for i in range(n):
                acc = drive[k, i]
                for j in range(n):
                    acc += Phi[w, i, j] * x[j]
                xn[i] = acc
            for i in range(n):
                x[i] = xn[i]
            for i in range(n):
                for j in range(n):
                    acc = 0.0
                    for a in range(n):
                        acc += Phi[w, i, a] * P[a, j]
                    T[i, j] = acc
            for i in range(n):
                for j in range(i, n):
                    acc = Qd[w, i, j]
                    for a in range(n):
                        acc += T[i, a] * Phi[w, j, a]
                    P[i, j] = acc
                    P[j, i] = acc
    return nll, n_obs


try:  # numba is a declared dependency; the pure-Python loop stays usable without it
    import numba

    _nll_scalar_compiled = numba.njit(cache=True)(_nll_scalar_loop)
except ImportError:  # pragma: no cover
    _nll_scalar_compiled = _nll_scalar_loop


def kalman_nll_fast(
    Phi: np.ndarray,
    Gamma0: np.ndarray,
    Gamma1: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    C: np.ndarray,
    D: np.ndarray,
    R: np.ndarray,
) -> float:
    """Same value as :func:`kalman_nll`; compiled loop for one output, reference otherwise."""
    if y.shape[1] != 1:
        return kalman_nll(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R)
    return _scalar_filter(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R, np.empty(0))


def kalman_innovations_fast(
    Phi: np.ndarray,
    Gamma0: np.ndarray,
    Gamma1: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    C: np.ndarray,
    D: np.ndarray,
    R: np.ndarray,
) -> np.ndarray:
    """One-step-ahead prediction errors, shape (N, ny), NaN where missing (compiled for one output)."""
    if y.shape[1] != 1:
        return kalman_filter_arrays(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R).innovations
    e = np.full(y.shape[0], np.nan)
    _scalar_filter(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R, e)
    return e[:, None]


def _scalar_filter(Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R, e_out) -> float:
    drive = input_drive(Gamma0, Gamma1, which, u)
    yd = np.ascontiguousarray((y - u @ D.T)[:, 0])
    nll, n_obs = _nll_scalar_compiled(
        np.ascontiguousarray(Phi),
        np.ascontiguousarray(Qd),
        np.ascontiguousarray(which, dtype=np.int64),
        np.ascontiguousarray(drive),
        yd,
        np.ascontiguousarray(x0, dtype=float),
        np.ascontiguousarray(P0, dtype=float),
        np.ascontiguousarray(C[0], dtype=float),
        float(R[0, 0]),
        e_out,
    )
    return float(nll + 0.5 * n_obs * _LOG_2PI)
