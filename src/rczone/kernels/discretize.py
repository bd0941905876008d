"""Compiled exact discretization of the stochastic bilinear model, per distinct interval.

The one implementation of the spectral formulas derived in :mod:`rczone.simulation.discretize`
(whose :func:`~rczone.simulation.discretize.interval_discretization` calls :func:`interval_matrices`;
the plain NumPy forms the tests compare these with are in ``tests/oracles.py``). For each distinct
interval ``(dt, m)`` with ``A = A0 + sum m_f N_f``, ``B = B0 + sum m_f M_f`` and diagonal
process-noise intensity ``Qc = diag(qc)``:

* ``Phi = e^{A dt}``, the ZOH or FOH input matrices ``G0, G1``, and
  ``Qd = int_0^dt e^{As} Qc e^{A's} ds``;
* for RC networks (``diag(c) A`` symmetric, checked by the caller) these come from the
  symmetric eigen-decomposition: in closed form for two states (one Jacobi rotation,
  :func:`rc2_discretize`, also used per sample by the fused 2-state kernel), by LAPACK's
  symmetric solver otherwise (:func:`spectral_modal`, in modal coordinates, where ``Phi`` is
  diagonal, for the modal filter of :mod:`rczone.kernels.kalman`; :func:`spectral_discretize`
  in the original ones);
* their derivatives along directions ``(dA, dB, dqc)`` for RC networks from the same
  decomposition (:func:`spectral_derivatives`): the Daleckii-Krein theorem with divided
  differences of ``exp`` (:func:`_dd2`, :func:`_dd3`, :func:`_dd4`), and for ``Qd`` a
  three-index closed form, all directions of an interval in a few stacked products; for two
  states the same formulas written out in scalars (:func:`spectral_derivatives2`);
* otherwise from matrix exponentials (:func:`expm_discretize`): the hold matrices from one
  block exponential, ``Qd`` by Van Loan's block exponential on a step short enough that
  ``e^{-A h}`` is harmless, then exact doubling. The derivatives are the Fréchet derivatives
  of the same exponentials (:func:`rczone.kernels.expm.expm_frechet`) carried through the
  doubling. Both routes are exact to rounding; the spectral one is several times cheaper.

References
----------
.. [1] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23(3), 1978.
.. [2] G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, Algorithm 8.5.1.
.. [3] N. J. Higham, *Functions of Matrices*, SIAM, 2008, sections 1.2, 3.1 and 10.7.4.
.. [4] A. McCurdy, K. C. Ng, B. N. Parlett, "Accurate computation of divided differences of
   the exponential function", Math. Comp. 43(168), 1984.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rczone.kernels.arrays import (
    Assembled,
    AssembledDerivatives,
    Discretization,
    Dynamics,
    DynamicsDerivatives,
    Eigen2,
    Interval,
    IntervalDirections,
    ModalBasis,
    ModalDynamics,
    Rc2Matrices,
    Rc2Model,
)
from rczone.kernels.expm import expm_frechet, matmul, norm1

#: Below this ``|x|`` the series of ``(e^x - 1 - x)/x^2`` is used.
SERIES_LIMIT = 0.2
#: Taylor coefficients ``1/(k+2)!``, k = 0..12, of ``(e^x - 1 - x)/x^2`` (truncation < 1e-19 below the limit).
PHI2_SERIES = np.array([1.0 / math.factorial(k + 2) for k in range(13)])
#: Van Loan's block exponential is applied on steps with ``||A||_1 h`` at most this.
VAN_LOAN_NORM = 0.5


@njit(cache=True, error_model="numpy")
def phi1(x: float, em1: float) -> float:
    """``(e^x - 1)/x`` from ``em1 = expm1(x)``."""
    return 1.0 if x == 0.0 else em1 / x


@njit(cache=True, error_model="numpy")
def phi2(x: float, em1: float) -> float:
    """``(e^x - 1 - x)/x^2`` from ``em1 = expm1(x)``, by its series for small ``|x|``."""
    if abs(x) < SERIES_LIMIT:
        c = PHI2_SERIES
        w = c[c.shape[0] - 1]
        for k in range(c.shape[0] - 2, -1, -1):
            w = w * x + c[k]
        return w
    return (em1 - x) / (x * x)


@njit(cache=True, error_model="numpy", inline="always")
def jacobi_tangent(a: float, b: float, d: float) -> float:
    """``t = tan(theta)`` of the Jacobi rotation ``[[c, s], [-s, c]]`` that diagonalizes ``[[a, b], [b, d]]`` [2]_.

    ``c = 1/sqrt(1 + t^2)``, ``s = t c``; the eigenvalues are ``a - t b`` and ``d + t b``, without
    cancellation when they nearly coincide. ``0`` when ``b = 0``.
    """
    if b == 0.0:
        return 0.0
    tau = (d - a) / (2.0 * b)
    at = abs(tau)
    # sqrt(1 + tau^2) without overflow for |tau| > 1e150
    root = at * math.sqrt(1.0 + (1.0 / at) ** 2) if at > 1e150 else math.sqrt(1.0 + at * at)
    return math.copysign(1.0, tau) / (at + root)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def rc2_discretize(model: Rc2Model, h: float, q0: float, q1: float, foh: bool) -> Rc2Matrices:
    """Exact discrete matrices of a 2-state RC model over ``h`` s, as 15 named numbers.

    ``A = [[a, a01], [a10, d]]`` with ``diag(s)^2 A`` symmetric (``s = sqrt(capacities)``), so
    ``S = diag(s) A diag(s)^{-1}`` is symmetric; its eigen-decomposition is one Jacobi
    rotation in closed form [2]_, without cancellation for nearly equal eigenvalues. Two
    ``exp`` and two ``expm1`` give every matrix (``e^x`` by ``exp``, not ``expm1(x) + 1``, whose
    rounding is relative ``1e-16 / e^x`` for a fast mode); ``e^{(l_0 + l_1) h} - 1`` is formed
    exactly from the ``expm1``.
    Scalars in, scalars out: the fused kernel calls this once per interval, and arrays passed
    to a numba function cost reference counting on every call.

    Parameters
    ----------
    model : Rc2Model
        ``A`` and the ``sqrt`` of the capacities with their reciprocals (constant over a data set:
        no division here), as named scalars (passed by value: no reference counts).
    h : float
        Interval, s.
    q0, q1 : float
        Process-noise intensities of the two states, K^2/s.
    foh : bool
        First-order hold (else zero-order).

    Returns
    -------
    Rc2Matrices
        ``Phi``, ``H0`` and ``H1`` with ``G0 = H0 B`` and ``G1 = H1 B`` (``H1 = 0`` for ZOH), and
        the upper triangle of ``Qd``.
    """
    a, a01, a10, d = model.a, model.a01, model.a10, model.d
    s0, s1, is0, is1 = model.s0, model.s1, model.is0, model.is1
    # symmetric S and its rotation [[cs, sn], [-sn, cs]]
    b = 0.5 * (a01 * s0 * is1 + a10 * s1 * is0)
    tn = jacobi_tangent(a, b, d)
    cs = 1.0 / math.sqrt(1.0 + tn * tn)
    sn = tn * cs
    # T = diag(s)^-1 V, U = T^-1 = V' diag(s)
    T00, T01, T10, T11 = cs * is0, sn * is0, -sn * is1, cs * is1
    U00, U01, U10, U11 = cs * s0, -sn * s1, sn * s0, cs * s1
    x0 = (a - tn * b) * h
    x1 = (d + tn * b) * h
    em0 = math.expm1(x0)
    em1 = math.expm1(x1)
    # not em + 1: that loses a fast mode's e^x (relative accuracy 1e-16 / e^x, 1e-7 at e^x = 1e-9)
    e0 = math.exp(x0)
    e1 = math.exp(x1)
    w10 = phi1(x0, em0)
    w11 = phi1(x1, em1)
    if foh:
        w20 = phi2(x0, em0)
        w21 = phi2(x1, em1)
        ga0, ga1 = (w10 - w20) * h, (w11 - w21) * h
        gb0, gb1 = w20 * h, w21 * h
    else:
        ga0, ga1 = w10 * h, w11 * h
        gb0, gb1 = 0.0, 0.0
    # W = U diag(q) U' weighted by (e^{(l_i + l_j) h} - 1)/(l_i + l_j); Qd = T W T'
    W00 = (U00 * U00 * q0 + U01 * U01 * q1) * (w10 * (0.5 * em0 + 1.0)) * h
    W01 = (U00 * U10 * q0 + U01 * U11 * q1) * phi1(x0 + x1, em0 + em1 + em0 * em1) * h
    W11 = (U10 * U10 * q0 + U11 * U11 * q1) * (w11 * (0.5 * em1 + 1.0)) * h
    v00 = T00 * W00 + T01 * W01
    v01 = T00 * W01 + T01 * W11
    v10 = T10 * W00 + T11 * W01
    v11 = T10 * W01 + T11 * W11
    return Rc2Matrices(
        T00 * e0 * U00 + T01 * e1 * U10,
        T00 * e0 * U01 + T01 * e1 * U11,
        T10 * e0 * U00 + T11 * e1 * U10,
        T10 * e0 * U01 + T11 * e1 * U11,
        T00 * ga0 * U00 + T01 * ga1 * U10,
        T00 * ga0 * U01 + T01 * ga1 * U11,
        T10 * ga0 * U00 + T11 * ga1 * U10,
        T10 * ga0 * U01 + T11 * ga1 * U11,
        T00 * gb0 * U00 + T01 * gb1 * U10,
        T00 * gb0 * U01 + T01 * gb1 * U11,
        T10 * gb0 * U00 + T11 * gb1 * U10,
        T10 * gb0 * U01 + T11 * gb1 * U11,
        v00 * T00 + v01 * T01,
        v00 * T10 + v01 * T11,
        v10 * T10 + v11 * T11,
    )


@njit(cache=True, error_model="numpy")
def symmetric_eigen(A: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``lam, V`` of ``S = diag(scale) A diag(scale)^-1`` (symmetrized, which removes only rounding) by LAPACK."""
    n = A.shape[0]
    S = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            S[i, j] = 0.5 * (scale[i] * A[i, j] / scale[j] + scale[j] * A[j, i] / scale[i])
    return np.linalg.eigh(S)


