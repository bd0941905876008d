"""The adjoint of the spectral discretization: matrix adjoints carried back to ``A``, ``B`` and ``qc``.

A reverse pass of the filter (:func:`rczone.kernels.reverse.nll_reverse`) gives the adjoints
``Phi_bar``, ``G0_bar``, ``Qd_bar`` of each distinct interval's discrete matrices. Contracting them
with the forward derivatives of those matrices along every parameter
(:func:`rczone.kernels.discretize.rc_interval_derivatives`) costs ``q`` derivative matrices per
interval; carrying them back through the same spectral formulas instead costs one pass per interval
whatever ``q``, and meets each parameter's ``dA0``, ``dN``, ``dB0``, ``dM``, ``dqc`` once, in
:func:`discretization_adjoints`' sums.

With ``S = T^-1 A T = diag(lam)`` (``T = D^-1 V`` of the symmetrized eigen-decomposition,
:func:`rczone.kernels.discretize.symmetric_eigen`) the Daleckii-Krein derivative
``dPhi = T (F o T^-1 dA T) T^-1`` has the adjoint ``A_bar = T^-T (F o T' Phi_bar T^-T) T'`` (Higham
[1]_, Theorem 3.11; Giles [2]_ for the adjoints of products). The zero-order hold's
``G0 = T diag(h phi1(lam h)) T^-1 B`` adds ``Fg o T' G0_bar (T^-1 B)'`` inside the same bracket and
``B_bar = T^-T diag(w) T' G0_bar``; the noise integral ``Qd = T (W o Om) T'`` (``W = T^-1 diag(qc)
T^-T``) adds ``2 sum_m S_im Y_ijm W_jm`` with ``S = T' Qd_bar T`` and gives
``qc_bar = diag(T^-T (S o Om) T^-1)``. The divided differences and their branches are those of the
forward formulas, so the gradient equals the forward contraction's to rounding. Zero-order hold
only: a first-order hold's ``G1`` keeps the forward contraction (:mod:`rczone.kernels.adjoint`).

References
----------
.. [1] N. J. Higham, *Functions of Matrices: Theory and Computation*, SIAM 2008, section 3.2
   (the Frechet derivative of a function of a diagonalizable matrix, Daleckii-Krein).
.. [2] M. B. Giles, "Collected matrix derivative results for forward and reverse mode
   algorithmic differentiation", in *Advances in Automatic Differentiation*, Springer 2008, 35-44.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rczone.kernels.arrays import Assembled, ModelAdjoints, SpectralWeights
from rczone.kernels.discretize import SERIES_LIMIT, _dd2, _dd3_sorted, _key_matrices, phi1, symmetric_eigen
from rczone.kernels.reverse import Adjoints


@njit(cache=True, error_model="numpy")
def _weights(lam: np.ndarray, h: float) -> SpectralWeights:
    """``x = lam h``, ``e^x``, the hold's weights ``h phi1(x)`` and the divided differences of ``Phi`` and ``G0``."""
    n = lam.shape[0]
    x = lam * h
    e = np.exp(x)
    wg = np.empty(n)
    F0 = np.empty((n, n))
    Fg = np.empty((n, n))
    for i in range(n):
        wg[i] = phi1(x[i], math.expm1(x[i])) * h
        for j in range(i, n):
            F0[i, j] = F0[j, i] = h * _dd2(x[i], x[j], e[i], e[j])
            Fg[i, j] = Fg[j, i] = h * h * _dd3_sorted(0.0, x[i], x[j], 1.0, e[i], e[j])
    return SpectralWeights(x, e, wg, F0, Fg)


