"""Exact discretization of LTI state spaces: the one place that says how it is done.

* zero-order hold (inputs constant over a sample),
* first-order hold (inputs linear between samples),
* the discrete process-noise covariance of a continuous white-noise input (Van Loan),
* the mean of the state over a zero-order-hold step (:func:`zoh_with_mean`, for references stated
  in hourly means).

:func:`zoh`, :func:`foh` and :func:`van_loan` work for any state space through one block
matrix exponential; :func:`process_noise_covariance` makes Van Loan's integral safe for
stiff models over long steps. For RC networks the same matrices follow exactly from a
symmetric eigen-decomposition (the identities are in the notes below), in closed form for two
states; :func:`rank_one_form` prepares the rank-one structure that the compiled simulation of
:mod:`rczone.kernels.rankone` exploits. All functions are pure over arrays.

:func:`interval_discretization` gives the matrices of every distinct sampling interval of a
bilinear model (the simulation, the Kalman filter and the smoother use it). It is a thin caller
of the compiled implementation, :func:`rczone.kernels.discretize.interval_matrices` (spectral
formulas for RC networks, compiled block exponentials otherwise), which the estimation engines
call directly with derivatives: the formulas exist once in production. Only complex matrices
(complex-step differentiation) and a process noise that is not diagonal take the block
exponentials of this module per interval. The plain NumPy spectral formulas are the tests'
oracles (``tests/oracles.py``).

References
----------
.. [1] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of Dynamic Systems*,
   3rd ed., 1998, sections 6.3 (ZOH) and 6.3.2 (triangle hold / FOH).
.. [2] C. F. Van Loan, "Computing integrals involving the matrix exponential",
   IEEE Trans. Automatic Control 23(3), 1978.
.. [3] N. J. Higham, *Functions of Matrices*, SIAM, 2008.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.linalg import expm, expm_frechet

from rczone.kernels.arrays import Dynamics


def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretization: ``x[k+1] = Phi x[k] + Gamma u[k]``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, p)
    dt : float
        Sample interval, s.

    Returns
    -------
    Phi : ndarray, shape (n, n)
    Gamma : ndarray, shape (n, p)

    Examples
    --------
    A room of time constant ``tau = R C`` driven by the outdoor temperature: one step is the
    exact exponential, ``Phi = exp(-dt / tau)``, ``Gamma = 1 - Phi`` (the DC gain is one).

    >>> import numpy as np
    >>> tau = 1e6 * 0.01
    >>> Phi, Gamma = zoh(np.array([[-1 / tau]]), np.array([[1 / tau]]), 600.0)
    >>> bool(np.isclose(Phi[0, 0], np.exp(-600.0 / tau)) and np.isclose(Gamma[0, 0], 1 - Phi[0, 0]))
    True
    """
    n = A.shape[0]
    E = expm(_zoh_block(A, B, dt))
    return E[:n, :n], E[:n, n:]


def _zoh_block(A: np.ndarray, B: np.ndarray, dt: float) -> np.ndarray:
    """``[[A dt, B dt], [0, 0]]``, whose exponential holds the ZOH pair."""
    n, p = B.shape
    blk = np.zeros((n + p, n + p), np.result_type(A, B))
    blk[:n, :n] = A * dt
    blk[:n, n:] = B * dt
    return blk


class ZohWithMean(NamedTuple):
    """A zero-order-hold step and the mean of the state over it (:func:`zoh_with_mean`)."""

    Phi: np.ndarray  #: (n, n), ``x[k+1] = Phi x[k] + Gamma u[k]``
    Gamma: np.ndarray  #: (n, p)
    Psi: np.ndarray  #: (n, n), mean over the step ``= Psi x[k] + Lambda u[k]``
    Lambda: np.ndarray  #: (n, p)