@njit(cache=True, error_model="numpy")
def spectral_modal(
    A: np.ndarray, B: np.ndarray, scale: np.ndarray, qc: np.ndarray, h: float, foh: bool
) -> ModalDynamics:
    """The exact discretization of an RC model in its modal coordinates ``xi = V' diag(scale) x``.

    ``S = diag(scale) A diag(scale)^-1`` (symmetrized, which removes only rounding) is
    ``V diag(lam) V'`` (LAPACK's symmetric solver). With ``T = diag(scale)^-1 V`` and
    ``T^-1 = V' diag(scale)`` the identities of :mod:`rczone.simulation.discretize` read, in
    ``xi``: ``Phi = diag(e^{lam h})``, ``G0 = diag(phi1 - phi2) T^-1 B``, ``G1 = diag(phi2) T^-1 B``
    (``phi2 = 0`` for ZOH) and ``Qd = W o F`` with ``W = T^-1 Qc T^-T`` and
    ``F_ij = (e^{(lam_i + lam_j) h} - 1)/(lam_i + lam_j)``, all evaluated with ``expm1``.

    Returns
    -------
    ModalDynamics
        Of this one interval: ``V`` (n, n); ``e`` (n,), ``e^{lam h}``; ``H0, H1`` (n, p), the hold
        matrices in modal coordinates; ``Qm`` (n, n), ``Qd`` in modal coordinates.
    """
    n = A.shape[0]
    p = B.shape[1]
    lam, V = symmetric_eigen(A, scale)
    Ti = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            Ti[j, i] = V[i, j] * scale[i]
    e = np.empty(n)
    w1 = np.empty(n)
    w2 = np.zeros(n)
    for i in range(n):
        x = lam[i] * h
        em = math.expm1(x)
        e[i] = math.exp(x)  # not em + 1, which loses a fast mode's e^x (below ~1e-8 relative accuracy)
        w1[i] = phi1(x, em) * h
        if foh:
            w2[i] = phi2(x, em) * h
    TiB = np.empty((n, p))
    matmul(Ti, B, TiB)
    H0 = np.empty((n, p))
    H1 = np.empty((n, p))
    for i in range(n):
        for j in range(p):
            H0[i, j] = (w1[i] - w2[i]) * TiB[i, j]
            H1[i, j] = w2[i] * TiB[i, j]
    Qm = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += Ti[i, k] * qc[k] * Ti[j, k]
            x = (lam[i] + lam[j]) * h
            acc *= phi1(x, math.expm1(x)) * h
            Qm[i, j] = acc
            Qm[j, i] = acc
    return ModalDynamics(V, e, H0, H1, Qm)


@njit(cache=True, error_model="numpy")
def spectral_discretize(step: Interval, how: Discretization, out: Dynamics) -> None:
    """Exact ``Phi, G0, G1, Qd`` of an RC model: :func:`spectral_modal` brought back by ``T = diag(scale)^-1 V``.

    Parameters
    ----------
    step : Interval
        The model over one interval.
    how : Discretization
        ``scale`` (``sqrt(capacities)``) and the hold are read.
    out : Dynamics
        Receives the matrices of this interval (2-d arrays; ``G1`` untouched for ZOH).
    """
    A, B, qc, h = step
    scale, foh = how.scale, how.foh
    Phi, G0, G1, Qd = out
    n = A.shape[0]
    p = B.shape[1]
    modal = spectral_modal(A, B, scale, qc, h, foh)
    V, e, H0, H1, Qm = modal.V, modal.e, modal.H0, modal.H1, modal.Qm
    T = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            T[i, j] = V[i, j] / scale[i]
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += T[i, k] * e[k] * V[j, k]
            Phi[i, j] = acc * scale[j]
        for j in range(p):
            a0 = 0.0
            a1 = 0.0
            for k in range(n):
                a0 += T[i, k] * H0[k, j]
                a1 += T[i, k] * H1[k, j]
            G0[i, j] = a0
            if foh:
                G1[i, j] = a1
    congruence(T, Qm, Qd)


@njit(cache=True, error_model="numpy")
def modal_matrices(mod: Assembled, how: Discretization) -> tuple[Dynamics, ModalBasis]:
    """The discrete matrices of each distinct interval in its modal coordinates, and those coordinates.

    :func:`spectral_modal` of each interval, as the :class:`Dynamics` the filter runs on
    (``Phi = diag(e)``, ``G0 = H0``, ``G1 = H1``, ``Qd = Qm``) with the :class:`ModalBasis` that
    maps them back (:func:`rczone.kernels.kalman.kalman_filter` with ``basis``).

    Parameters
    ----------
    mod : Assembled
        The bilinear model (``A0, N, B0, M``) and its process noise ``qc``.
    how : Discretization
        The distinct intervals, ``scale`` (``sqrt(capacities)``, required), the hold and ``noise``.

    Returns
    -------
    Dynamics
    ModalBasis
    """
    keys, scale, foh = how.keys, how.scale, how.foh
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    K = keys.shape[0]
    V = np.empty((K, n, n))
    Phi = np.zeros((K, n, n))
    G0 = np.empty((K, n, p))
    G1 = np.empty((K, n, p))
    Qd = np.empty((K, n, n))
    qc = mod.qc if how.noise else np.zeros(n)
    for k in range(K):
        A, B = _key_matrices(mod, keys[k])
        step = spectral_modal(A, B, scale, qc, keys[k, 0], foh)
        V[k], G0[k], G1[k], Qd[k] = step.V, step.H0, step.H1, step.Qm
        for i in range(n):
            Phi[k, i, i] = step.e[i]
    return Dynamics(Phi, G0, G1, Qd), ModalBasis(V, scale)