@njit(cache=True, error_model="numpy")
def _noise_adjoint(Ti, qc, sw: SpectralWeights, h, S, Eb) -> np.ndarray:
    """Add the noise integral's share to ``Eb`` (the adjoint of ``T^-1 dA T``); return ``S o Om``."""
    x, e, F0 = sw.x, sw.e, sw.F0
    n = x.shape[0]
    W = np.empty((n, n))
    Om = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += Ti[i, k] * qc[k] * Ti[j, k]
            W[i, j] = W[j, i] = acc
            xs = x[i] + x[j]
            Om[i, j] = Om[j, i] = phi1(xs, math.expm1(xs)) * h
    for m in range(n):
        for i in range(n):
            for j in range(i, n):
                lo = min(x[i], x[j]) + x[m]
                hi = max(x[i], x[j]) + x[m]
                if hi <= 0.0 and lo <= -SERIES_LIMIT:  # the branch of the forward formula
                    v = h * (Om[i if x[i] >= x[j] else j, m] - e[m] * F0[i, j]) / (-lo)
                else:
                    v = h * h * _dd3_sorted(0.0, x[i] + x[m], x[j] + x[m], 1.0, e[i] * e[m], e[j] * e[m])
                Eb[i, j] += 2.0 * S[i, m] * v * W[j, m]
                if j != i:
                    Eb[j, i] += 2.0 * S[j, m] * v * W[i, m]
    return S * Om


@njit(cache=True, error_model="numpy")
def interval_adjoint(
    A: np.ndarray,
    B: np.ndarray,
    qc: np.ndarray,
    h: float,
    scale: np.ndarray,
    w: int,
    bars: Adjoints,
    out: ModelAdjoints,
) -> None:
    """Add to ``out`` the adjoints of ``A``, ``B``, ``qc`` from those of interval ``w``'s ``Phi``, ``G0``, ``Qd`` (ZOH).

    ``A``, ``B`` are the interval's continuous matrices, ``h`` its length, ``scale`` the square roots
    of the capacities that symmetrize ``A`` (module notes).
    """
    Phib, G0b, Qdb = bars.Phi[w], bars.G0[w], bars.Qd[w]
    n = A.shape[0]
    lam, V = symmetric_eigen(A, scale)
    T = np.empty((n, n))
    Ti = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            T[i, j] = V[i, j] / scale[i]
            Ti[j, i] = V[i, j] * scale[i]
    sw = _weights(lam, h)
    Tt = np.ascontiguousarray(T.T)
    Tit = np.ascontiguousarray(Ti.T)
    TiB = Ti @ B
    Eb = sw.F0 * (Tt @ Phib @ Tit) + sw.Fg * (Tt @ G0b @ np.ascontiguousarray(TiB.T))
    TG = Tt @ G0b
    for i in range(n):
        TG[i] *= sw.wg[i]
    out.B[:, :] += Tit @ TG
    S = Tt @ Qdb @ T
    SOm = _noise_adjoint(Ti, qc, sw, h, S, Eb)
    out.A[:, :] += Tit @ Eb @ Tt
    back = Tit @ SOm @ Ti
    for k in range(n):
        out.qc[k] += back[k, k]


@njit(cache=True, error_model="numpy")
def discretization_adjoints(mod: Assembled, keys: np.ndarray, bars: Adjoints) -> ModelAdjoints:
    """The adjoints of ``A0`` and the ``N_f``, of ``B0`` and the ``M_f`` and of ``qc``, from the filter's ``bars``.

    Each distinct interval ``keys[w] = (h, m_1, ...)`` has ``A = A0 + sum m_f N_f`` and
    ``B = B0 + sum m_f M_f``: its adjoints add to ``A0``'s and ``B0``'s, and ``m_f`` times them to
    ``N_f``'s and ``M_f``'s.
    """
    n, p, nf = mod.A0.shape[0], mod.B0.shape[1], mod.N.shape[0]
    scale = np.sqrt(mod.cap)
    total = ModelAdjoints(np.zeros((1 + nf, n, n)), np.zeros((1 + nf, n, p)), np.zeros(n))
    for w in range(keys.shape[0]):
        A, B = _key_matrices(mod, keys[w])
        one = ModelAdjoints(np.zeros((n, n)), np.zeros((n, p)), total.qc)  # qc's adjoint summed in place
        interval_adjoint(A, B, mod.qc, keys[w, 0], scale, w, bars, one)
        total.A[0] += one.A
        total.B[0] += one.B
        for f in range(nf):
            mf = keys[w, 1 + f]
            if mf != 0.0:
                total.A[1 + f] += mf * one.A
                total.B[1 + f] += mf * one.B
    return total
