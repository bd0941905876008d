"""Compiled matrix exponential of small dense matrices, and its Fréchet derivatives.

``expm_frechet(A, E)`` returns ``e^A`` and, for each direction ``E[j]``, the Fréchet
derivative ``L(A, E_j) = d/dh e^{A + h E_j} |_{h=0}``, by scaling and squaring with a
diagonal Padé approximant whose degree (3, 5, 7, 9 or 13) is chosen from ``||A||_1`` so that
the backward error is below the unit roundoff [1]_; the derivatives are the exact
derivatives of that approximant and of the squarings [2]_, so they cost about three matrix
products each instead of the exponential of a block matrix twice the size. The Padé
numerator and denominator, their LU factorization and the squarings are shared by every
direction.

The discretization kernels (:mod:`rczone.kernels.discretize`) use it for the hold matrices
and the Van Loan integral of the process noise, and their derivatives. Loops are explicit
(no BLAS call per product): the matrices here have at most a few dozen rows.

References
----------
.. [1] N. J. Higham, "The scaling and squaring method for the matrix exponential revisited",
   SIAM J. Matrix Anal. Appl. 26(4) (2005) 1179-1193, Algorithm 2.3 and Table 2.3.
.. [2] A. H. Al-Mohy, N. J. Higham, "Computing the Fréchet derivative of the matrix
   exponential, with an application to condition number estimation", SIAM J. Matrix Anal.
   Appl. 30(4) (2009) 1639-1657, Algorithm 6.4.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: ``theta_m`` of [1]_ Table 2.3: largest ``||A||_1`` for which the degree-m Padé approximant is
#: accurate to the unit roundoff, for m = 3, 5, 7, 9, 13.
_THETA = np.array(
    [1.495585217958292e-2, 2.539398330063230e-1, 9.504178996162932e-1, 2.097847961257068, 5.371920351148152]
)
_DEGREES = np.array([3, 5, 7, 9, 13])
#: Coefficients ``b_0 .. b_m`` of the degree-m diagonal Padé approximant of ``e^x`` (rows padded with 0).
_PADE = np.zeros((5, 14))
_PADE[0, :4] = [120.0, 60.0, 12.0, 1.0]
_PADE[1, :6] = [30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0]
_PADE[2, :8] = [17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0]
_PADE[3, :10] = [
    17643225600.0,
    8821612800.0,
    2075673600.0,
    302702400.0,
    30270240.0,
    2162160.0,
    110880.0,
    3960.0,
    90.0,
    1.0,
]
#: Coefficient indices of the degree-13 terms (with A^6, A^4, A^2): U's high and low part, V's.
_HI_W = np.array([13, 11, 9])
_LO_W = np.array([7, 5, 3])
_HI_Z = np.array([12, 10, 8])
_LO_Z = np.array([6, 4, 2])
_PADE[4, :] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
]


@njit(cache=True, error_model="numpy")
def matmul(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``out = a @ b`` for small contiguous matrices (``out`` must not alias ``a`` or ``b``)."""
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            out[i, j] = 0.0
    _add_product(a, b, out)


@njit(cache=True, error_model="numpy")
def norm1(a: np.ndarray) -> float:
    """The 1-norm (largest column sum of absolute values) of a matrix."""
    big = 0.0
    for j in range(a.shape[1]):
        c = 0.0
        for i in range(a.shape[0]):
            c += abs(a[i, j])
        big = max(big, c)
    return big


@njit(cache=True, error_model="numpy")
def _combine(
    out: np.ndarray, c: np.ndarray, mats: np.ndarray, first: int, step: int, idx: np.ndarray, diag: float
) -> None:
    """``out = sum_k c[idx[k]] mats[first + k step] + diag I`` over ``k < len(idx)``."""
    n = out.shape[0]
    for i in range(n):
        for j in range(n):
            s = 0.0
            for k in range(idx.shape[0]):
                s += c[idx[k]] * mats[first + k * step, i, j]
            out[i, j] = s
        out[i, i] += diag