@njit(cache=True, error_model="numpy")
def expm_discretize(
    step: Interval, dstep: IntervalDirections, how: Discretization, out: Dynamics, dout: DynamicsDerivatives
) -> None:
    """``Phi, G0, G1, Qd`` and their derivatives along ``q`` directions, by matrix exponentials.

    Parameters
    ----------
    step : Interval
        ``A``, ``B`` (shapes (n, n), (n, p)), ``Qc = diag(qc)`` and the interval ``h``, s.
    dstep : IntervalDirections
        Directions (derivatives of ``A``, ``B``, ``qc`` with respect to one parameter each),
        shapes (q, n, n), (q, n, p), (q, n).
    how : Discretization
        The hold (``foh``) and ``noise`` are read.
    out : Dynamics
        Receives ``Phi, G0, G1, Qd`` of this interval (2-d arrays; ``G1`` untouched for ZOH).
    dout : DynamicsDerivatives
        Receives their derivatives, shapes (q, n, n), (q, n, p), (q, n, p), (q, n, n); ``dG1``
        untouched for ZOH. Without ``noise``, ``Qd`` and ``dQd`` are zero.
    """
    A, B, qc, h = step
    dA, dB, dqc = dstep
    foh, noise = how.foh, how.noise
    Phi, G0, G1, Qd = out
    dPhi, dG0, dG1, dQd = dout
    n = A.shape[0]
    p = B.shape[1]
    q = dA.shape[0]
    # hold matrices: exp of [[A h, B h, 0], [0, 0, I], [0, 0, 0]] (the last block row/column for FOH)
    nb = n + (2 * p if foh else p)
    Z = np.zeros((nb, nb))
    for i in range(n):
        for j in range(n):
            Z[i, j] = A[i, j] * h
        for j in range(p):
            Z[i, n + j] = B[i, j] * h
    if foh:
        for j in range(p):
            Z[n + j, n + p + j] = 1.0
    # directions that move the hold matrices
    dyn = np.zeros(q, dtype=np.int64)
    n_dyn = 0
    for k in range(q):
        moved = False
        for i in range(n):
            for j in range(n):
                moved = moved or dA[k, i, j] != 0.0
            for j in range(p):
                moved = moved or dB[k, i, j] != 0.0
        if moved:
            dyn[n_dyn] = k
            n_dyn += 1
    dZ = np.zeros((n_dyn, nb, nb))
    for kk in range(n_dyn):
        k = dyn[kk]
        for i in range(n):
            for j in range(n):
                dZ[kk, i, j] = dA[k, i, j] * h
            for j in range(p):
                dZ[kk, i, n + j] = dB[k, i, j] * h
    E, L = expm_frechet(Z, dZ)
    for i in range(n):
        for j in range(n):
            Phi[i, j] = E[i, j]
        for j in range(p):
            if foh:
                G1[i, j] = E[i, n + p + j]
                G0[i, j] = E[i, n + j] - E[i, n + p + j]
            else:
                G0[i, j] = E[i, n + j]
    for k in range(q):
        for i in range(n):
            for j in range(n):
                dPhi[k, i, j] = 0.0
            for j in range(p):
                dG0[k, i, j] = 0.0
                if foh:
                    dG1[k, i, j] = 0.0
    for kk in range(n_dyn):
        k = dyn[kk]
        for i in range(n):
            for j in range(n):
                dPhi[k, i, j] = L[kk, i, j]
            for j in range(p):
                if foh:
                    dG1[k, i, j] = L[kk, i, n + p + j]
                    dG0[k, i, j] = L[kk, i, n + j] - L[kk, i, n + p + j]
                else:
                    dG0[k, i, j] = L[kk, i, n + j]
    if noise:
        _van_loan_doubling(A, qc, h, dA, dqc, Qd, dQd)
    else:
        for i in range(n):
            for j in range(n):
                Qd[i, j] = 0.0
                for k in range(q):
                    dQd[k, i, j] = 0.0


@njit(cache=True, error_model="numpy")
def _van_loan_doubling(
    A: np.ndarray, qc: np.ndarray, dt: float, dA: np.ndarray, dqc: np.ndarray, Qd: np.ndarray, dQd: np.ndarray
) -> None:
    """``Qd`` over ``dt`` and its derivatives: Van Loan on ``h = dt / 2^s``, then exact doubling.

    Van Loan's block exponential ``exp([[-A, Qc], [0, A']] h)`` holds ``e^{-A h}``; for a stiff
    model over a long interval it would overflow into cancellation, so ``h`` is halved until
    ``||A||_1 h <= 1/2`` and ``Qd(2h) = Qd(h) + Phi(h) Qd(h) Phi(h)'`` (every term positive
    semidefinite), ``Phi(2h) = Phi(h)^2`` recover ``dt``; the derivatives follow the same
    recursion by the product rule.
    """
    n = A.shape[0]
    q = dA.shape[0]
    norm = norm1(A) * dt
    s = math.ceil(math.log2(norm / VAN_LOAN_NORM)) if norm > VAN_LOAN_NORM else 0
    h = dt * 0.5**s
    # directions that move Qd: A or qc
    act = np.zeros(q, dtype=np.int64)
    n_act = 0
    for k in range(q):
        moved = False
        for i in range(n):
            moved = moved or dqc[k, i] != 0.0
            for j in range(n):
                moved = moved or dA[k, i, j] != 0.0
        if moved:
            act[n_act] = k
            n_act += 1
    H = np.zeros((2 * n, 2 * n))
    for i in range(n):
        H[i, n + i] = qc[i] * h
        for j in range(n):
            H[i, j] = -A[i, j] * h
            H[n + i, n + j] = A[j, i] * h
    dH = np.zeros((n_act, 2 * n, 2 * n))
    for kk in range(n_act):
        k = act[kk]
        for i in range(n):
            dH[kk, i, n + i] = dqc[k, i] * h
            for j in range(n):
                dH[kk, i, j] = -dA[k, i, j] * h
                dH[kk, n + i, n + j] = dA[k, j, i] * h
    E, L = expm_frechet(H, dH)
    # Phi(h) = E22', Qd(h) = E22' E12
    F = np.empty((n, n))
    Q = np.empty((n, n))
    dF = np.zeros((n_act, n, n))
    dQ = np.zeros((n_act, n, n))
    for i in range(n):
        for j in range(n):
            F[i, j] = E[n + j, n + i]
            acc = 0.0
            for k in range(n):
                acc += E[n + k, n + i] * E[k, n + j]
            Q[i, j] = acc
    _symmetrize(Q)
    for kk in range(n_act):
        for i in range(n):
            for j in range(n):
                dF[kk, i, j] = L[kk, n + j, n + i]
                acc = 0.0
                for k in range(n):
                    acc += L[kk, n + k, n + i] * E[k, n + j] + E[n + k, n + i] * L[kk, k, n + j]
                dQ[kk, i, j] = acc
        _symmetrize(dQ[kk])
    T = np.empty((n, n))
    T2 = np.empty((n, n))
    for _ in range(s):
        # derivatives first (they use Q and Phi of the current step)
        for kk in range(n_act):
            # dQ + dF Q F' + F dQ F' + F Q dF'
            matmul(dF[kk], Q, T)  # dF Q
            for i in range(n):
                for j in range(n):
                    acc = 0.0
                    for k in range(n):
                        acc += T[i, k] * F[j, k]
                    T2[i, j] = acc  # dF Q F'
            matmul(F, dQ[kk], T)  # F dQ
            for i in range(n):
                for j in range(i, n):
                    acc = 0.0
                    for k in range(n):
                        acc += T[i, k] * F[j, k]
                    v = dQ[kk, i, j] + acc + T2[i, j] + T2[j, i]
                    dQ[kk, i, j] = v
                    dQ[kk, j, i] = v
            matmul(dF[kk], F, T)
            matmul(F, dF[kk], T2)
            for i in range(n):
                for j in range(n):
                    dF[kk, i, j] = T[i, j] + T2[i, j]
        matmul(F, Q, T)
        for i in range(n):
            for j in range(i, n):
                acc = 0.0
                for k in range(n):
                    acc += T[i, k] * F[j, k]
                v = Q[i, j] + acc
                Q[i, j] = v
                Q[j, i] = v
        matmul(F, F, T)
        for i in range(n):
            for j in range(n):
                F[i, j] = T[i, j]
    for i in range(n):
        for j in range(n):
            Qd[i, j] = Q[i, j]
    for k in range(q):
        for i in range(n):
            for j in range(n):
                dQd[k, i, j] = 0.0
    for kk in range(n_act):
        k = act[kk]
        for i in range(n):
            for j in range(n):
                dQd[k, i, j] = dQ[kk, i, j]


#: Taylor terms summed for a divided difference of ``exp`` whose nodes lie within :data:`SERIES_LIMIT`.
DD_TERMS = 14


@njit(cache=True, error_model="numpy")
def _dd_series(y0: float, y1: float, y2: float, k: int) -> float:
    """``exp[y0, ..., y_{k-1}, 0]`` (``k`` = 2 or 3; pass ``y2 = 0`` for ``k = 2``) by its Taylor series.

    ``exp[x_0..x_k] = sum_m h_m(x)/(m + k)!`` with ``h_m`` the complete homogeneous symmetric
    polynomials (one node at 0 contributes nothing to them), built by ``h_m(y_0..y_j) =
    h_m(y_0..y_{j-1}) + y_j h_{m-1}(y_0..y_j)``. With ``|y| < 0.2`` the truncation is below ``1e-20``.
    """
    p0 = 1.0
    p1 = 1.0
    p2 = 1.0
    fact = 2.0 if k == 2 else 6.0
    acc = 1.0 / fact
    for m in range(1, DD_TERMS + 1):
        p0 = p0 * y0
        p1 = p0 + y1 * p1
        p2 = p1 + y2 * p2
        fact *= m + k
        acc += p2 / fact
    return acc


@njit(cache=True, error_model="numpy")
def _dd2(x0: float, x1: float, e0: float, e1: float) -> float:
    """``exp[x0, x1] = (e^{x1} - e^{x0})/(x1 - x0)`` (``e^{x0}`` when equal) from ``e0 = e^{x0}``, ``e1 = e^{x1}``.

    Apart (``|x1 - x0| >= 0.2``) the difference loses at most a factor ``1/(1 - e^{-0.2}) < 6``;
    closer, ``e^{max} phi1(-|d|)`` has no subtraction at all.
    """
    d = x1 - x0
    if abs(d) >= SERIES_LIMIT:
        return (e1 - e0) / d
    if d >= 0.0:
        return e1 * phi1(-d, math.expm1(-d))
    return e0 * phi1(d, math.expm1(d))