def zoh_with_mean(A: np.ndarray, B: np.ndarray, dt: float) -> ZohWithMean:
    """A zero-order-hold step and the exact mean of the state over it, from one block exponential.

    ``(1/dt) integral_0^dt x(s) ds = Psi x[k] + Lambda u[k]``: the quantity hourly-mean
    references (VDI 6007) are stated in. The exponential of ``[[0, I, 0], [0, A, B], [0, 0, 0]] dt``
    holds ``Phi``, ``Gamma`` and the integrals ``int e^{As} ds`` and ``int int e^{Ar} B dr ds``
    (Van Loan [2]_).

    Examples
    --------
    One node of time constant ``tau``: the mean of ``x`` decaying from 1 with no input over a step
    is ``(1 - exp(-dt / tau)) tau / dt``.

    >>> import numpy as np
    >>> step = zoh_with_mean(np.array([[-1 / 3600.0]]), np.zeros((1, 1)), 3600.0)
    >>> bool(np.isclose(step.Psi[0, 0], 1 - np.exp(-1.0)))
    True
    """
    n, p = B.shape
    big = np.zeros((2 * n + p, 2 * n + p), np.result_type(A, B, float))
    big[:n, n : 2 * n] = np.eye(n)
    big[n : 2 * n, n : 2 * n] = A
    big[n : 2 * n, 2 * n :] = B
    E = expm(big * dt)
    return ZohWithMean(
        E[n : 2 * n, n : 2 * n], E[n : 2 * n, 2 * n :], E[:n, n : 2 * n] / dt, E[:n, 2 * n :] / dt
    )


