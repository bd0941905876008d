"""Compiled Kalman likelihood of a 2-state RC model, discretized exactly on the fly.

With the flow ``m`` changing at every sample, a likelihood evaluation is dominated by the
discretization (one ``Phi``, ``Gamma`` and ``Qd`` per sample), not by the filter. For an
RC network ``S = diag(s) A(m) diag(s)^{-1}`` (``s = sqrt(capacities)``) is symmetric, and
for two states its eigen-decomposition is one Jacobi rotation in closed form. Every
discrete matrix is then a product of that rotation with scalar functions of the two
eigenvalues (see :mod:`rczone.simulation.discretize` for the identities):

* ``Phi = T diag(e^{l dt}) T^{-1}``, ``T = diag(s)^{-1} V``;
* ZOH ``Gamma = T diag(phi1) T^{-1} B(m)``; FOH ``G1 = T diag(phi2) T^{-1} B(m)``,
  ``G0 = T diag(phi1 - phi2) T^{-1} B(m)``;
* ``Qd = T [W_ij (e^{(l_i + l_j) dt} - 1)/(l_i + l_j)] T'``, ``W = T^{-1} Qc T^{-T}``.

These are exact (no series truncation beyond rounding), so the kernel returns the same
``-log L`` as :func:`rczone.estimation.kalman.kalman_nll` on the matrices of
:func:`rczone.estimation.kalman.stochastic_matrices`, with two ``expm1`` per sample instead
of two matrix exponentials. The filter recursion (Joseph-form update, symmetrized, NaN =
missing) is the reference's, for one output.

References
----------
.. [1] H. Madsen, J. Holst, "Estimation of continuous-time models for the heat dynamics
   of a building", Energy and Buildings 22 (1995) 67-79.
.. [2] G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, Algorithm 8.5.1.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rczone.errors import InputShapeError
from rczone.network.statespace import BilinearStateSpace
from rczone.simulation.discretize import SYMMETRY_RTOL, symmetrizing_scale
from rczone.simulation.intervals import interval_keys, unique_rows
from rczone.simulation.simulate import HOLDS

_LOG_2PI = math.log(2.0 * math.pi)
_SERIES_LIMIT = 0.2
_PHI2 = np.array([1.0 / math.factorial(k + 2) for k in range(13)])
_NO_GROUPS = np.empty(0, dtype=np.int64)

#: Use a table of distinct intervals when it has at most this fraction of the intervals.
GROUP_FRACTION = 0.5


def interval_groups(t: np.ndarray, m: np.ndarray) -> np.ndarray | None:
    """Intervals that share their length and flows, so their discrete matrices are equal.

    Measured flows are quantized (a damper position, a logger resolution of 1 g/s), so a
    night of 720 samples typically has a few dozen distinct ``(dt, m)`` pairs; the kernels
    then discretize each pair once instead of every interval. Matching is exact (bit
    equality), so the results are identical to discretizing every interval.

    Parameters
    ----------
    t : ndarray, shape (N,)
    m : ndarray, shape (N, n_flows)

    Returns
    -------
    groups : ndarray of int64, shape (N - 1,), or None
        ``groups[k]`` is the group of interval ``k`` (``0 .. G - 1``); None when the groups
        would save little (more than :data:`GROUP_FRACTION` of the intervals are distinct) or
        there is no interval.
    """
    t = np.asarray(t, dtype=np.float64)
    m = np.asarray(m, dtype=np.float64).reshape(t.shape[0], -1)
    if t.shape[0] < 2:
        return None
    uniq, _, groups = unique_rows(interval_keys(t, m))
    if uniq.shape[0] > GROUP_FRACTION * groups.shape[0]:
        return None
    return groups


@njit(cache=True, error_model="numpy")
def _phi2(x: float, em1: float, phi2: np.ndarray) -> float:
    """``(e^x - 1 - x)/x^2`` from ``em1 = expm1(x)``, as :func:`rczone.simulation.discretize.phi_weights`."""
    if abs(x) < _SERIES_LIMIT:
        w2 = phi2[phi2.shape[0] - 1]
        for k in range(phi2.shape[0] - 2, -1, -1):
            w2 = w2 * x + phi2[k]
        return w2
    return (em1 - x) / (x * x)


@njit(cache=True, error_model="numpy")
def _ratio(x: float, em1: float) -> float:
    """``(e^x - 1)/x`` from ``em1 = expm1(x)``."""
    return 1.0 if x == 0.0 else em1 / x


@njit(cache=True, error_model="numpy")
def nll_rc2_kernel(
    A0: np.ndarray,
    N: np.ndarray,
    B0: np.ndarray,
    M: np.ndarray,
    cap: np.ndarray,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    c: np.ndarray,
    dd: np.ndarray,
    r: float,
    Qc: np.ndarray,
    foh: bool,
    phi2: np.ndarray,
    rtol: float,
    e_out: np.ndarray,
    groups: np.ndarray,
) -> tuple[float, int]:
    """``-log L`` without the ``0.5 n log 2 pi`` term, and the number of observations.

    Parameters
    ----------
    A0, N, B0, M : ndarray, shapes (2, 2), (nf, 2, 2), (2, p), (nf, 2, p)
        Bilinear state space (``A = A0 + sum m_f N_f``, ``B = B0 + sum m_f M_f``).
    cap : ndarray, shape (2,)
        Capacities; ``diag(cap) A0`` and every ``diag(cap) N_f`` must be symmetric (checked to
        :data:`rczone.simulation.discretize.SYMMETRY_RTOL`; otherwise ``(nan, -1)`` is returned).
    t : ndarray, shape (N,)
        Sample times, s.
    m : ndarray, shape (N, nf)
    u : ndarray, shape (N, p)
    y : ndarray, shape (N,)
        Measurements; NaN where missing.
    x0, P0 : ndarray, shapes (2,), (2, 2)
        Prior at the first sample.
    c, dd : ndarray, shapes (2,), (p,)
        Output row ``y = c' x + dd' u``.
    r : float
        Measurement-noise variance.
    Qc : ndarray, shape (2, 2)
        Process-noise intensity.
    foh : bool
    phi2 : ndarray
        Taylor coefficients for :func:`_phi2`.
    rtol : float
        Symmetry tolerance.
    e_out : ndarray, shape (N,) or (0,)
        Receives the innovations (one-step prediction errors) when it has one entry per
        sample; entries of missing samples are left as they are. With ``P0 = Qc = 0`` the
        filter never corrects the state, so these are the open-loop output errors.
    groups : ndarray of int64, shape (N - 1,) or (0,)
        Intervals with equal length and flows (:func:`interval_groups`): interval ``k``
        uses the matrices of group ``groups[k]``, computed at the group's first interval.
        Empty: discretize every interval whose length or flows differ from the previous one.
    """
    n_t = y.shape[0]
    keep = e_out.shape[0] == n_t
    nf = N.shape[0]
    p = B0.shape[1]
    if not (cap[0] > 0.0 and cap[1] > 0.0):
        return math.nan, -1
    for f in range(-1, nf):
        mat = A0 if f < 0 else N[f]
        big = 0.0
        for i in range(2):
            for j in range(2):
                big = max(big, abs(cap[i] * mat[i, j]))
        if abs(cap[0] * mat[0, 1] - cap[1] * mat[1, 0]) > rtol * big:
            return math.nan, -1
    s0 = math.sqrt(cap[0])
    s1 = math.sqrt(cap[1])
    is0 = 1.0 / s0
    is1 = 1.0 / s1
    r01 = s0 / s1
    ir01 = s1 / s0
    x = np.empty(2)
    P = np.empty((2, 2))
    for i in range(2):
        x[i] = x0[i]
        for j in range(2):
            P[i, j] = P0[i, j]
    # with groups, each group's matrices are computed at its first interval and kept;
    # without, one slot holds the current run of intervals with equal length and flows
    table = groups.shape[0] > 0
    n_slots = 1
    for k in range(groups.shape[0]):
        n_slots = max(n_slots, groups[k] + 1)
    Phi = np.empty((n_slots, 2, 2))
    Qd = np.empty((n_slots, 2, 2))
    G0 = np.empty((n_slots, 2, p))
    G1 = np.zeros((n_slots, 2, p))
    ready = np.zeros(n_slots, dtype=np.bool_)
    nll = 0.0
    n_obs = 0
    for k in range(n_t):
        if not math.isnan(y[k]):
            pc0 = P[0, 0] * c[0] + P[0, 1] * c[1]
            pc1 = P[1, 0] * c[0] + P[1, 1] * c[1]
            s = r + c[0] * pc0 + c[1] * pc1
            innov = y[k] - c[0] * x[0] - c[1] * x[1]
            for j in range(p):
                innov -= dd[j] * u[k, j]
            if keep:
                e_out[k] = innov
            inv_s = 1.0 / s
            k0 = pc0 * inv_s
            k1 = pc1 * inv_s
            x[0] += k0 * innov
            x[1] += k1 * innov
            # Joseph form (I - K c') P (I - K c')' + r K K', as the reference
            i00 = 1.0 - k0 * c[0]
            i01 = -k0 * c[1]
            i10 = -k1 * c[0]
            i11 = 1.0 - k1 * c[1]
            t00 = i00 * P[0, 0] + i01 * P[1, 0]
            t01 = i00 * P[0, 1] + i01 * P[1, 1]
            t10 = i10 * P[0, 0] + i11 * P[1, 0]
            t11 = i10 * P[0, 1] + i11 * P[1, 1]
            p00 = t00 * i00 + t01 * i01 + r * k0 * k0
            p01 = t00 * i10 + t01 * i11 + r * k0 * k1
            p11 = t10 * i10 + t11 * i11 + r * k1 * k1
            P[0, 0] = p00
            P[0, 1] = p01
            P[1, 0] = p01
            P[1, 1] = p11
            nll += 0.5 * (math.log(s) + innov * innov * inv_s)
            n_obs += 1
        if k == n_t - 1:
            break
        if table:
            g = groups[k]
            fresh = not ready[g]
            ready[g] = True
        else:
            g = 0
            fresh = k == 0 or t[k + 1] - t[k] != t[k] - t[k - 1]
            for f in range(nf):
                if k > 0 and m[k, f] != m[k - 1, f]:
                    fresh = True
        if fresh:
            kk = k
            h = t[k + 1] - t[k]
            a = A0[0, 0]
            a01 = A0[0, 1]
            a10 = A0[1, 0]
            d = A0[1, 1]
            for f in range(nf):
                mf = m[kk, f]
                a += mf * N[f, 0, 0]
                a01 += mf * N[f, 0, 1]
                a10 += mf * N[f, 1, 0]
                d += mf * N[f, 1, 1]
            # symmetric S = diag(s) A diag(s)^-1 and its Jacobi rotation [[cs, sn], [-sn, cs]]
            b = 0.5 * (a01 * r01 + a10 * ir01)
            if b == 0.0:
                tn = 0.0
            else:
                tau = (d - a) / (2.0 * b)
                at = abs(tau)
                # sqrt(1 + tau^2) without overflow for |tau| > 1e150
                root = at * math.sqrt(1.0 + (1.0 / at) ** 2) if at > 1e150 else math.sqrt(1.0 + at * at)
                tn = math.copysign(1.0, tau) / (at + root)
            cs = 1.0 / math.sqrt(1.0 + tn * tn)
            sn = tn * cs
            # T = diag(s)^-1 V, Ti = T^-1 = V' diag(s)
            T00, T01, T10, T11 = cs * is0, sn * is0, -sn * is1, cs * is1
            U00, U01, U10, U11 = cs * s0, -sn * s1, sn * s0, cs * s1
            x0_ = (a - tn * b) * h
            x1_ = (d + tn * b) * h
            # two expm1 per interval; e^{(l_i + l_j) h} - 1 = em1_i + em1_j + em1_i em1_j exactly;
            # e = em1 + 1 is accurate to eps absolutely, which is all Phi (|e| <= 1) needs
            em0 = math.expm1(x0_)
            em1_ = math.expm1(x1_)
            e0 = em0 + 1.0
            e1 = em1_ + 1.0
            # (e^x - 1)/x with one division per eigenvalue, reused below
            ix0 = 1.0 / x0_ if x0_ != 0.0 else 0.0
            ix1 = 1.0 / x1_ if x1_ != 0.0 else 0.0
            w10 = em0 * ix0 if x0_ != 0.0 else 1.0
            w11 = em1_ * ix1 if x1_ != 0.0 else 1.0
            if foh:
                w20 = _phi2(x0_, em0, phi2)
                w21 = _phi2(x1_, em1_, phi2)
                ga0, ga1 = (w10 - w20) * h, (w11 - w21) * h
                gb0, gb1 = w20 * h, w21 * h
            else:
                ga0, ga1 = w10 * h, w11 * h
                gb0, gb1 = 0.0, 0.0
            Phi[g, 0, 0] = T00 * e0 * U00 + T01 * e1 * U10
            Phi[g, 0, 1] = T00 * e0 * U01 + T01 * e1 * U11
            Phi[g, 1, 0] = T10 * e0 * U00 + T11 * e1 * U10
            Phi[g, 1, 1] = T10 * e0 * U01 + T11 * e1 * U11
            for j in range(p):
                bj0 = B0[0, j]
                bj1 = B0[1, j]
                for f in range(nf):
                    bj0 += m[kk, f] * M[f, 0, j]
                    bj1 += m[kk, f] * M[f, 1, j]
                z0 = U00 * bj0 + U01 * bj1
                z1 = U10 * bj0 + U11 * bj1
                G0[g, 0, j] = T00 * ga0 * z0 + T01 * ga1 * z1
                G0[g, 1, j] = T10 * ga0 * z0 + T11 * ga1 * z1
                if foh:
                    G1[g, 0, j] = T00 * gb0 * z0 + T01 * gb1 * z1
                    G1[g, 1, j] = T10 * gb0 * z0 + T11 * gb1 * z1
            # W = Ti Qc Ti' weighted by (e^{(l_i + l_j) h} - 1)/(l_i + l_j); Qd = T W T'
            y00 = U00 * Qc[0, 0] + U01 * Qc[1, 0]
            y01 = U00 * Qc[0, 1] + U01 * Qc[1, 1]
            y10 = U10 * Qc[0, 0] + U11 * Qc[1, 0]
            y11 = U10 * Qc[0, 1] + U11 * Qc[1, 1]
            W00 = (y00 * U00 + y01 * U01) * (w10 * (0.5 * em0 + 1.0)) * h
            W01 = (y00 * U10 + y01 * U11) * _ratio(x0_ + x1_, em0 + em1_ + em0 * em1_) * h
            W11 = (y10 * U10 + y11 * U11) * (w11 * (0.5 * em1_ + 1.0)) * h
            v00 = T00 * W00 + T01 * W01
            v01 = T00 * W01 + T01 * W11
            v10 = T10 * W00 + T11 * W01
            v11 = T10 * W01 + T11 * W11
            Qd[g, 0, 0] = v00 * T00 + v01 * T01
            q01 = v00 * T10 + v01 * T11
            Qd[g, 0, 1] = q01
            Qd[g, 1, 0] = q01
            Qd[g, 1, 1] = v10 * T10 + v11 * T11
        f00 = Phi[g, 0, 0]
        f01 = Phi[g, 0, 1]
        f10 = Phi[g, 1, 0]
        f11 = Phi[g, 1, 1]
        xn0 = f00 * x[0] + f01 * x[1]
        xn1 = f10 * x[0] + f11 * x[1]
        for j in range(p):
            xn0 += G0[g, 0, j] * u[k, j]
            xn1 += G0[g, 1, j] * u[k, j]
        if foh:
            for j in range(p):
                xn0 += G1[g, 0, j] * u[k + 1, j]
                xn1 += G1[g, 1, j] * u[k + 1, j]
        x[0] = xn0
        x[1] = xn1
        # P <- Phi P Phi' + Qd (symmetric)
        a0 = f00 * P[0, 0] + f01 * P[1, 0]
        a1 = f00 * P[0, 1] + f01 * P[1, 1]
        b0 = f10 * P[0, 0] + f11 * P[1, 0]
        b1 = f10 * P[0, 1] + f11 * P[1, 1]
        q01 = Qd[g, 0, 1] + a0 * f10 + a1 * f11
        P[0, 0] = Qd[g, 0, 0] + a0 * f00 + a1 * f01
        P[0, 1] = q01
        P[1, 0] = q01
        P[1, 1] = Qd[g, 1, 1] + b0 * f10 + b1 * f11
    return nll, n_obs


@njit(cache=True, error_model="numpy")
def nll_rc2_from_values(
    L: np.ndarray,
    P: np.ndarray,
    E: np.ndarray,
    Gb0: np.ndarray,
    Nf: np.ndarray,
    Mf: np.ndarray,
    res: np.ndarray,
    cap: np.ndarray,
    iout: int,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    P0: np.ndarray,
    Qc: np.ndarray,
    r: float,
    foh: bool,
    phi2: np.ndarray,
    rtol: float,
    e_out: np.ndarray,
    groups: np.ndarray,
) -> tuple[float, int]:
    """:func:`nll_rc2_kernel` straight from resistor values and capacities (no Python in between).

    Assembles ``A = -L' diag(1/res) L / cap``, ``B = (P' diag(1/res) E + Gb0) / cap``,
    ``N = Nf / cap``, ``M = Mf / cap`` (:attr:`rczone.network.RCNetwork.conductance_form`),
    starts the measured state ``iout`` at ``y[0]`` and the other in steady state given it (as
    :func:`rczone.estimation.costs.auto_initial_state`), and runs the filter. Output ``y =
    x[iout]``.
    """
    nres = L.shape[0]
    p = E.shape[1]
    nf = Nf.shape[0]
    A0 = np.zeros((2, 2))
    B0 = np.zeros((2, p))
    N = np.empty((nf, 2, 2))
    M = np.empty((nf, 2, p))
    for k in range(nres):
        g = 1.0 / res[k]
        for i in range(2):
            if L[k, i] != 0.0:
                for j in range(2):
                    A0[i, j] -= L[k, i] * g * L[k, j]
                for j in range(p):
                    B0[i, j] += P[k, i] * g * E[k, j]
    for i in range(2):
        for j in range(2):
            A0[i, j] /= cap[i]
        for j in range(p):
            B0[i, j] = (B0[i, j] + Gb0[i, j]) / cap[i]
        for f in range(nf):
            for j in range(2):
                N[f, i, j] = Nf[f, i, j] / cap[i]
            for j in range(p):
                M[f, i, j] = Mf[f, i, j] / cap[i]
    io = iout
    fo = 1 - iout
    x0 = np.empty(2)
    x0[io] = y[0]
    a_ff = A0[fo, fo]
    a_fi = A0[fo, io]
    for f in range(nf):
        a_ff += m[0, f] * N[f, fo, fo]
        a_fi += m[0, f] * N[f, fo, io]
    bu = 0.0
    for j in range(p):
        bj = B0[fo, j]
        for f in range(nf):
            bj += m[0, f] * M[f, fo, j]
        bu += bj * u[0, j]
    x0[fo] = -(bu + a_fi * y[0]) / a_ff
    c = np.zeros(2)
    c[io] = 1.0
    dd = np.zeros(p)
    return nll_rc2_kernel(A0, N, B0, M, cap, t, m, u, y, x0, P0, c, dd, r, Qc, foh, phi2, rtol, e_out, groups)


def kalman_nll_rc2_values(
    network,
    res: np.ndarray,
    cap: np.ndarray,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    P0: np.ndarray,
    Qc: np.ndarray,
    R: float,
    hold: str = "zoh",
    innovations: np.ndarray | None = None,
    groups: np.ndarray | None = None,
) -> float:
    """``-log L`` (with ``0.5 n log 2 pi``) from parameter values; see :func:`nll_rc2_from_values`.

    ``y`` is shape (N, 1) with a finite first sample; ``m`` (N, n_flows) and ``u`` (N, p) in
    the network's orders; contiguous float64 arrays are used as they are. ``groups`` is
    :func:`interval_groups` of ``(t, m)`` (discretize each distinct interval once).
    """
    form = network.conductance_form
    f = np.ascontiguousarray
    nll, n_obs = nll_rc2_from_values(
        form.L,
        form.P,
        form.E,
        form.Gb0,
        form.Nf,
        form.Mf,
        f(res, dtype=np.float64),
        f(cap, dtype=np.float64),
        form.output_state[0],
        f(t, dtype=np.float64),
        f(m, dtype=np.float64),
        f(u, dtype=np.float64),
        f(y[:, 0], dtype=np.float64),
        f(P0, dtype=np.float64),
        f(Qc, dtype=np.float64),
        float(R),
        hold == "foh",
        _PHI2,
        SYMMETRY_RTOL,
        np.empty(0) if innovations is None else innovations,
        _NO_GROUPS if groups is None else groups,
    )
    if n_obs < 0:
        raise InputShapeError("the network's state space is not symmetrizable; use the general filter")
    return float(nll + 0.5 * n_obs * _LOG_2PI)


def rc2_applicable(ss: BilinearStateSpace, n_outputs: int) -> bool:
    """Whether :func:`kalman_nll_rc2` handles this model: 2 states, one output, RC-symmetrizable."""
    if ss.n_states != 2 or n_outputs != 1:
        return False
    c = ss.capacities
    if c.shape == (2,) and c[0] > 0 and c[1] > 0:
        # quick scalar form of symmetrizing_scale for 2 states: c0 A01 == c1 A10, likewise for N
        mats = [ss.A, *ss.N]
        if all(
            abs(c[0] * a[0, 1] - c[1] * a[1, 0])
            <= SYMMETRY_RTOL * max(abs(c[0] * a[0, 1]), abs(c[1] * a[1, 0]))
            for a in mats
        ) and all(math.isfinite(x) for a in mats for x in a.flat):
            return True
    return symmetrizing_scale(ss.A, ss.N, ss.capacities) is not None


def kalman_nll_rc2(
    ss: BilinearStateSpace,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    Qc: np.ndarray,
    R: np.ndarray,
    hold: str = "zoh",
    innovations: np.ndarray | None = None,
    groups: np.ndarray | None = None,
) -> float:
    """``-log L`` (including ``0.5 n log 2 pi``) of a 2-state RC model, one output.

    Equal to ``kalman_nll(*stochastic_matrices(ss, t, m, Qc, hold), u, y, x0, P0, ss.C, ss.D, R)``
    of :mod:`rczone.estimation.kalman`, computed in one compiled pass.

    Parameters
    ----------
    ss : BilinearStateSpace
        Two states, symmetrizable (see :func:`rc2_applicable`).
    t : ndarray, shape (N,)
        Sample times, s, strictly increasing.
    m : ndarray, shape (N, n_flows)
    u : ndarray, shape (N, p)
    y : ndarray, shape (N, 1)
        Measurements; NaN where missing.
    x0 : ndarray, shape (2,)
    P0 : ndarray, shape (2, 2)
    Qc : ndarray, shape (2, 2)
        Process-noise intensity, K^2/s.
    R : ndarray, shape (1, 1)
        Measurement-noise variance, K^2.
    hold : {"zoh", "foh"}
    innovations : ndarray, shape (N,), optional
        Filled with the one-step prediction errors (missing samples untouched).
    groups : ndarray, optional
        :func:`interval_groups` of ``(t, m)``: discretize each distinct interval once.

    Returns
    -------
    float
    """
    if hold not in HOLDS:
        raise InputShapeError(f"hold must be one of {HOLDS}, got {hold!r}")
    if ss.n_states != 2:
        raise InputShapeError(
            f"kalman_nll_rc2 needs a 2-state RC model, got {ss.n_states} states;"
            " use rczone.estimation.kalman.kalman_nll instead"
        )
    y = np.asarray(y, dtype=np.float64)
    if y.ndim != 2 or y.shape[1] != 1 or ss.C.shape[0] != 1:
        raise InputShapeError(f"kalman_nll_rc2 needs one output, y of shape (N, 1); got {y.shape}")
    if innovations is not None and (
        innovations.shape != (y.shape[0],)
        or innovations.dtype != np.float64
        or not innovations.flags.c_contiguous
    ):
        raise InputShapeError(f"innovations must be a contiguous float64 array of shape ({y.shape[0]},)")
    f = np.ascontiguousarray
    # contiguous float64 everywhere: one compiled specialization serves every caller
    nll, n_obs = nll_rc2_kernel(
        f(ss.A, dtype=np.float64),
        f(ss.N, dtype=np.float64),
        f(ss.B, dtype=np.float64),
        f(ss.M, dtype=np.float64),
        f(ss.capacities, dtype=np.float64),
        f(t, dtype=np.float64),
        f(m, dtype=np.float64),
        f(u, dtype=np.float64),
        f(y[:, 0]),
        f(x0, dtype=np.float64),
        f(P0, dtype=np.float64),
        f(ss.C[0], dtype=np.float64),
        f(ss.D[0], dtype=np.float64),
        float(R[0, 0]),
        f(Qc, dtype=np.float64),
        hold == "foh",
        _PHI2,
        SYMMETRY_RTOL,
        np.empty(0) if innovations is None else innovations,
        _NO_GROUPS if groups is None else groups,
    )
    if n_obs < 0:
        raise InputShapeError(
            "kalman_nll_rc2 needs an RC model (diag(capacities) A and diag(capacities) N symmetric);"
            " use rczone.estimation.kalman.kalman_nll for other state spaces"
        )
    return float(nll + 0.5 * n_obs * _LOG_2PI)