@njit(cache=True, error_model="numpy")
def _dd3(x0: float, x1: float, x2: float, e0: float, e1: float, e2: float) -> float:
    """``exp[x0, x1, x2]`` for ascending nodes, with their exponentials.

    Nodes within :data:`SERIES_LIMIT`: the series around the largest; otherwise the recurrence
    dropping the two extreme nodes, whose subtraction loses at most a factor ``~2/0.2`` because
    the divided differences of ``exp`` increase in every node [1]_.

    References
    ----------
    .. [1] A. McCurdy, K. C. Ng, B. N. Parlett, "Accurate computation of divided differences of
       the exponential function", Math. Comp. 43(168), 1984.
    """
    if x2 - x0 < SERIES_LIMIT:
        return e2 * _dd_series(x0 - x2, x1 - x2, 0.0, 2)
    return (_dd2(x1, x2, e1, e2) - _dd2(x0, x1, e0, e1)) / (x2 - x0)


@njit(cache=True, error_model="numpy")
def _dd3_sorted(a: float, b: float, c: float, ea: float, eb: float, ec: float) -> float:
    """``exp[a, b, c]`` for nodes in any order (divided differences are symmetric)."""
    if a > b:
        a, b, ea, eb = b, a, eb, ea
    if b > c:
        b, c, eb, ec = c, b, ec, eb
        if a > b:
            a, b, ea, eb = b, a, eb, ea
    return _dd3(a, b, c, ea, eb, ec)


@njit(cache=True, error_model="numpy")
def _dd4(x0: float, x1: float, x2: float, x3: float, e0: float, e1: float, e2: float, e3: float) -> float:
    """``exp[x0, x1, x2, x3]`` for ascending nodes, as :func:`_dd3` one order higher."""
    if x3 - x0 < SERIES_LIMIT:
        return e3 * _dd_series(x0 - x3, x1 - x3, x2 - x3, 3)
    return (_dd3(x1, x2, x3, e1, e2, e3) - _dd3(x0, x1, x2, e0, e1, e2)) / (x3 - x0)


@njit(cache=True, error_model="numpy")
def _dd4_00(a: float, b: float, ea: float, eb: float) -> float:
    """``exp[0, 0, a, b]``: the divided difference of ``phi2`` at ``a, b``."""
    if a > b:
        a, b, ea, eb = b, a, eb, ea
    if b <= 0.0:
        return _dd4(a, b, 0.0, 0.0, ea, eb, 1.0, 1.0)
    if a <= 0.0:
        return _dd4(a, 0.0, 0.0, b, ea, 1.0, 1.0, eb)
    return _dd4(0.0, 0.0, a, b, 1.0, 1.0, ea, eb)


@njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})
def spectral_derivatives(
    step: Interval, dstep: IntervalDirections, how: Discretization, out: Dynamics, dout: DynamicsDerivatives
) -> None:
    """As :func:`expm_discretize` for an RC model, from one symmetric eigen-decomposition.

    ``S = D A D^-1 = V diag(lam) V'`` with ``D = diag(scale)``, ``T = D^-1 V``, ``T^-1 = V' D``.
    A direction ``dA`` (any matrix: a capacity's is not symmetrized by ``D``, which is held at the
    current point, since ``f(A) = D^-1 f(S) D`` for every ``A``) becomes ``E = T^-1 dA T`` and
    the Daleckii-Krein theorem [1]_ gives ``d f(A)[dA] = T (f[lam_i, lam_j] o E) T^-1`` with the
    divided differences ``f[l_i, l_j]`` (``f'(l_i)`` when equal). With ``x = lam h``:

    * ``Phi = e^{Ah}``: ``f[l_i, l_j] = h exp[x_i, x_j]``;
    * ``h phi1(Ah) B`` and ``h phi2(Ah) B`` (``G0`` is their difference, ``G1`` the second, for
      FOH; ``G0`` the first for ZOH): ``h^2 exp[0, x_i, x_j]``, ``h^2 exp[0, 0, x_i, x_j]``
      (``phi1(x) = exp[0, x]``, ``phi2(x) = exp[0, 0, x]``), plus ``f(A) dB``;
    * ``Qd = T (W o Om) T'`` with ``W = T^-1 Qc T^-T``, ``Om_il = h exp[0, x_i + x_l]``: the
      derivative of ``int_0^h e^{As} Qc e^{A's} ds`` is ``T (X + X' + (T^-1 dQc T^-T) o Om) T'``
      with ``X_il = sum_j E_ij W_jl Y_ijl`` and ``Y_ijl = int_0^h (e^{l_i s} - e^{l_j s})/(l_i - l_j)
      e^{l_l s} ds = h^2 exp[0, x_i + x_l, x_j + x_l]`` (three indices).

    Divided differences of ``exp`` come from :func:`_dd2`, :func:`_dd3`, :func:`_dd4`, accurate
    to a few ulps for equal, close and distant nodes alike [2]_, so repeated eigenvalues need
    no special case.

    Parameters
    ----------
    step, dstep, out, dout
        As :func:`expm_discretize`.
    how : Discretization
        ``scale``, ``sqrt(capacities)``: ``diag(scale) A diag(scale)^-1`` is symmetric (checked by
        the caller); the hold and ``noise``.

    References
    ----------
    .. [1] N. J. Higham, *Functions of Matrices*, SIAM, 2008, Theorem 3.11 and section 10.6.
    .. [2] A. McCurdy, K. C. Ng, B. N. Parlett, "Accurate computation of divided differences of
       the exponential function", Math. Comp. 43(168), 1984.
    """
    A, B, qc, h = step
    dA, dB, dqc = dstep
    scale, foh, noise = how.scale, how.foh, how.noise
    Phi, G0, G1, Qd = out
    dPhi, dG0, dG1, dQd = dout
    n = A.shape[0]
    p = B.shape[1]
    q = dA.shape[0]
    lam, V = symmetric_eigen(A, scale)
    T = np.empty((n, n))
    Ti = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            T[i, j] = V[i, j] / scale[i]
            Ti[j, i] = V[i, j] * scale[i]
    x = np.empty(n)
    e = np.empty(n)
    wg0 = np.empty(n)  # G0 = T diag(wg0) T^-1 B: h (phi1 - phi2), h phi1 for ZOH
    wg1 = np.zeros(n)
    for i in range(n):
        x[i] = lam[i] * h
        em = math.expm1(x[i])
        e[i] = math.exp(x[i])  # not em + 1, which loses e^x below 1e-17 (relative accuracy of dPhi)
        w1 = phi1(x[i], em) * h
        if foh:
            wg1[i] = phi2(x[i], em) * h
        wg0[i] = w1 - wg1[i]
    # divided-difference kernels of Phi and of the hold matrices
    F0 = np.empty((n, n))
    Fg0 = np.empty((n, n))
    Fg1 = np.zeros((n, n))
    h2 = h * h
    for i in range(n):
        for j in range(i, n):
            F0[i, j] = h * _dd2(x[i], x[j], e[i], e[j])
            f1 = h2 * _dd3_sorted(0.0, x[i], x[j], 1.0, e[i], e[j])
            if foh:
                Fg1[i, j] = h2 * _dd4_00(x[i], x[j], e[i], e[j])
                Fg1[j, i] = Fg1[i, j]
            Fg0[i, j] = f1 - Fg1[i, j]
            F0[j, i] = F0[i, j]
            Fg0[j, i] = Fg0[i, j]
    TiB = np.empty((n, p))
    matmul(Ti, B, TiB)
    M0 = np.empty((n, p))
    M1 = np.empty((n, p))
    for i in range(n):
        for j in range(p):
            M0[i, j] = wg0[i] * TiB[i, j]
            M1[i, j] = wg1[i] * TiB[i, j]
    matmul(T, M0, G0)
    if foh:
        matmul(T, M1, G1)
    TE = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            TE[i, j] = T[i, j] * e[j]
    matmul(TE, Ti, Phi)
    # noise: W, Om, Y and Qd
    W = np.zeros((n, n))
    Om = np.zeros((n, n))
    Y = np.zeros((n, n, n))  # W_jm Y_ijm at [i, j, m] (the docstring's l)
    if noise:
        ee = np.empty((n, n))
        for i in range(n):
            for j in range(i, n):
                acc = 0.0
                for k in range(n):
                    acc += Ti[i, k] * qc[k] * Ti[j, k]
                W[i, j] = acc
                W[j, i] = acc
                xs = x[i] + x[j]
                Om[i, j] = phi1(xs, math.expm1(xs)) * h
                Om[j, i] = Om[i, j]
                ee[i, j] = e[i] * e[j]
                ee[j, i] = ee[i, j]
        for m in range(n):
            for i in range(n):
                for j in range(i, n):
                    lo = min(x[i], x[j]) + x[m]
                    hi = max(x[i], x[j]) + x[m]
                    if hi <= 0.0 and lo <= -SERIES_LIMIT:
                        # _dd3's recurrence from tables: exp[hi, 0] = Om/h, exp[lo, hi] = e_m F0_ij/h
                        v = h * (Om[i if x[i] >= x[j] else j, m] - e[m] * F0[i, j]) / (-lo)
                    else:
                        v = h2 * _dd3_sorted(0.0, x[i] + x[m], x[j] + x[m], 1.0, ee[i, m], ee[j, m])
                    Y[i, j, m] = v * W[j, m]
                    Y[j, i, m] = v * W[i, m]
        for i in range(n):
            for j in range(n):
                TE[i, j] = W[i, j] * Om[i, j]
        congruence(T, TE, Qd)
    else:
        for i in range(n):
            for j in range(n):
                Qd[i, j] = 0.0
    # The directions that move A (E_d = T^-1 dA_d T, dPhi), the hold matrices and Qd, each kind
    # at once: n-by-n blocks side by side ("h", shape (n, k n)) or on top of each other ("v",
    # shape (k n, n)), so that each product is one BLAS call; the others have zero derivatives.
    movA = np.zeros(q, dtype=np.bool_)
    movG = np.zeros(q, dtype=np.bool_)
    movQ = np.zeros(q, dtype=np.bool_)
    for d in range(q):
        for i in range(n):
            for j in range(n):
                movA[d] = movA[d] or dA[d, i, j] != 0.0
            for j in range(p):
                movG[d] = movG[d] or dB[d, i, j] != 0.0
            movQ[d] = movQ[d] or (noise and dqc[d, i] != 0.0)
        movG[d] = movG[d] or movA[d]
        movQ[d] = movQ[d] or (noise and movA[d])
    sA, qa = _slots(movA)
    sG, qg = _slots(movG)
    sQ, qq = _slots(movQ)
    Eh = _sandwich(Ti, dA, T, sA, qa)
    # dPhi_d = T (F0 o E_d) T^-1
    Ph = np.empty((n, qa * n))
    for i in range(n):
        for a in range(qa):
            for j in range(n):
                Ph[i, a * n + j] = F0[i, j] * Eh[i, a * n + j]
    # (a BLAS product with an empty side is not defined: each kind only when it has directions)
    Pv = np.dot(_h2v(np.dot(T, Ph), qa), Ti) if qa else np.empty((0, n))
    _unstack(Pv, sA, dPhi)
    # dG_d = T ((Fg o E_d) T^-1 B + diag(wg) T^-1 dB_d)
    TdB = _sandwich(Ti, dB, np.eye(p), sG, qg)
    for hold in range(2 if foh else 1):
        Fg = Fg0 if hold == 0 else Fg1
        wg = wg0 if hold == 0 else wg1
        Gv = np.zeros((qg * n, n))
        for d in range(q):
            if sA[d] >= 0:
                a = sA[d]
                g = sG[d]
                for i in range(n):
                    for j in range(n):
                        Gv[g * n + i, j] = Fg[i, j] * Eh[i, a * n + j]
        Mv = np.dot(Gv, TiB) if qg and p else np.zeros((qg * n, p))
        Mh = np.empty((n, qg * p))
        for g in range(qg):
            for i in range(n):
                for j in range(p):
                    Mh[i, g * p + j] = Mv[g * n + i, j] + wg[i] * TdB[i, g * p + j]
        Gv = _h2v(np.dot(T, Mh), qg) if qg and p else np.zeros((qg * n, p))
        _unstack(Gv, sG, dG0 if hold == 0 else dG1)
    # dQd_d = T (X_d + X_d' + (T^-1 diag(dqc_d) T^-T) o Om) T' with X_d[i, l] = sum_j E_d[i, j] W_jl Y_ijl
    Zh = np.zeros((n, qq * n))
    for d in range(q):
        if sQ[d] < 0:
            continue
        c0 = sQ[d] * n
        if sA[d] >= 0:
            a0 = sA[d] * n
            for i in range(n):
                for j in range(n):
                    c = Eh[i, a0 + j]
                    if c != 0.0:
                        for m in range(n):
                            Zh[i, c0 + m] += c * Y[i, j, m]
            for i in range(n):
                for j in range(i + 1, n):
                    v = Zh[i, c0 + j] + Zh[j, c0 + i]
                    Zh[i, c0 + j] = v
                    Zh[j, c0 + i] = v
                Zh[i, c0 + i] *= 2.0
        if movQ[d]:
            for k in range(n):
                c = dqc[d, k]
                if c != 0.0:
                    for i in range(n):
                        for j in range(n):
                            Zh[i, c0 + j] += c * Ti[i, k] * Ti[j, k] * Om[i, j]
    Qv = np.dot(_h2v(np.dot(T, Zh), qq), np.ascontiguousarray(T.T)) if qq else np.empty((0, n))
    for g in range(qq):
        for i in range(n):
            for j in range(i + 1, n):
                v = 0.5 * (Qv[g * n + i, j] + Qv[g * n + j, i])
                Qv[g * n + i, j] = v
                Qv[g * n + j, i] = v
    _unstack(Qv, sQ, dQd)