def zoh_derivative(
    A: np.ndarray, B: np.ndarray, dA: np.ndarray, dB: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Derivative of the :func:`zoh` pair ``(Phi, Gamma)`` along a direction ``(dA, dB)``.

    The ZOH pair is a block of ``expm([[A dt, B dt], [0, 0]])``; its derivative is the same
    block of the Fréchet derivative of the exponential in the direction ``[[dA dt, dB dt],
    [0, 0]]`` (Higham [3]_, section 10.6; scipy's ``expm_frechet``). With ``dA = N``, ``dB = M``
    this is the sensitivity of the exact discrete model to a supply flow.

    Returns
    -------
    dPhi : ndarray, shape (n, n)
    dGamma : ndarray, shape (n, p)
    """
    n = A.shape[0]
    _, L = expm_frechet(_zoh_block(A, B, dt), _zoh_block(dA, dB, dt))
    return L[:n, :n], L[:n, n:]


def foh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-order-hold discretization: ``x[k+1] = Phi x[k] + G0 u[k] + G1 u[k+1]``.

    The input is linear between the samples ``u[k]`` and ``u[k+1]``.

    Returns
    -------
    Phi : ndarray, shape (n, n)
    G0, G1 : ndarray, shape (n, p)
    """
    n, p = B.shape
    blk = np.zeros((n + 2 * p, n + 2 * p), np.result_type(A, B))
    blk[:n, :n] = A * dt
    blk[:n, n : n + p] = B * dt
    blk[n : n + p, n + p :] = np.eye(p)
    E = expm(blk)
    gz, gr = E[:n, n : n + p], E[:n, n + p :]
    return E[:n, :n], gz - gr, gr


def van_loan(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """Discrete covariance ``Qd = int_0^dt e^{A s} Qc e^{A' s} ds`` of continuous white noise.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    Qc : ndarray, shape (n, n)
        Continuous-time noise intensity (``sigma sigma'``), units of x^2/s.
    dt : float

    Returns
    -------
    Qd : ndarray, shape (n, n), symmetric
    """
    n = A.shape[0]
    blk = np.zeros((2 * n, 2 * n), np.result_type(A, Qc))
    blk[:n, :n] = -A * dt
    blk[:n, n:] = Qc * dt
    blk[n:, n:] = A.T * dt
    E = expm(blk)
    Phi_T = E[n:, n:]
    Qd = Phi_T.T @ E[:n, n:]
    return 0.5 * (Qd + Qd.T)


def process_noise_covariance(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """``Qd = int_0^dt e^{As} Qc e^{A's} ds`` by Van Loan on a short step and doubling.

    Van Loan's block exponential contains ``e^{-A dt}``; for a stiff model over a long
    interval (``|lambda| dt`` of hundreds) it overflows into cancellation and returns
    garbage. Here the interval is halved ``s`` times until ``||A|| h <= 1/2``, Van Loan is
    applied on ``h``, and the exact doubling ``Qd(2h) = Qd(h) + Phi(h) Qd(h) Phi(h)'``,
    ``Phi(2h) = Phi(h)^2`` recovers ``dt``. Every step adds positive semidefinite terms,
    so no cancellation occurs. Complex arguments are allowed (complex-step differentiation).

    Parameters
    ----------
    A : ndarray, shape (n, n), 1/s
    Qc : ndarray, shape (n, n), K^2/s
    dt : float, s

    Returns
    -------
    ndarray, shape (n, n), symmetric
    """
    norm = float(np.linalg.norm(np.real(A), 1)) * dt
    s = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    h = dt / 2.0**s
    Q = van_loan(A, Qc, h)
    Phi = expm(A * h)
    for _ in range(s):
        Q = Q + Phi @ Q @ Phi.T
        Phi = Phi @ Phi
    return 0.5 * (Q + Q.T)


# ---------------------------------------------------------------------------
# Spectral (exact, expm-free) discretization of RC state matrices
# ---------------------------------------------------------------------------
#
# An RC network's energy balance is ``Cap dx/dt = -G x + ...`` with ``Cap`` diagonal
# positive and ``G`` a symmetric conductance matrix (Kron reduction of massless nodes keeps it
# symmetric; supply air adds ``m cp`` to a diagonal entry). Hence ``A = Cap^{-1} (-G - m cp e e')``
# and ``S = Cap^{1/2} A Cap^{-1/2}`` is symmetric: ``S = V diag(lam) V'`` with ``V``
# orthogonal and ``lam`` real. Every function of ``A`` needed by the discretization then
# reduces to scalar functions of the eigenvalues:
#
#   Phi  = T diag(e^{lam dt}) T^{-1},            T = Cap^{-1/2} V,  T^{-1} = V' Cap^{1/2}
#   Gamma_zoh = T diag(phi1(lam)) T^{-1} B,      phi1(l) = int_0^dt e^{l s} ds = (e^{l dt} - 1)/l
#   G1 (FOH)  = T diag(phi2(lam)) T^{-1} B,      phi2(l) = (e^{l dt} - 1 - l dt)/(l^2 dt)
#   G0 (FOH)  = Gamma_zoh - G1
#   Qd = T W T',  W_ij = (T^{-1} Qc T^{-T})_ij (e^{(l_i + l_j) dt} - 1)/(l_i + l_j)
#
# These are exact identities (no truncation); the scalar functions are evaluated with
# ``expm1`` and a short series where ``l dt`` is tiny, so they are accurate to rounding for
# slow and for stiff modes alike (unlike Van Loan's block exponential, which contains
# ``e^{-A dt}`` and loses everything for stiff models over long steps).
#
# Derivatives (compiled only, :func:`rczone.kernels.discretize.spectral_derivatives`). Since
# ``f(A) = Cap^{-1/2} f(S) Cap^{1/2}`` for any ``A`` with the scale held fixed, a direction ``dA``
# (symmetrizable or not: a capacity's is not) enters as ``E = T^{-1} dA T``, and the
# Daleckii-Krein theorem gives ``d f(A) = T (f[l_i, l_j] o E) T^{-1}`` with the divided
# differences of ``f``. With ``x = l dt``: ``e^{l dt}[l_i, l_j] = dt exp[x_i, x_j]``,
# ``phi1[.] = dt^2 exp[0, x_i, x_j]``, ``phi2[.] = dt^2 exp[0, 0, x_i, x_j]`` (``phi1(x) = exp[0, x]``,
# ``phi2(x) = exp[0, 0, x]``), and ``dQd = T (X + X' + (T^{-1} dQc T^{-T}) o Om) T'`` with
# ``X_il = sum_j E_ij W_jl dt^2 exp[0, x_i + x_l, x_j + x_l]`` and ``Om_ij = dt exp[0, x_i + x_j]``.

#: Relative asymmetry of ``Cap A`` (and of every ``Cap N_k``) tolerated by :func:`symmetrizing_scale`.
SYMMETRY_RTOL = 1e-12


def symmetrizing_scale(A: np.ndarray, N: np.ndarray, capacities: np.ndarray) -> np.ndarray | None:
    """``sqrt(capacities)`` if it symmetrizes ``A + sum m_k N_k`` for every ``m``, else None.

    The spectral discretization (:func:`rczone.kernels.discretize.interval_matrices`) is valid when
    ``diag(c) A`` and every ``diag(c) N_k`` are symmetric (an RC network with supply air
    entering capacitive nodes). This is checked numerically, to a relative tolerance
    :data:`SYMMETRY_RTOL`, so that a state space of another form (for example the block
    system of the sensitivity equations) falls back to the general matrix exponential.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    N : ndarray, shape (n_flows, n, n)
    capacities : ndarray, shape (n,)
        Heat capacities of the states, J/K.

    Returns
    -------
    ndarray, shape (n,), or None
    """
    if np.iscomplexobj(A) or np.iscomplexobj(N):
        return None  # complex-step differentiation: the eigen-decomposition is not analytic
    c = np.asarray(capacities, dtype=float)
    if c.shape != (A.shape[0],) or not np.all(np.isfinite(c)) or np.any(c <= 0):
        return None
    CA = c[None, :, None] * np.concatenate([A[None], N])
    if not np.all(np.isfinite(CA)):
        return None
    asym = np.abs(CA - np.swapaxes(CA, 1, 2)).max(axis=(1, 2))
    if np.any(asym > SYMMETRY_RTOL * np.abs(CA).max(axis=(1, 2))):
        return None
    return np.sqrt(c)


@dataclass(frozen=True)
class RankOneForm:
    """``diag(s) (A + m N) diag(s)^{-1} = Q (diag(d) + m sigma z z') Q'`` with deflation done.

    Attributes
    ----------
    Q : ndarray, shape (n, n)
        Orthogonal; columns ordered as the ``r`` active components (``d`` ascending) and then
        the deflated ones (``z_j = 0``: eigenpairs independent of ``m``).
    d : ndarray, shape (n,)
    z : ndarray, shape (r,)
        Active components of ``Q' w``; every one is non-negligible.
    sigma : float
        The one non-zero eigenvalue of ``diag(s) N diag(s)^{-1}`` (``-cp/C`` for supply air).
    scale : ndarray, shape (n,)
        ``s = sqrt(capacities)``.
    """

    Q: np.ndarray
    d: np.ndarray
    z: np.ndarray
    sigma: float
    scale: np.ndarray

    @property
    def r(self) -> int:
        return self.z.shape[0]


def rank_one_form(A: np.ndarray, N: np.ndarray, scale: np.ndarray, m_max: float) -> RankOneForm | None:
    """The rank-one structure of a one-flow RC model, or None when it does not apply.

    ``S(m) = diag(s) (A + m N) diag(s)^{-1} = S0 + m sigma w w'`` when the flow term is of rank
    one (supply air into one capacitive node). With ``S0 = Q0 diag(d) Q0'``, ``z = Q0' w``.
    Deflation (once, for all ``|m| <= m_max``): a component with
    ``|rho_max z_j| |z| <= tol`` is dropped, and two nearly equal ``d`` are rotated so that one
    ``z`` vanishes when the rotation's off-diagonal ``|(d_j - d_i) c s| <= tol``; here
    ``tol = 8 eps max(|d|, |rho_max| |z|^2)``. Each deflation perturbs ``S`` by at most ``tol``
    in norm, i.e. relative ``8 eps``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    N : ndarray, shape (1, n, n)
    scale : ndarray, shape (n,)
        From :func:`symmetrizing_scale`.
    m_max : float
        Largest ``|m|`` in the data.

    References
    ----------
    .. [1] J. J. Dongarra, D. C. Sorensen, "A fully parallel algorithm for the symmetric
       eigenvalue problem", SIAM J. Sci. Stat. Comput. 8(2) (1987), section 3 (deflation).
    """
    if N.shape[0] != 1:
        return None
    S0 = scale[:, None] * A / scale[None, :]
    Sig = scale[:, None] * N[0] / scale[None, :]
    nz = np.flatnonzero(Sig)
    if nz.size == 1 and nz[0] % (A.shape[0] + 1) == 0:  # supply air: one diagonal entry
        i = nz[0] // (A.shape[0] + 1)
        sigma, w = float(Sig[i, i]), np.eye(A.shape[0])[i]
    else:
        ev, W = np.linalg.eigh(0.5 * (Sig + Sig.T))
        k = int(np.argmax(np.abs(ev)))
        big = abs(ev[k])
        if big == 0.0 or np.sum(np.abs(ev) > 1e-13 * big) != 1:
            return None
        sigma, w = float(ev[k]), W[:, k]
    dv, Q = np.linalg.eigh(0.5 * (S0 + S0.T))
    Q = Q.copy()
    zv = Q.T @ w
    d, z = dv.tolist(), zv.tolist()  # scalar work below is faster on Python floats
    rho = abs(sigma) * float(m_max)
    tol = 8 * float(np.finfo(float).eps) * max(float(np.max(np.abs(dv))), rho * float(zv @ zv))
    znorm = math.sqrt(float(zv @ zv))
    active = [j for j in range(len(d)) if rho * abs(z[j]) * znorm > tol]
    deflated = [j for j in range(len(d)) if rho * abs(z[j]) * znorm <= tol]
    keep: list[int] = []
    for j in active:  # ascending d
        if keep:
            i = keep[-1]
            rr = math.hypot(z[i], z[j])
            c, s = z[j] / rr, z[i] / rr
            if abs((d[j] - d[i]) * c * s) <= tol:
                qi, qj = Q[:, i].copy(), Q[:, j].copy()
                Q[:, i], Q[:, j] = c * qi - s * qj, s * qi + c * qj
                d[i], d[j] = c * c * d[i] + s * s * d[j], s * s * d[i] + c * c * d[j]
                z[i], z[j] = 0.0, rr
                keep[-1] = j
                deflated.append(i)
                continue
        keep.append(j)
    order = keep + deflated
    d, z = np.array(d), np.array(z)
    return RankOneForm(Q[:, order], d[order], z[keep], sigma, scale)


def interval_discretization(
    A: np.ndarray,
    N: np.ndarray,
    B: np.ndarray,
    M: np.ndarray,
    capacities: np.ndarray,
    keys: np.ndarray,
    hold: str = "zoh",
    Qc: np.ndarray | None = None,
) -> Dynamics:
    """Exact discrete matrices of ``dx/dt = (A + sum m_f N_f) x + (B + sum m_f M_f) u`` per interval.

    Real matrices with a diagonal ``Qc`` (every RC model) are discretized by the compiled
    :func:`rczone.kernels.discretize.interval_matrices`: RC networks (:func:`symmetrizing_scale`
    succeeds) from one symmetric eigen-decomposition per interval, any other state space from
    block matrix exponentials. Complex matrices (complex-step differentiation) or a full ``Qc``
    take one :func:`zoh` / :func:`foh` and :func:`process_noise_covariance` per interval.

    Parameters
    ----------
    A, N, B, M : ndarray, shapes (n, n), (nf, n, n), (n, p), (nf, n, p)
    capacities : ndarray, shape (n,)
    keys : ndarray, shape (K, 1 + nf)
        ``(dt, m_1, ..., m_nf)`` of each interval (typically the distinct ones).
    hold : {"zoh", "foh"}
    Qc : ndarray, shape (n, n), optional
        Continuous process-noise intensity; ``Qd`` is zero without it.

    Returns
    -------
    Dynamics
        ``Phi`` (K, n, n); ``G0, G1`` (K, n, p), the input matrices applied to ``u[k]`` and
        ``u[k+1]`` (``G1`` is zero for ZOH); ``Qd`` (K, n, n).
    """
    qc = _diagonal_intensity(Qc, A.shape[0])
    if qc is not None and not any(np.iscomplexobj(a) for a in (A, N, B, M)):
        from rczone.kernels.arrays import Discretization, dynamics_model
        from rczone.kernels.discretize import matrices_kernel

        scale = symmetrizing_scale(A, N, capacities)
        kernel = matrices_kernel(A.shape[0], scale is not None)
        how = Discretization(
            np.require(keys, np.float64, "CW"),
            np.empty(0) if scale is None else scale,
            hold == "foh",
            Qc is not None,
        )
        return kernel(dynamics_model(A, N, B, M, qc), how)
    n, p, K = A.shape[0], B.shape[1], keys.shape[0]
    dtype = np.result_type(A, N, B, M, float if Qc is None else Qc)
    Phi = np.empty((K, n, n), dtype)
    G0 = np.empty((K, n, p), dtype)
    G1 = np.zeros((K, n, p), dtype)
    Qd = np.zeros((K, n, n), dtype)
    for k in range(K):
        Ak = A + np.tensordot(keys[k, 1:], N, axes=1)
        Bk = B + np.tensordot(keys[k, 1:], M, axes=1)
        dt = float(keys[k, 0])
        if hold == "zoh":
            Phi[k], G0[k] = zoh(Ak, Bk, dt)
        else:
            Phi[k], G0[k], G1[k] = foh(Ak, Bk, dt)
        if Qc is not None and np.any(Qc):
            Qd[k] = process_noise_covariance(Ak, Qc, dt)
    return Dynamics(Phi, G0, G1, Qd)


def _diagonal_intensity(Qc: np.ndarray | None, n: int) -> np.ndarray | None:
    """The diagonal of a real diagonal ``Qc`` (zeros without one); None when it is complex or full."""
    if Qc is None:
        return np.zeros(n)
    Qc = np.asarray(Qc)
    if np.iscomplexobj(Qc) or np.count_nonzero(Qc) != np.count_nonzero(np.diagonal(Qc)):
        return None
    return np.ascontiguousarray(np.diagonal(Qc), dtype=float)
