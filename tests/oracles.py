"""Plain NumPy oracles of the compiled paths: the filter, the spectral discretization, the simulation loop, the costs.

These are the references the tests compare rczone's compiled kernels and engines with. They
are written from the textbook recursions in the plainest form (one Python loop over the
samples, dense NumPy algebra, complex values allowed for complex-step differentiation), and
they are not part of the product: nothing in ``src/`` imports them.

References
----------
.. [1] A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman Filter*,
   Cambridge University Press, 1989, section 3.4 (prediction-error decomposition).
.. [2] J. Durbin, S. J. Koopman, *Time Series Analysis by State Space Methods*, 2nd ed.,
   Oxford University Press, 2012, section 6.4 (univariate treatment of multivariate series).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import Objective, log_prior_penalty
from rczone.estimation.data import Dataset
from rczone.estimation.engines import filter_arrays, measured_states, network_theta
from rczone.estimation.kalman import (
    FilterOutput,
    FilterProblem,
    input_drive,
    kalman_filter_arrays,
    measurement_variances,
)
from rczone.network import RCNetwork
from rczone.network.stochastic import initial_state_names
from rczone.simulation.discretize import foh, zoh
from rczone.simulation.simulate import transition_matrices

_LOG_2PI = math.log(2.0 * math.pi)


# ----------------------------------------------------------------------------- the Kalman filter


def update_step(x: np.ndarray, P: np.ndarray, c: np.ndarray, r: float, e: float) -> tuple:
    """Scalar measurement update of one output (the ``update_step`` of :func:`rczone.kernels.kalman.kalman_filter`).

    ``s = c'Pc + r``, ``k = Pc/s``, ``x + k e``, ``P - k (Pc)'``; returns ``(x, P, s)``.
    """
    pc = P @ c
    s = c @ pc + r
    k = pc / s
    P = P - np.outer(k, pc)
    return x + k * e, 0.5 * (P + P.T), s


def predict_step(x: np.ndarray, P: np.ndarray, Phi: np.ndarray, Qd: np.ndarray, drive: np.ndarray) -> tuple:
    """Time update (the ``predict_step`` of :func:`rczone.kernels.kalman.kalman_filter`): ``(Phi x + drive, Phi P Phi' + Qd)``."""
    P = Phi @ P @ Phi.T + Qd
    return Phi @ x + drive, 0.5 * (P + P.T)


def kalman_filter_reference(problem: FilterProblem) -> FilterOutput:
    """Run the filter over all samples in plain NumPy: the reference the compiled filter is tested against.

    ``x0, P0`` are the prior of the state at the first sample (the first measurement is used
    in the likelihood). The observed outputs of each sample are processed one at a time
    (:func:`update_step`); missing ones (NaN in ``y``) are skipped. Complex matrices are
    allowed (complex-step differentiation).

    Parameters
    ----------
    problem : FilterProblem

    Returns
    -------
    FilterOutput
    """
    Phi, Gamma0, Gamma1, Qd, which, u, y, x0, P0, C, D, R = problem
    r = measurement_variances(R)
    N, n, ny = y.shape[0], x0.shape[0], y.shape[1]
    dtype = np.result_type(Phi, Qd, x0, P0, C, D, r, float)
    drive = input_drive(Gamma0, Gamma1, which, u)
    yd = y - u @ D.T
    e_all = np.full((N, ny), np.nan, dtype)
    S_all = np.empty((N, ny, ny), dtype)
    xp_all = np.empty((N, n), dtype)
    xf_all = np.empty((N, n), dtype)
    Pp_all = np.empty((N, n, n), dtype)
    Pf_all = np.empty((N, n, n), dtype)
    x = np.array(x0, dtype=dtype)
    P = np.array(P0, dtype=dtype)
    nll = 0.0
    n_obs = 0
    for k in range(N):
        xp_all[k] = x
        Pp_all[k] = P
        S_all[k] = C @ P @ C.T + np.diag(r)
        obs = np.flatnonzero(~np.isnan(np.real(y[k])))
        e_all[k, obs] = yd[k, obs] - C[obs] @ x
        for j in obs:
            e = yd[k, j] - C[j] @ x
            x, P, s = update_step(x, P, C[j], r[j], e)
            nll = nll + 0.5 * (np.log(s) + e * e / s)
            n_obs += 1
        xf_all[k] = x
        Pf_all[k] = P
        if k < N - 1:
            x, P = predict_step(x, P, Phi[which[k]], Qd[which[k]], drive[k])
    nll = nll + 0.5 * n_obs * _LOG_2PI
    return FilterOutput(
        nll=nll,
        innovations=e_all,
        S=S_all,
        x_pred=xp_all,
        x_filt=xf_all,
        P_pred=Pp_all,
        n_obs=n_obs,
        P_filt=Pf_all,
    )


# ----------------------------------------------------------------------------- the spectral discretization
#
# The NumPy form of the spectral formulas of rczone.simulation.discretize (its module notes), batched
# over intervals; production computes them compiled (rczone.kernels.discretize.interval_matrices).


def spectral_decomposition(A: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of ``S = diag(scale) A diag(scale)^{-1}`` for a stack of matrices.

    ``S`` is symmetrized (``(S + S')/2``, which removes only rounding) and decomposed by a
    closed-form Jacobi rotation for ``n <= 2`` and by LAPACK's symmetric solver otherwise.

    Parameters
    ----------
    A : ndarray, shape (K, n, n)
    scale : ndarray, shape (n,)
        From :func:`symmetrizing_scale`.

    Returns
    -------
    lam : ndarray, shape (K, n)
        Eigenvalues of ``A``, 1/s.
    V : ndarray, shape (K, n, n)
        Orthogonal eigenvectors of ``S`` (columns).

    References
    ----------
    .. [1] G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, Algorithm 8.5.1
       (the symmetric 2-by-2 Schur decomposition).
    """
    S = scale[:, None] * A / scale[None, :]
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    n = S.shape[-1]
    if n == 1:
        return S[:, :, 0].copy(), np.ones_like(S)
    if n == 2:
        return _jacobi2(S[:, 0, 0], S[:, 0, 1], S[:, 1, 1])
    return np.linalg.eigh(S)


def _jacobi2(a: np.ndarray, b: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form eigen-decomposition of symmetric 2x2 matrices ``[[a, b], [b, d]]``.

    The rotation ``J = [[c, s], [-s, c]]`` with ``t = s/c`` the smaller root of
    ``t^2 + 2 tau t - 1 = 0``, ``tau = (d - a)/(2 b)``, gives ``J' S J = diag(a - t b, d + t b)``
    without cancellation (Golub & Van Loan, Algorithm 8.5.1).
    """
    nz = b != 0.0
    bb = np.where(nz, b, 1.0)
    tau = (d - a) / (2.0 * bb)
    # 1/(|tau| + hypot(1, tau)) stays finite for huge |tau|
    t = np.where(nz, np.copysign(1.0, tau) / (np.abs(tau) + np.hypot(1.0, tau)), 0.0)
    c = 1.0 / np.sqrt(1.0 + t * t)
    s = t * c
    lam = np.stack([a - t * b, d + t * b], axis=-1)
    V = np.empty((*a.shape, 2, 2))
    V[..., 0, 0], V[..., 0, 1], V[..., 1, 0], V[..., 1, 1] = c, s, -s, c
    return lam, V


def phi_weights(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``e^x``, ``(e^x - 1)/x`` and ``(e^x - 1 - x)/x^2`` evaluated without cancellation.

    With ``x = lam dt`` these are ``Phi``'s eigenvalues and ``phi1/dt``, ``phi2/dt`` of the
    hold integrals. ``exp`` and ``expm1`` keep the first two accurate to rounding for any ``x``. The
    third uses its Taylor series ``sum_k x^k/(k+2)!`` (k <= 12, truncation below ``1e-19``)
    for ``|x| < 0.2`` and ``(expm1(x) - x)/x^2`` (relative rounding ``< 2 eps/|x| <= 1e-15``)
    otherwise.
    """
    x = np.asarray(x, dtype=float)
    em1 = np.expm1(x)
    zero = x == 0.0
    w1 = np.where(zero, 1.0, em1 / np.where(zero, 1.0, x))
    small = np.abs(x) < _SERIES_LIMIT
    xs = np.where(small, 1.0, x)
    series = np.full_like(x, _PHI2_SERIES[-1])
    for c in _PHI2_SERIES[-2::-1]:
        series = series * x + c
    w2 = np.where(small, series, (em1 - xs) / (xs * xs))
    return np.exp(x), w1, w2


_SERIES_LIMIT = 0.2


#: Taylor coefficients 1/(k+2)! of (e^x - 1 - x)/x^2, k = 0..12.
_PHI2_SERIES = tuple(1.0 / float(np.prod(np.arange(1, k + 3))) for k in range(13))


def spectral_transition(
    lam: np.ndarray, V: np.ndarray, scale: np.ndarray, B: np.ndarray, dt: np.ndarray, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact ZOH/FOH matrices of ``dx/dt = A x + B u`` from the spectral form of ``A``.

    ``Phi = T E T^{-1}``, ``G = T diag(w) T^{-1} B`` with ``T = diag(scale)^{-1} V`` (see the
    module notes); identical to :func:`zoh` / :func:`foh` up to rounding.

    Parameters
    ----------
    lam, V : ndarray, shapes (K, n), (K, n, n)
        From :func:`spectral_decomposition`.
    scale : ndarray, shape (n,)
    B : ndarray, shape (K, n, p)
    dt : ndarray, shape (K,)
        Sample intervals, s.
    hold : {"zoh", "foh"}

    Returns
    -------
    Phi : ndarray, shape (K, n, n)
    G0, G1 : ndarray, shape (K, n, p)
        ``G1`` is zero for ZOH.

    References
    ----------
    .. [1] N. J. Higham, *Functions of Matrices*, SIAM, 2008, section 1.2 (functions of a
       diagonalizable matrix) and section 10.7.4 (the phi functions of exponential
       integrators).
    """
    dt = np.asarray(dt, dtype=float)
    e, w1, w2 = phi_weights(lam * dt[:, None])
    T = V / scale[None, :, None]
    Ti = np.swapaxes(V, -1, -2) * scale[None, None, :]
    Phi = (T * e[:, None, :]) @ Ti
    TiB = Ti @ B
    if hold == "zoh":
        G0 = T @ (TiB * (w1 * dt[:, None])[:, :, None])
        return Phi, G0, np.zeros_like(G0)
    G1 = T @ (TiB * (w2 * dt[:, None])[:, :, None])
    G0 = T @ (TiB * ((w1 - w2) * dt[:, None])[:, :, None])
    return Phi, G0, G1


def spectral_noise_covariance(
    lam: np.ndarray, V: np.ndarray, scale: np.ndarray, Qc: np.ndarray, dt: np.ndarray
) -> np.ndarray:
    """``Qd = int_0^dt e^{As} Qc e^{A's} ds`` in closed form from the spectral form of ``A``.

    In the eigenbasis the integrand is elementwise ``W_ij e^{(l_i + l_j) s}``, whose integral is
    ``W_ij (e^{(l_i + l_j) dt} - 1)/(l_i + l_j)``; every term is evaluated with ``expm1``, so
    stiff models over long steps are as accurate as slow ones (no ``e^{-A dt}`` is formed).

    Parameters
    ----------
    lam, V : ndarray, shapes (K, n), (K, n, n)
    scale : ndarray, shape (n,)
    Qc : ndarray, shape (n, n)
        Continuous noise intensity, K^2/s.
    dt : ndarray, shape (K,)

    Returns
    -------
    Qd : ndarray, shape (K, n, n), symmetric

    References
    ----------
    .. [1] C. F. Van Loan, "Computing integrals involving the matrix exponential",
       IEEE Trans. Automatic Control 23(3), 1978 (the integral being computed).
    """
    dt = np.asarray(dt, dtype=float)
    T = V / scale[None, :, None]
    Ti = np.swapaxes(V, -1, -2) * scale[None, None, :]
    W = Ti @ Qc @ np.swapaxes(Ti, -1, -2)
    x = (lam[:, :, None] + lam[:, None, :]) * dt[:, None, None]
    _, w1, _ = phi_weights(x)
    Qd = T @ (W * w1 * dt[:, None, None]) @ np.swapaxes(T, -1, -2)
    return 0.5 * (Qd + np.swapaxes(Qd, -1, -2))


def transition_matrices_expm(
    ss, uniq: np.ndarray, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One scipy block exponential per row of ``uniq = [dt, m...]`` (:func:`zoh` / :func:`foh`, no spectral path)."""
    K, n, p = uniq.shape[0], ss.n_states, ss.B.shape[1]
    Phi, G0, G1 = np.empty((K, n, n)), np.empty((K, n, p)), np.zeros((K, n, p))
    for k in range(K):
        A, B = ss.matrices(uniq[k, 1:])
        if hold == "zoh":
            Phi[k], G0[k] = zoh(A, B, float(uniq[k, 0]))
        else:
            Phi[k], G0[k], G1[k] = foh(A, B, float(uniq[k, 0]))
    return Phi, G0, G1


# ----------------------------------------------------------------------------- the simulation loop


def propagate_reference(
    Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray, x0: np.ndarray
) -> np.ndarray:
    """``x[k+1] = Phi[w] x[k] + G0[w] u[k] + G1[w] u[k+1]`` in a Python loop (complex values allowed)."""
    N = u.shape[0]
    x = np.empty((N, x0.shape[0]), np.result_type(Phi, G0, G1, u, x0))
    x[0] = x0
    for k in range(N - 1):
        w = which[k]
        x[k + 1] = Phi[w] @ x[k] + G0[w] @ u[k] + G1[w] @ u[k + 1]
    return x


# ----------------------------------------------------------------------------- the identification costs


def trapezoid_reference(t: np.ndarray, e: np.ndarray) -> float:
    """``int e(t)^2 dt`` by the trapezoid rule over the intervals with both ends measured, outputs summed."""
    sq = e * e
    seg = 0.5 * (sq[:-1] + sq[1:]) * np.diff(t)[:, None]
    return float(np.sum(seg[np.isfinite(seg)]))


def initial_state_reference(ss, values: Mapping[str, float], data: Dataset) -> np.ndarray:
    """``x0_<state>`` where given; else measured states at their first measurement, the others at the
    steady state given them (one dense solve)."""
    names = initial_state_names(ss.state_names)
    A, B = ss.matrices(data.m[0]) if ss.n_flows else (ss.A, ss.B)
    y0, u0 = data.y[0], data.u[0]
    meas = {i: j for i, j in measured_states(ss).items() if math.isfinite(y0[j])}
    x = np.zeros(ss.n_states)
    fixed = np.array(sorted(meas), dtype=int)
    free = np.array([i for i in range(ss.n_states) if i not in meas], dtype=int)
    x[fixed] = [y0[meas[i]] for i in fixed]
    if free.size:
        rhs = -(B[free] @ u0) - A[np.ix_(free, fixed)] @ x[fixed]
        x[free] = np.linalg.solve(A[np.ix_(free, free)], rhs)
    for i, n in enumerate(names):
        if n in values:
            x[i] = values[n]
    return x


def reference_cost(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str, method: str
) -> float:
    """``J_LS`` (``method="ls"``, trapezoid rule on the open-loop errors) or ``-log L``, in plain NumPy."""
    if method == "ls":
        ss = network.state_space(network_theta(network, values))
        x0 = initial_state_reference(ss, values, data)
        Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, hold)
        x = propagate_reference(Phi, G0, G1, which, data.u, x0)
        return trapezoid_reference(data.t, data.y - (x @ ss.C.T + data.u @ ss.D.T))
    return kalman_filter_reference(filter_arrays(network, values, data, hold)).nll


def objective_reference_cost(objective: Objective, theta: np.ndarray) -> float:
    """The cost of ``objective`` at physical values ``theta`` by :func:`reference_cost`; ``inf`` where invalid."""
    values = objective.spec.values(theta)
    try:
        j = reference_cost(
            objective.network,
            values,
            objective.data,
            objective.hold,
            "ls" if objective.method == "ls" else "ml",
        )
    except (ParameterError, np.linalg.LinAlgError):
        return math.inf
    if objective.method == "map":
        j = objective.likelihood_weight * j + log_prior_penalty(
            objective.spec, np.asarray(theta, dtype=float), objective.prior_spread
        )
    return j if math.isfinite(j) else math.inf


# ----------------------------------------------------------------------------- the k-step predictor


def k_step_prediction_error(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, k: int = 1, hold: str = "zoh"
) -> np.ndarray:
    """``y[j] - y_hat[j | j - k]`` from the filtered state at ``j - k`` stepped by hand; NaN for the first ``k``.

    The loop form of :func:`rczone.estimation.forecast.k_step_band` (which is vectorized over origins).
    """
    problem = filter_arrays(network, values, data, hold)
    out = kalman_filter_arrays(problem)
    drive = input_drive(problem.G0, problem.G1, problem.which, problem.u)
    err = np.full(problem.y.shape, np.nan)
    for j in range(k, data.n_samples):
        x = out.x_filt[j - k]
        for i in range(j - k, j):
            x = problem.Phi[problem.which[i]] @ x + drive[i]
        err[j] = problem.y[j] - (problem.C @ x + problem.D @ problem.u[j])
    return err


def k_step_prediction_sd(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, k: int = 1, hold: str = "zoh"
) -> np.ndarray:
    """The standard deviation of ``y_hat[j | j - k]``: ``P_j-k|j-k`` stepped by hand, ``C P C' + R``.

    The loop form of the variance :func:`rczone.estimation.forecast.k_step_band` computes (with the
    process noise of each interval, Madsen 2007, section 10.3); NaN for the first ``k``.
    """
    problem = filter_arrays(network, values, data, hold)
    out = kalman_filter_arrays(problem)
    sd = np.full(problem.y.shape, np.nan)
    for j in range(k, data.n_samples):
        P = out.P_filt[j - k]
        for i in range(j - k, j):
            F = problem.Phi[problem.which[i]]
            P = F @ P @ F.T + problem.Qd[problem.which[i]]
        sd[j] = np.sqrt(np.diag(problem.C @ P @ problem.C.T + problem.R))
    return sd