@njit(cache=True, error_model="numpy", inline="always")
def _eig2(a: float, b: float, d: float) -> Eigen2:
    """The eigen-decomposition of the symmetric ``[[a, b], [b, d]]`` by one Jacobi rotation (:func:`jacobi_tangent`).

    Backward stable, as LAPACK's solver is; the eigenvalues ascending, as LAPACK's.
    """
    t = jacobi_tangent(a, b, d)
    c = 1.0 / math.sqrt(1.0 + t * t)
    s = t * c
    l0 = a - t * b
    l1 = d + t * b
    if l0 <= l1:
        return Eigen2(l0, l1, c, s, -s, c)
    return Eigen2(l1, l0, s, c, c, -s)


@njit(cache=True, error_model="numpy", inline="always")
def _y2(a: float, b: float, ea: float, eb: float, om: float, emf0: float, h: float) -> float:
    """``h^2 exp[0, a, b]`` with ``a = x_i + x_m``, ``b = x_j + x_m`` of :func:`spectral_derivatives`.

    ``ea, eb`` their exponentials; ``om = Om[argmax(x_i, x_j), m]`` and ``emf0 = e^{x_m} F0_ij``
    for the recurrence taken when both nodes are negative and apart.
    """
    lo = min(a, b)
    if max(a, b) <= 0.0 and lo <= -SERIES_LIMIT:
        return h * (om - emf0) / (-lo)
    return h * h * _dd3_sorted(0.0, a, b, 1.0, ea, eb)


@njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})
def spectral_derivatives2(
    step: Interval, dstep: IntervalDirections, how: Discretization, out: Dynamics, dout: DynamicsDerivatives
) -> None:
    """:func:`spectral_derivatives` of a 2-state RC model, written out in scalars.

    The same Daleckii-Krein formulas, with the eigen-decomposition of the symmetrized 2-by-2
    matrix by one Jacobi rotation (Golub and Van Loan [1]_, Algorithm 8.5.1) and no work arrays: a 2-state model's
    gradient discretizes and differentiates every distinct interval at each evaluation, and the
    general function's LAPACK call, BLAS products and some fifty small arrays were most of that.
    Written for the fused 2-state adjoint (:mod:`rczone.kernels.adjoint`); the tests compare it
    with the complex step through ``scipy.linalg.expm``.

    Parameters
    ----------
    step, dstep, how, out, dout
        As :func:`spectral_derivatives`, with two states.

    References
    ----------
    .. [1] G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins, 2013.
    """
    A, B, qc, h = step
    dA, dB, dqc = dstep
    scale, foh, noise = how.scale, how.foh, how.noise
    Phi, G0, G1, Qd = out
    dPhi, dG0, dG1, dQd = dout
    p = B.shape[1]
    q = dA.shape[0]
    s0, s1 = scale[0], scale[1]
    b = 0.5 * (s0 * A[0, 1] / s1 + s1 * A[1, 0] / s0)
    eig = _eig2(A[0, 0], b, A[1, 1])
    l0, l1, v00, v01, v10, v11 = eig.lam0, eig.lam1, eig.v00, eig.v01, eig.v10, eig.v11
    # T = diag(scale)^-1 V, T^-1 = V' diag(scale)
    t00, t01, t10, t11 = v00 / s0, v01 / s0, v10 / s1, v11 / s1
    i00, i01, i10, i11 = v00 * s0, v10 * s1, v01 * s0, v11 * s1
    h2 = h * h
    x0 = l0 * h
    x1 = l1 * h
    em0 = math.expm1(x0)
    em1 = math.expm1(x1)
    e0 = math.exp(x0)
    e1 = math.exp(x1)
    g10 = phi2(x0, em0) * h if foh else 0.0
    g11 = phi2(x1, em1) * h if foh else 0.0
    g00 = phi1(x0, em0) * h - g10
    g01 = phi1(x1, em1) * h - g11
    # divided-difference kernels (symmetric): F0 of Phi, Fg0 and Fg1 of the hold matrices
    f00 = h * _dd2(x0, x0, e0, e0)
    f01 = h * _dd2(x0, x1, e0, e1)
    f11 = h * _dd2(x1, x1, e1, e1)
    k00 = h2 * _dd4_00(x0, x0, e0, e0) if foh else 0.0
    k01 = h2 * _dd4_00(x0, x1, e0, e1) if foh else 0.0
    k11 = h2 * _dd4_00(x1, x1, e1, e1) if foh else 0.0
    j00 = h2 * _dd3_sorted(0.0, x0, x0, 1.0, e0, e0) - k00
    j01 = h2 * _dd3_sorted(0.0, x0, x1, 1.0, e0, e1) - k01
    j11 = h2 * _dd3_sorted(0.0, x1, x1, 1.0, e1, e1) - k11
    # Phi = T diag(e) T^-1; G = T diag(g) T^-1 B
    Phi[0, 0] = t00 * e0 * i00 + t01 * e1 * i10
    Phi[0, 1] = t00 * e0 * i01 + t01 * e1 * i11
    Phi[1, 0] = t10 * e0 * i00 + t11 * e1 * i10
    Phi[1, 1] = t10 * e0 * i01 + t11 * e1 * i11
    for c in range(p):
        u0 = i00 * B[0, c] + i01 * B[1, c]
        u1 = i10 * B[0, c] + i11 * B[1, c]
        G0[0, c] = t00 * g00 * u0 + t01 * g01 * u1
        G0[1, c] = t10 * g00 * u0 + t11 * g01 * u1
        if foh:
            G1[0, c] = t00 * g10 * u0 + t01 * g11 * u1
            G1[1, c] = t10 * g10 * u0 + t11 * g11 * u1
    # noise: W = T^-1 Qc T^-T, Om_il = h exp[0, x_i + x_l], Qd = T (W o Om) T'
    w00 = w01 = w11 = o00 = o01 = o11 = 0.0
    y000 = y001 = y010 = y011 = y100 = y101 = y110 = y111 = 0.0  # W_jm Y_ijm at y_ijm
    if noise:
        w00 = i00 * qc[0] * i00 + i01 * qc[1] * i01
        w01 = i00 * qc[0] * i10 + i01 * qc[1] * i11
        w11 = i10 * qc[0] * i10 + i11 * qc[1] * i11
        o00 = phi1(2.0 * x0, math.expm1(2.0 * x0)) * h
        o01 = phi1(x0 + x1, math.expm1(x0 + x1)) * h
        o11 = phi1(2.0 * x1, math.expm1(2.0 * x1)) * h
        # Om[argmax(x_i, x_j), m]: x0 <= x1, so the pair (0, 1) takes row 1
        v = _y2(2.0 * x0, 2.0 * x0, e0 * e0, e0 * e0, o00, e0 * f00, h)
        y000 = v * w00
        v = _y2(x0 + x1, x0 + x1, e0 * e1, e0 * e1, o01, e1 * f00, h)
        y001 = v * w01
        v = _y2(x0 + x0, x1 + x0, e0 * e0, e1 * e0, o01, e0 * f01, h)
        y010 = v * w01
        y100 = v * w00
        v = _y2(x0 + x1, x1 + x1, e0 * e1, e1 * e1, o11, e1 * f01, h)
        y011 = v * w11
        y101 = v * w01
        v = _y2(x1 + x0, x1 + x0, e1 * e0, e1 * e0, o01, e0 * f11, h)
        y110 = v * w01
        v = _y2(2.0 * x1, 2.0 * x1, e1 * e1, e1 * e1, o11, e1 * f11, h)
        y111 = v * w11
        z00, z01, z11 = w00 * o00, w01 * o01, w11 * o11
        a00 = t00 * z00 + t01 * z01
        a01 = t00 * z01 + t01 * z11
        a10 = t10 * z00 + t11 * z01
        a11 = t10 * z01 + t11 * z11
        Qd[0, 0] = a00 * t00 + a01 * t01
        Qd[0, 1] = a00 * t10 + a01 * t11
        Qd[1, 0] = Qd[0, 1]
        Qd[1, 1] = a10 * t10 + a11 * t11
    else:
        Qd[0, 0] = Qd[0, 1] = Qd[1, 0] = Qd[1, 1] = 0.0
    for d in range(q):
        movA = dA[d, 0, 0] != 0.0 or dA[d, 0, 1] != 0.0 or dA[d, 1, 0] != 0.0 or dA[d, 1, 1] != 0.0
        movB = False
        for c in range(p):
            movB = movB or dB[d, 0, c] != 0.0 or dB[d, 1, c] != 0.0
        movq = noise and (dqc[d, 0] != 0.0 or dqc[d, 1] != 0.0)
        # E = T^-1 dA T
        r00 = dA[d, 0, 0] * t00 + dA[d, 0, 1] * t10
        r01 = dA[d, 0, 0] * t01 + dA[d, 0, 1] * t11
        r10 = dA[d, 1, 0] * t00 + dA[d, 1, 1] * t10
        r11 = dA[d, 1, 0] * t01 + dA[d, 1, 1] * t11
        E00 = i00 * r00 + i01 * r10
        E01 = i00 * r01 + i01 * r11
        E10 = i10 * r00 + i11 * r10
        E11 = i10 * r01 + i11 * r11
        # dPhi = T (F0 o E) T^-1
        m00, m01, m10, m11 = f00 * E00, f01 * E01, f01 * E10, f11 * E11
        n00 = t00 * m00 + t01 * m10
        n01 = t00 * m01 + t01 * m11
        n10 = t10 * m00 + t11 * m10
        n11 = t10 * m01 + t11 * m11
        dPhi[d, 0, 0] = n00 * i00 + n01 * i10
        dPhi[d, 0, 1] = n00 * i01 + n01 * i11
        dPhi[d, 1, 0] = n10 * i00 + n11 * i10
        dPhi[d, 1, 1] = n10 * i01 + n11 * i11
        # dG = T ((Fg o E) T^-1 B + diag(g) T^-1 dB)
        for c in range(p):
            if not (movA or movB):
                dG0[d, 0, c] = dG0[d, 1, c] = 0.0
                continue
            u0 = i00 * B[0, c] + i01 * B[1, c]
            u1 = i10 * B[0, c] + i11 * B[1, c]
            du0 = i00 * dB[d, 0, c] + i01 * dB[d, 1, c]
            du1 = i10 * dB[d, 0, c] + i11 * dB[d, 1, c]
            a0 = j00 * E00 * u0 + j01 * E01 * u1 + g00 * du0
            a1 = j01 * E10 * u0 + j11 * E11 * u1 + g01 * du1
            dG0[d, 0, c] = t00 * a0 + t01 * a1
            dG0[d, 1, c] = t10 * a0 + t11 * a1
            if foh:
                a0 = k00 * E00 * u0 + k01 * E01 * u1 + g10 * du0
                a1 = k01 * E10 * u0 + k11 * E11 * u1 + g11 * du1
                dG1[d, 0, c] = t00 * a0 + t01 * a1
                dG1[d, 1, c] = t10 * a0 + t11 * a1
        # dQd = T (X + X' + (T^-1 diag(dqc) T^-T) o Om) T' with X_il = sum_j E_ij W_jl Y_ijl
        if not (noise and (movA or movq)):
            dQd[d, 0, 0] = dQd[d, 0, 1] = dQd[d, 1, 0] = dQd[d, 1, 1] = 0.0
            continue
        X00 = E00 * y000 + E01 * y010
        X01 = E00 * y001 + E01 * y011
        X10 = E10 * y100 + E11 * y110
        X11 = E10 * y101 + E11 * y111
        z00 = 2.0 * X00
        z01 = X01 + X10
        z11 = 2.0 * X11
        if movq:
            q0, q1 = dqc[d, 0], dqc[d, 1]
            z00 += (i00 * q0 * i00 + i01 * q1 * i01) * o00
            z01 += (i00 * q0 * i10 + i01 * q1 * i11) * o01
            z11 += (i10 * q0 * i10 + i11 * q1 * i11) * o11
        a00 = t00 * z00 + t01 * z01
        a01 = t00 * z01 + t01 * z11
        a10 = t10 * z00 + t11 * z01
        a11 = t10 * z01 + t11 * z11
        dQd[d, 0, 0] = a00 * t00 + a01 * t01
        dQd[d, 0, 1] = 0.5 * ((a00 * t10 + a01 * t11) + (a10 * t00 + a11 * t01))
        dQd[d, 1, 0] = dQd[d, 0, 1]
        dQd[d, 1, 1] = a10 * t10 + a11 * t11