@njit(cache=True, error_model="numpy")
def _add_product(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``out += a @ b``."""
    n, k = a.shape
    m = b.shape[1]
    for i in range(n):
        for q in range(k):
            aiq = a[i, q]
            if aiq != 0.0:
                for j in range(m):
                    out[i, j] += aiq * b[q, j]


@njit(cache=True, error_model="numpy")
def lu_factor(a: np.ndarray, piv: np.ndarray) -> None:
    """In-place LU factorization with partial pivoting (``piv[k]``: row swapped with ``k``)."""
    n = a.shape[0]
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                t = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = t
        d = a[k, k]
        if d != 0.0:
            for i in range(k + 1, n):
                a[i, k] /= d
                f = a[i, k]
                if f != 0.0:
                    for j in range(k + 1, n):
                        a[i, j] -= f * a[k, j]


@njit(cache=True, error_model="numpy")
def lu_solve(lu: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """Solve ``A X = b`` in place for the factorization of :func:`lu_factor` (``b`` shape (n, m))."""
    n = lu.shape[0]
    m = b.shape[1]
    for k in range(n):
        p = piv[k]
        if p != k:
            for j in range(m):
                t = b[k, j]
                b[k, j] = b[p, j]
                b[p, j] = t
    for i in range(n):
        for k in range(i):
            f = lu[i, k]
            if f != 0.0:
                for j in range(m):
                    b[i, j] -= f * b[k, j]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            f = lu[i, k]
            if f != 0.0:
                for j in range(m):
                    b[i, j] -= f * b[k, j]
        d = lu[i, i]
        for j in range(m):
            b[i, j] /= d


@njit(cache=True, error_model="numpy")
def expm_frechet(A: np.ndarray, E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``e^A`` and the Fréchet derivatives ``L(A, E[j])`` (see the module notes).

    Parameters
    ----------
    A : ndarray, shape (n, n)
    E : ndarray, shape (q, n, n)
        Directions; ``q = 0`` computes the exponential only.

    Returns
    -------
    X : ndarray, shape (n, n)
        ``e^A``.
    L : ndarray, shape (q, n, n)
    """
    n = A.shape[0]
    q = E.shape[0]
    nrm = norm1(A)
    deg = 4
    for i in range(4):
        if nrm <= _THETA[i]:
            deg = i
            break
    s = 0
    if deg == 4 and nrm > _THETA[4]:
        s = max(0, math.ceil(math.log2(nrm / _THETA[4])))
    scale = 0.5**s
    a = np.empty((n, n))
    e = np.empty((q, n, n))
    for i in range(n):
        for j in range(n):
            a[i, j] = A[i, j] * scale
    for k in range(q):
        for i in range(n):
            for j in range(n):
                e[k, i, j] = E[k, i, j] * scale
    b = _PADE[deg]
    m = _DEGREES[deg]
    # even powers A^0, A^2, A^4 (, A^6, A^8) and their derivatives M_2k = L_{x^2k}(A, E)
    n_pow = 3 if m == 13 else m // 2
    pw = np.zeros((n_pow + 1, n, n))
    for i in range(n):
        pw[0, i, i] = 1.0
    matmul(a, a, pw[1])
    for k in range(2, n_pow + 1):
        matmul(pw[k - 1], pw[1], pw[k])
    dpw = np.zeros((q, n_pow + 1, n, n))
    for d in range(q):
        _add_product(a, e[d], dpw[d, 1])
        _add_product(e[d], a, dpw[d, 1])
        for k in range(2, n_pow + 1):
            _add_product(pw[k - 1], dpw[d, 1], dpw[d, k])
            _add_product(dpw[d, k - 1], pw[1], dpw[d, k])
    U = np.empty((n, n))
    V = np.empty((n, n))
    W = np.empty((n, n))
    dU = np.empty((q, n, n))
    dV = np.empty((q, n, n))
    Lw = np.empty((n, n))
    if m == 13:
        # U = A [A^6 (b13 A^6 + b11 A^4 + b9 A^2) + b7 A^6 + b5 A^4 + b3 A^2 + b1 I], V likewise with even b
        W1 = np.empty((n, n))
        Z1 = np.empty((n, n))
        Lw1 = np.empty((n, n))
        Lz1 = np.empty((n, n))
        _combine(W1, b, pw, 3, -1, _HI_W, 0.0)
        _combine(Z1, b, pw, 3, -1, _HI_Z, 0.0)
        _combine(W, b, pw, 3, -1, _LO_W, b[1])
        _combine(V, b, pw, 3, -1, _LO_Z, b[0])
        _add_product(pw[3], W1, W)
        _add_product(pw[3], Z1, V)
        matmul(a, W, U)
        for d in range(q):
            _combine(Lw1, b, dpw[d], 3, -1, _HI_W, 0.0)
            _combine(Lz1, b, dpw[d], 3, -1, _HI_Z, 0.0)
            _combine(Lw, b, dpw[d], 3, -1, _LO_W, 0.0)
            _combine(dV[d], b, dpw[d], 3, -1, _LO_Z, 0.0)
            _add_product(pw[3], Lw1, Lw)
            _add_product(dpw[d, 3], W1, Lw)
            _add_product(pw[3], Lz1, dV[d])
            _add_product(dpw[d, 3], Z1, dV[d])
            matmul(a, Lw, dU[d])
            _add_product(e[d], W, dU[d])
    else:
        odd = np.arange(3, m + 1, 2)
        even = np.arange(2, m + 1, 2)
        _combine(W, b, pw, 1, 1, odd, b[1])
        _combine(V, b, pw, 1, 1, even, b[0])
        matmul(a, W, U)
        for d in range(q):
            _combine(Lw, b, dpw[d], 1, 1, odd, 0.0)
            _combine(dV[d], b, dpw[d], 1, 1, even, 0.0)
            matmul(a, Lw, dU[d])
            _add_product(e[d], W, dU[d])
    # (V - U) X = V + U;  (V - U) L = dU + dV + (dU - dV) X
    den = np.empty((n, n))
    X = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            den[i, j] = V[i, j] - U[i, j]
            X[i, j] = V[i, j] + U[i, j]
    piv = np.empty(n, dtype=np.int64)
    lu_factor(den, piv)
    lu_solve(den, piv, X)
    L = np.empty((q, n, n))
    diff = np.empty((n, n))
    for d in range(q):
        for i in range(n):
            for j in range(n):
                L[d, i, j] = dU[d, i, j] + dV[d, i, j]
                diff[i, j] = dU[d, i, j] - dV[d, i, j]
        _add_product(diff, X, L[d])
        lu_solve(den, piv, L[d])
    tmp = np.empty((n, n))
    for _ in range(s):
        for d in range(q):
            matmul(X, L[d], tmp)
            _add_product(L[d], X, tmp)
            for i in range(n):
                for j in range(n):
                    L[d, i, j] = tmp[i, j]
        matmul(X, X, tmp)
        for i in range(n):
            for j in range(n):
                X[i, j] = tmp[i, j]
    return X, L


@njit(cache=True, error_model="numpy")
def expm(A: np.ndarray) -> np.ndarray:
    """``e^A`` (see :func:`expm_frechet`)."""
    return expm_frechet(A, np.empty((0, A.shape[0], A.shape[0])))[0]