@njit(cache=True, error_model="numpy")
def _slots(moved: np.ndarray) -> tuple[np.ndarray, int]:
    """The place of each moved direction in a stack of the moved ones (-1 for the others), and their number."""
    slot = np.full(moved.shape[0], -1, dtype=np.int64)
    k = 0
    for d in range(moved.shape[0]):
        if moved[d]:
            slot[d] = k
            k += 1
    return slot, k


@njit(cache=True, error_model="numpy")
def _unstack(Xv: np.ndarray, slot: np.ndarray, out: np.ndarray) -> None:
    """``out[d]`` = block ``slot[d]`` of the vertical stack ``Xv`` (zero where ``slot[d] < 0``)."""
    n, m = out.shape[1], out.shape[2]
    for d in range(out.shape[0]):
        s = slot[d]
        for i in range(n):
            for j in range(m):
                out[d, i, j] = Xv[s * n + i, j] if s >= 0 else 0.0


@njit(cache=True, error_model="numpy")
def _sandwich(L: np.ndarray, D: np.ndarray, R: np.ndarray, slot: np.ndarray, k: int) -> np.ndarray:
    """``L D_d R`` for the ``D_d`` of a stack (q, n, m) with ``slot[d] >= 0``, side by side in that order (n', k m').

    Only the non-zero rows of each ``D_d`` are visited: a parameter's derivative of ``A`` or
    ``B`` has one (a capacity) or a few (a resistance) of them, or none (a noise level).
    """
    q, n, m = D.shape
    r = R.shape[1]
    out = np.zeros((L.shape[0], k * r))
    row = np.empty(r)
    for d in range(q):
        if slot[d] < 0:
            continue
        c0 = slot[d] * r
        for a in range(n):
            nz = False
            for b in range(m):
                nz = nz or D[d, a, b] != 0.0
            if not nz:
                continue
            for j in range(r):
                row[j] = 0.0
            for b in range(m):
                c = D[d, a, b]
                if c != 0.0:
                    for j in range(r):
                        row[j] += c * R[b, j]
            for i in range(L.shape[0]):
                c = L[i, a]
                for j in range(r):
                    out[i, c0 + j] += c * row[j]
    return out


@njit(cache=True, error_model="numpy")
def _h2v(Xh: np.ndarray, k: int) -> np.ndarray:
    """``k`` blocks side by side ``(n, k m)`` to on top of each other ``(k n, m)``."""
    n = Xh.shape[0]
    m = Xh.shape[1] // k if k else 0
    Xv = np.empty((k * n, m))
    for d in range(k):
        for i in range(n):
            for j in range(m):
                Xv[d * n + i, j] = Xh[i, d * m + j]
    return Xv


@njit(cache=True, error_model="numpy")
def congruence(T: np.ndarray, Z: np.ndarray, out: np.ndarray) -> None:
    """``out = T Z T'`` for symmetric ``Z``, exactly symmetric (``out`` may be ``Z``)."""
    n = T.shape[0]
    TZ = np.empty((n, n))
    matmul(T, Z, TZ)
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += TZ[i, k] * T[j, k]
            out[i, j] = acc
            out[j, i] = acc


@njit(cache=True, error_model="numpy")
def _symmetrize(X: np.ndarray) -> None:
    for i in range(X.shape[0]):
        for j in range(i + 1, X.shape[0]):
            v = 0.5 * (X[i, j] + X[j, i])
            X[i, j] = v
            X[j, i] = v


@njit(cache=True, error_model="numpy", inline="always")
def _key_matrices(mod: Assembled, key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A0 + sum m_f N_f`` and ``B0 + sum m_f M_f`` for ``key = (dt, m_1, ...)``."""
    N, M = mod.N, mod.M
    A = mod.A0.copy()
    B = mod.B0.copy()
    for f in range(N.shape[0]):
        mf = key[1 + f]
        if mf != 0.0:
            for i in range(A.shape[0]):
                for j in range(A.shape[1]):
                    A[i, j] += mf * N[f, i, j]
                for j in range(B.shape[1]):
                    B[i, j] += mf * M[f, i, j]
    return A, B


@njit(cache=True, error_model="numpy", inline="always")
def _rc_interval(step: Interval, how: Discretization, out: Dynamics, k: int) -> None:
    """Interval ``k`` of an RC network into the stacks ``out``: the closed 2-state form or the spectral formulas.

    The closed form writes its few numbers in place (no views of the stacks per interval: with
    thousands of distinct intervals their reference counts are a tenth of the 2-state cost).
    """
    if how.scale.shape[0] != 2:
        spectral_discretize(step, how, Dynamics(out.Phi[k], out.G0[k], out.G1[k], out.Qd[k]))
        return
    _rc2_interval(step, how, out, k)


@njit(cache=True, error_model="numpy", inline="always")
def _rc2_interval(step: Interval, how: Discretization, out: Dynamics, k: int) -> None:
    """Interval ``k`` of a 2-state RC network into the stacks ``out``, by :func:`rc2_discretize`."""
    A, B, qc, h = step
    scale = how.scale
    Phi, G0, G1, Qd = out
    m = rc2_discretize(
        Rc2Model(A[0, 0], A[0, 1], A[1, 0], A[1, 1], scale[0], scale[1], 1.0 / scale[0], 1.0 / scale[1]),
        h,
        qc[0],
        qc[1],
        how.foh,
    )
    Phi[k, 0, 0], Phi[k, 0, 1], Phi[k, 1, 0], Phi[k, 1, 1] = m.phi00, m.phi01, m.phi10, m.phi11
    Qd[k, 0, 0], Qd[k, 0, 1], Qd[k, 1, 0], Qd[k, 1, 1] = m.qd00, m.qd01, m.qd01, m.qd11
    for j in range(B.shape[1]):
        G0[k, 0, j] = m.h0_00 * B[0, j] + m.h0_01 * B[1, j]
        G0[k, 1, j] = m.h0_10 * B[0, j] + m.h0_11 * B[1, j]
        G1[k, 0, j] = m.h1_00 * B[0, j] + m.h1_01 * B[1, j]
        G1[k, 1, j] = m.h1_10 * B[0, j] + m.h1_11 * B[1, j]


@njit(cache=True, error_model="numpy")
def rc_interval_matrices(mod: Assembled, how: Discretization) -> Dynamics:
    """:func:`interval_matrices` of an RC network (``scale`` symmetrizes every ``A``), by spectral formulas only.

    The same matrices; a caller that knows its model is an RC network calls this one, which does
    not compile the matrix-exponential route (a first run's compile time, issue 19).

    Parameters
    ----------
    mod, how
        As :func:`interval_matrices` (``how.scale`` required).

    Returns
    -------
    Dynamics
    """
    keys = how.keys
    out, qc = _matrix_stacks(mod, how)
    for k in range(keys.shape[0]):
        A, B = _key_matrices(mod, keys[k])
        _rc_interval(Interval(A, B, qc, keys[k, 0]), how, out, k)
    return out


@njit(cache=True, error_model="numpy")
def rc2_interval_matrices(mod: Assembled, how: Discretization) -> Dynamics:
    """:func:`rc_interval_matrices` of a 2-state RC network: the closed form only.

    Called for two states, it compiles no eigen-solver (a first run's compile time).
    """
    keys = how.keys
    out, qc = _matrix_stacks(mod, how)
    for k in range(keys.shape[0]):
        A, B = _key_matrices(mod, keys[k])
        _rc2_interval(Interval(A, B, qc, keys[k, 0]), how, out, k)
    return out


def matrices_kernel(n: int, rc: bool):
    """The compiled function that discretizes every interval of an ``n``-state model, called from Python.

    :func:`rc2_interval_matrices` for a 2-state RC network, :func:`rc_interval_matrices` for a
    larger one (``rc``: its ``scale`` symmetrizes ``A``), :func:`expm_interval_matrices` otherwise
    (the output sensitivities' augmented system, for one): each compiles only the route it runs (a
    first run's time).
    """
    if not rc:
        return expm_interval_matrices
    return rc2_interval_matrices if n == 2 else rc_interval_matrices


def derivatives_kernel(rc: bool):
    """The compiled :func:`interval_derivatives` of one route, called from Python (the general engine).

    :func:`rc_derivatives` for an RC network (``rc``: its ``scale`` symmetrizes ``A``; spectral
    formulas only), :func:`expm_interval_derivatives` otherwise: each compiles only the route it runs.
    """
    return rc_derivatives if rc else expm_interval_derivatives


@njit(cache=True, error_model="numpy", inline="always")
def _matrix_stacks(mod: Assembled, how: Discretization) -> tuple[Dynamics, np.ndarray]:
    """Room for the matrices of every interval (``G1``, ``Qd`` zero), and the noise intensities (zero without noise)."""
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    K = how.keys.shape[0]
    out = Dynamics(np.empty((K, n, n)), np.empty((K, n, p)), np.zeros((K, n, p)), np.zeros((K, n, n)))
    return out, mod.qc if how.noise else np.zeros(n)


@njit(cache=True, error_model="numpy")
def _key_directions(der: AssembledDerivatives, key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives of :func:`_key_matrices`' sums along each direction, shapes (q, n, n), (q, n, p)."""
    dN, dM = der.dN, der.dM
    dA = der.dA0.copy()
    dB = der.dB0.copy()
    for f in range(dN.shape[1]):
        mf = key[1 + f]
        if mf != 0.0:
            for d in range(dA.shape[0]):
                for i in range(dA.shape[1]):
                    for j in range(dA.shape[2]):
                        dA[d, i, j] += mf * dN[d, f, i, j]
                    for j in range(dB.shape[2]):
                        dB[d, i, j] += mf * dM[d, f, i, j]
    return dA, dB


@njit(cache=True, error_model="numpy")
def interval_matrices(mod: Assembled, how: Discretization) -> Dynamics:
    """The discrete matrices of each distinct interval.

    Parameters
    ----------
    mod : Assembled
        The bilinear model: ``A = A0 + sum_f m_f N_f``, ``B = B0 + sum_f m_f M_f`` (shapes (n, n),
        (nf, n, n), (n, p), (nf, n, p)) and the process-noise intensities ``qc`` (n,); the other
        fields are not read (:func:`rczone.kernels.arrays.dynamics_model` builds one from matrices).
    how : Discretization
        ``keys`` (K, 1 + nf), ``(dt, m_1, ..., m_nf)`` of each distinct interval; ``scale``,
        ``sqrt(capacities)`` when it symmetrizes every ``A`` (an RC network: spectral formulas,
        :func:`rc_interval_matrices`), empty for matrix exponentials; the hold; ``noise``: compute
        ``Qd`` (zero otherwise, e.g. for open-loop least squares).

    Returns
    -------
    Dynamics
    """
    if how.scale.shape[0] == mod.A0.shape[0]:
        return rc_interval_matrices(mod, how)
    return expm_interval_matrices(mod, how)


@njit(cache=True, error_model="numpy")
def expm_interval_matrices(mod: Assembled, how: Discretization) -> Dynamics:
    """:func:`interval_matrices` by block matrix exponentials only (``how.scale`` is not read).

    For a model that is no RC network; called directly, it compiles no spectral route.
    """
    n = mod.A0.shape[0]
    keys = how.keys
    p = mod.B0.shape[1]
    K = keys.shape[0]
    out = Dynamics(np.empty((K, n, n)), np.empty((K, n, p)), np.zeros((K, n, p)), np.zeros((K, n, n)))
    none = IntervalDirections(np.empty((0, n, n)), np.empty((0, n, p)), np.empty((0, n)))
    dout = DynamicsDerivatives(
        np.empty((0, n, n)), np.empty((0, n, p)), np.empty((0, n, p)), np.empty((0, n, n))
    )
    for k in range(K):
        A, B = _key_matrices(mod, keys[k])
        step = Interval(A, B, mod.qc, keys[k, 0])
        expm_discretize(step, none, how, Dynamics(out.Phi[k], out.G0[k], out.G1[k], out.Qd[k]), dout)
    return out


@njit(cache=True, error_model="numpy", inline="always")
def _stacks(mod: Assembled, der: AssembledDerivatives, K: int) -> tuple[Dynamics, DynamicsDerivatives]:
    """Room for the matrices of ``K`` intervals and their derivatives (``G1``, ``dG1`` zero: ZOH leaves them)."""
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    q = der.dA0.shape[0]
    mats = Dynamics(np.empty((K, n, n)), np.empty((K, n, p)), np.zeros((K, n, p)), np.empty((K, n, n)))
    dmats = DynamicsDerivatives(
        np.empty((K, q, n, n)), np.empty((K, q, n, p)), np.zeros((K, q, n, p)), np.empty((K, q, n, n))
    )
    return mats, dmats


@njit(cache=True, error_model="numpy", inline="always")
def _interval(
    mod: Assembled,
    der: AssembledDerivatives,
    key: np.ndarray,
    mats: Dynamics,
    dmats: DynamicsDerivatives,
    k: int,
) -> tuple[Interval, IntervalDirections, Dynamics, DynamicsDerivatives]:
    """Interval ``key = (dt, m_1, ...)``'s model and directions, and the ``k``-th slices of the stacks it fills."""
    A, B = _key_matrices(mod, key)
    dA, dB = _key_directions(der, key)
    return (
        Interval(A, B, mod.qc, key[0]),
        IntervalDirections(dA, dB, der.dqc),
        Dynamics(mats.Phi[k], mats.G0[k], mats.G1[k], mats.Qd[k]),
        DynamicsDerivatives(dmats.dPhi[k], dmats.dG0[k], dmats.dG1[k], dmats.dQd[k]),
    )


@njit(cache=True, error_model="numpy", inline="always")
def rc_interval_derivatives(
    mod: Assembled, der: AssembledDerivatives, how: Discretization
) -> tuple[Dynamics, DynamicsDerivatives]:
    """:func:`interval_derivatives` of an RC network, by the spectral formulas only (written out for two states).

    An RC network's ``diag(scale) A diag(scale)^-1`` is symmetric; a caller that knows its model is
    one (the general adjoint, :func:`rczone.kernels.adjoint.gradient_general`) calls this and does
    not compile the matrix exponentials' Fréchet derivatives it never runs (a first fit's compile
    time); two states go to :func:`rc2_interval_derivatives`.
    :func:`interval_derivatives` calls it for such models too. Inlined into its callers: no
    separate machine code of its own.

    Parameters
    ----------
    mod, der, how
        As :func:`interval_derivatives` (``how.scale``, ``sqrt(capacities)``, required).

    Returns
    -------
    Dynamics
    DynamicsDerivatives
    """
    if mod.A0.shape[0] == 2:
        return rc2_interval_derivatives(mod, der, how)
    mats, dmats = _stacks(mod, der, how.keys.shape[0])
    for k in range(how.keys.shape[0]):
        step, dstep, out, dout = _interval(mod, der, how.keys[k], mats, dmats, k)
        spectral_derivatives(step, dstep, how, out, dout)
    return mats, dmats


@njit(cache=True, error_model="numpy", inline="always")
def rc2_interval_derivatives(
    mod: Assembled, der: AssembledDerivatives, how: Discretization
) -> tuple[Dynamics, DynamicsDerivatives]:
    """:func:`rc_interval_derivatives` of a 2-state RC network, by :func:`spectral_derivatives2`.

    The fused 2-state adjoint calls it and compiles no general eigen-solver or BLAS route.
    Inlined into its callers.
    """
    mats, dmats = _stacks(mod, der, how.keys.shape[0])
    for k in range(how.keys.shape[0]):
        step, dstep, out, dout = _interval(mod, der, how.keys[k], mats, dmats, k)
        spectral_derivatives2(step, dstep, how, out, dout)
    return mats, dmats


@njit(cache=True, error_model="numpy")
def interval_derivatives(
    mod: Assembled, der: AssembledDerivatives, how: Discretization
) -> tuple[Dynamics, DynamicsDerivatives]:
    """As :func:`interval_matrices`, with the derivatives along ``q`` directions.

    Parameters
    ----------
    mod : Assembled
        As :func:`interval_matrices`.
    der : AssembledDerivatives
        ``dA0, dN, dB0, dM, dqc`` (shapes (q, n, n), (q, nf, n, n), (q, n, p), (q, nf, n, p),
        (q, n)) are read (:func:`rczone.kernels.arrays.dynamics_derivatives` builds one).
    how : Discretization
        As :func:`interval_matrices`: ``scale`` for an RC network (:func:`rc_interval_derivatives`),
        empty for matrix exponentials (:func:`expm_discretize`).

    Returns
    -------
    Dynamics
        As :func:`interval_matrices`.
    DynamicsDerivatives
        Their derivatives along the ``q`` directions.
    """
    if how.scale.shape[0] == mod.A0.shape[0]:
        return rc_interval_derivatives(mod, der, how)
    return expm_interval_derivatives(mod, der, how)


@njit(cache=True, error_model="numpy")
def rc_derivatives(
    mod: Assembled, der: AssembledDerivatives, how: Discretization
) -> tuple[Dynamics, DynamicsDerivatives]:
    """:func:`rc_interval_derivatives` compiled on its own, for Python callers (:func:`derivatives_kernel`)."""
    return rc_interval_derivatives(mod, der, how)


@njit(cache=True, error_model="numpy")
def expm_interval_derivatives(
    mod: Assembled, der: AssembledDerivatives, how: Discretization
) -> tuple[Dynamics, DynamicsDerivatives]:
    """:func:`interval_derivatives` by block matrix exponentials and their Fréchet derivatives only."""
    mats, dmats = _stacks(mod, der, how.keys.shape[0])
    for k in range(how.keys.shape[0]):
        step, dstep, out, dout = _interval(mod, der, how.keys[k], mats, dmats, k)
        expm_discretize(step, dstep, how, out, dout)
    return mats, dmats
