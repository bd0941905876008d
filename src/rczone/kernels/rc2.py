"""Fused likelihood of a 2-state RC model with one output: discretization and filter in one pass.

With the flow ``m`` changing at every sample, a likelihood evaluation of a small model is
dominated by the discretization (one ``Phi``, ``Gamma`` and ``Qd`` per sample), not by the
filter. For two states the discrete matrices have a closed form
(:func:`rczone.kernels.discretize.rc2_discretize`: one Jacobi rotation and two ``expm1``);
this kernel computes them for every interval whose length or flows differ from the previous
one (or once per group of equal intervals, :func:`rczone.simulation.intervals.interval_groups`)
in a first pass, then runs the filter recursion unrolled for two states in a second. It is
the general filter (:func:`rczone.kernels.kalman.kalman_filter`) specialized by hand: the
same sequential update and time update, the same steady-state rule, so the same ``-log L``
to rounding (tested against it); it is used only where it is measurably faster
(``docs/performance.md``), and never for gradients. :func:`filter_rc2` is the same recursion (without
the steady state) over given discrete matrices with every intermediate result kept (what the
prediction bands of a 2-state model read), a small kernel: a first fit does not compile the general filter.

References
----------
.. [1] H. Madsen, J. Holst, "Estimation of continuous-time models for the heat dynamics of a
   building", Energy and Buildings 22 (1995) 67-79.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rczone.kernels.arrays import Dynamics, FilterStart, FilterTrace, Moments2, Observation, Rc2Model, Series
from rczone.kernels.discretize import rc2_discretize


@njit(cache=True, error_model="numpy")
def symmetric_rc2(A0: np.ndarray, N: np.ndarray, cap: np.ndarray, rtol: float) -> bool:
    """Whether ``diag(cap) A0`` and every ``diag(cap) N_f`` are symmetric to ``rtol`` (capacities > 0)."""
    if not (cap[0] > 0.0 and cap[1] > 0.0 and cap[0] < math.inf and cap[1] < math.inf):
        return False
    for f in range(-1, N.shape[0]):
        mat = A0 if f < 0 else N[f]
        big = 0.0
        for i in range(2):
            for j in range(2):
                v = cap[i] * mat[i, j]
                if not abs(v) < math.inf:
                    return False
                big = max(big, abs(v))
        if abs(cap[0] * mat[0, 1] - cap[1] * mat[1, 0]) > rtol * big:
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def flow_matrix(A0: np.ndarray, N: np.ndarray, m: np.ndarray, k: int) -> tuple[float, float, float, float]:
    """``A = A0 + sum_f m[k, f] N_f`` of a 2-state model as ``(a00, a01, a10, a11)``."""
    a, a01, a10, d = A0[0, 0], A0[0, 1], A0[1, 0], A0[1, 1]
    for f in range(N.shape[0]):
        mf = m[k, f]
        a += mf * N[f, 0, 0]
        a01 += mf * N[f, 0, 1]
        a10 += mf * N[f, 1, 0]
        d += mf * N[f, 1, 1]
    return a, a01, a10, d


@njit(cache=True, error_model="numpy", inline="always")
def flow_column(B0: np.ndarray, M: np.ndarray, m: np.ndarray, k: int, j: int) -> tuple[float, float]:
    """Column ``j`` of ``B = B0 + sum_f m[k, f] M_f`` of a 2-state model."""
    b0 = B0[0, j]
    b1 = B0[1, j]
    for f in range(M.shape[0]):
        b0 += m[k, f] * M[f, 0, j]
        b1 += m[k, f] * M[f, 1, j]
    return b0, b1


@njit(cache=True, error_model="numpy", inline="always")
def correct_rc2(m: Moments2, g0: float, g1: float, e: float, inv: float) -> Moments2:
    """The scalar measurement update of a 2-state filter: ``x += g e/s``, ``P -= g g'/s`` (``g = Pc``,
    ``inv = 1/s``)."""
    return Moments2(
        m.x0 + g0 * e * inv,
        m.x1 + g1 * e * inv,
        m.p00 - g0 * g0 * inv,
        m.p01 - g0 * g1 * inv,
        m.p11 - g1 * g1 * inv,
    )


@njit(cache=True, error_model="numpy", inline="always")
def predict_rc2(dyn: Dynamics, w: int, u: np.ndarray, k: int, foh: bool, m: Moments2) -> Moments2:
    """The time update of a 2-state filter over interval ``w``: ``x = Phi x + G0 u_k (+ G1 u_k+1)``,
    ``P = Phi P Phi' + Qd``."""
    Phi, G0, G1, Qd = dyn
    n0 = Phi[w, 0, 0] * m.x0 + Phi[w, 0, 1] * m.x1
    n1 = Phi[w, 1, 0] * m.x0 + Phi[w, 1, 1] * m.x1
    for j in range(u.shape[1]):
        n0 += G0[w, 0, j] * u[k, j]
        n1 += G0[w, 1, j] * u[k, j]
        if foh:
            n0 += G1[w, 0, j] * u[k + 1, j]
            n1 += G1[w, 1, j] * u[k + 1, j]
    f00, f01, f10, f11 = Phi[w, 0, 0], Phi[w, 0, 1], Phi[w, 1, 0], Phi[w, 1, 1]
    a0 = f00 * m.p00 + f01 * m.p01
    a1 = f00 * m.p01 + f01 * m.p11
    b0 = f10 * m.p00 + f11 * m.p01
    b1 = f10 * m.p01 + f11 * m.p11
    return Moments2(
        n0,
        n1,
        Qd[w, 0, 0] + a0 * f00 + a1 * f01,
        0.5 * (Qd[w, 0, 1] + Qd[w, 1, 0]) + a0 * f10 + a1 * f11,
        Qd[w, 1, 1] + b0 * f10 + b1 * f11,
    )


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def nll_rc2(
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
    qc: np.ndarray,
    foh: bool,
    rtol: float,
    steady_rtol: float,
    e_out: np.ndarray,
    groups: np.ndarray,
) -> tuple[float, int]:
    """``-log L`` without the ``0.5 n log 2 pi`` term, and the number of observations.

    Parameters
    ----------
    A0, N, B0, M : ndarray, shapes (2, 2), (nf, 2, 2), (2, p), (nf, 2, p)
        Bilinear state space (``A = A0 + sum m_f N_f``, ``B = B0 + sum m_f M_f``).
    cap : ndarray, shape (2,)
        Capacities; ``diag(cap) A0`` and every ``diag(cap) N_f`` must be symmetric to ``rtol``
        (:func:`symmetric_rc2`; otherwise ``(nan, -1)`` is returned; ``(nan, -2)`` for an
        innovation variance that is not positive).
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
    qc : ndarray, shape (2,)
        Process-noise intensities of the two states.
    foh : bool
    rtol, steady_rtol : float
        Symmetry tolerance; relative tolerance of the steady state
        (:data:`rczone.kernels.kalman.STEADY_RTOL`, 0 disables it).
    e_out : ndarray, shape (N,) or (0,)
        Receives the innovations when it has one entry per sample; entries of missing samples
        are left as they are. With ``P0 = qc = 0`` the gain is zero, so these are the
        open-loop output errors.
    groups : ndarray of int64, shape (N - 1,) or (0,)
        Intervals with equal length and flows: interval ``k`` uses the matrices of group
        ``groups[k]``, computed at the group's first interval. Empty: discretize every
        interval whose length or flows differ from the previous one.
    """
    n_t = y.shape[0]
    keep = e_out.shape[0] == n_t
    nf = N.shape[0]
    p = B0.shape[1]
    if not symmetric_rc2(A0, N, cap, rtol):
        return math.nan, -1
    s0 = math.sqrt(cap[0])
    s1 = math.sqrt(cap[1])
    is0 = 1.0 / s0
    is1 = 1.0 / s1
    # pass 1: the slot of each interval (its group, or its run of equal intervals) and the
    # discrete matrices of each slot, computed at its first interval
    n_int = max(n_t - 1, 0)
    slot = np.empty(n_int, dtype=np.int64)
    n_slots = 0
    if groups.shape[0] > 0:
        for k in range(n_int):
            slot[k] = groups[k]
            n_slots = max(n_slots, groups[k] + 1)
    else:
        for k in range(n_int):
            fresh = k == 0 or t[k + 1] - t[k] != t[k] - t[k - 1]
            for f in range(nf):
                fresh = fresh or m[k, f] != m[k - 1, f]
            if fresh:
                n_slots += 1
            slot[k] = n_slots - 1
    Phi = np.empty((max(n_slots, 1), 4))
    Qd = np.empty((max(n_slots, 1), 3))
    G0 = np.zeros((max(n_slots, 1), 2, p))
    G1 = np.zeros((max(n_slots, 1), 2, p))
    ready = np.zeros(max(n_slots, 1), dtype=np.bool_)
    for k in range(n_int):
        g = slot[k]
        if ready[g]:
            continue
        ready[g] = True
        a, a01, a10, d = flow_matrix(A0, N, m, k)
        mt = rc2_discretize(Rc2Model(a, a01, a10, d, s0, s1, is0, is1), t[k + 1] - t[k], qc[0], qc[1], foh)
        Phi[g, 0], Phi[g, 1], Phi[g, 2], Phi[g, 3] = mt.phi00, mt.phi01, mt.phi10, mt.phi11
        Qd[g, 0], Qd[g, 1], Qd[g, 2] = mt.qd00, mt.qd01, mt.qd11
        for j in range(p):
            # B(m) = B0 + sum m_f M_f, column j
            b0, b1 = flow_column(B0, M, m, k, j)
            G0[g, 0, j] = mt.h0_00 * b0 + mt.h0_01 * b1
            G0[g, 1, j] = mt.h0_10 * b0 + mt.h0_11 * b1
            if foh:
                G1[g, 0, j] = mt.h1_00 * b0 + mt.h1_01 * b1
                G1[g, 1, j] = mt.h1_10 * b0 + mt.h1_11 * b1
    has_dd = False
    for j in range(p):
        has_dd = has_dd or dd[j] != 0.0
    # pass 2: the filter (the sequential update and time update of rczone.kernels.kalman, unrolled)
    c0, c1 = c[0], c[1]
    x0_, x1_ = x0[0], x0[1]
    p00, p01, p11 = P0[0, 0], 0.5 * (P0[0, 1] + P0[1, 0]), P0[1, 1]
    n_obs = 0
    steady = False
    steady_slot = -1
    steady_obs = False
    prev_slot = -1
    prev_obs = False
    k0 = k1 = s = inv_s = 0.0
    log_sum = 0.0  # sum of log s over the updates before the steady state(s) ...
    prod = 1.0  # ... with the product not yet logged
    n_steady = 0  # updates in a steady state (each with the s of the steady state it is in)
    sq_sum = 0.0  # sum e^2 / s
    pp00 = pp01 = pp11 = 0.0  # predicted covariance of the previous sample
    pf00 = pf01 = pf11 = 0.0  # filtered covariance (to leave the steady state from)
    for k in range(n_t):
        yk = y[k]
        obs = yk == yk
        if steady and obs != steady_obs:
            steady = False
            log_sum += n_steady * math.log(s) if n_steady else 0.0
            n_steady = 0
        if not steady:
            pp00, pp01, pp11 = p00, p01, p11
        if obs:
            innov = yk - c0 * x0_ - c1 * x1_
            if has_dd:
                for j in range(p):
                    innov -= dd[j] * u[k, j]
            if keep:
                e_out[k] = innov
            if not steady:
                pc0 = p00 * c0 + p01 * c1
                pc1 = p01 * c0 + p11 * c1
                s = r + c0 * pc0 + c1 * pc1
                if not s > 0.0:
                    return math.nan, -2
                inv_s = 1.0 / s
                k0 = pc0 * inv_s
                k1 = pc1 * inv_s
                p00 -= k0 * pc0
                p01 -= k0 * pc1
                p11 -= k1 * pc1
                # sum log s as the log of a running product (one log per ~dozens of samples)
                if 1e-100 < s < 1e100:
                    prod *= s
                    if not 1e-200 < prod < 1e200:
                        log_sum += math.log(prod)
                        prod = 1.0
                else:
                    log_sum += math.log(s)
            else:
                n_steady += 1
            x0_ += k0 * innov
            x1_ += k1 * innov
            sq_sum += innov * innov * inv_s
            n_obs += 1
        if not steady:
            pf00, pf01, pf11 = p00, p01, p11
        if k == n_t - 1:
            break
        g = slot[k]
        f00, f01, f10, f11 = Phi[g, 0], Phi[g, 1], Phi[g, 2], Phi[g, 3]
        xn0 = f00 * x0_ + f01 * x1_
        xn1 = f10 * x0_ + f11 * x1_
        for j in range(p):
            xn0 += G0[g, 0, j] * u[k, j]
            xn1 += G0[g, 1, j] * u[k, j]
        if foh:
            for j in range(p):
                xn0 += G1[g, 0, j] * u[k + 1, j]
                xn1 += G1[g, 1, j] * u[k + 1, j]
        x0_ = xn0
        x1_ = xn1
        if steady and g != steady_slot:
            steady = False
            log_sum += n_steady * math.log(s) if n_steady else 0.0
            n_steady = 0
            p00, p01, p11 = pf00, pf01, pf11
        if not steady:
            # P <- Phi P Phi' + Qd
            a0 = f00 * p00 + f01 * p01
            a1 = f00 * p01 + f01 * p11
            b0 = f10 * p00 + f11 * p01
            b1 = f10 * p01 + f11 * p11
            p00 = Qd[g, 0] + a0 * f00 + a1 * f01
            p01 = Qd[g, 1] + a0 * f10 + a1 * f11
            p11 = Qd[g, 2] + b0 * f10 + b1 * f11
            if steady_rtol > 0.0 and g == prev_slot and obs == prev_obs:
                big = max(abs(p00), abs(p01), abs(p11))
                diff = max(abs(p00 - pp00), abs(p01 - pp01), abs(p11 - pp11))
                if diff <= steady_rtol * big:
                    steady = True
                    steady_slot = g
                    steady_obs = obs
        prev_slot = g
        prev_obs = obs
    if n_steady:
        log_sum += n_steady * math.log(s)
    return 0.5 * (log_sum + math.log(prod) + sq_sum), n_obs


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def simulate_rc2(
    A0: np.ndarray,
    N: np.ndarray,
    B0: np.ndarray,
    M: np.ndarray,
    cap: np.ndarray,
    C: np.ndarray,
    D: np.ndarray,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    x0: np.ndarray,
    foh: bool,
    rtol: float,
    x: np.ndarray,
    y: np.ndarray,
) -> int:
    """Exact simulation of a 2-state RC model, checks of the inputs included; ``0`` when done.

    The discrete matrices (:func:`rczone.kernels.discretize.rc2_discretize`) are computed at
    each interval whose length or flows differ from the previous one, as in :func:`nll_rc2`,
    so a regularly sampled LTI model is discretized once. Nothing is computed for inputs that
    the public checks would refuse: the caller then runs them for their message.

    Parameters
    ----------
    A0, N, B0, M, cap
        As :func:`nll_rc2`.
    C, D : ndarray, shapes (ny, 2), (ny, p)
        Output equation.
    t, m, u : ndarray, shapes (N,), (N, nf), (N, p)
    x0 : ndarray, shape (2,) or (0,)
        Initial state; empty: the steady state at the first inputs and flows.
    foh : bool
    rtol : float
        Symmetry tolerance of :func:`symmetric_rc2`.
    x, y : ndarray, shapes (N, 2), (N, ny)
        Receive the states and outputs.

    Returns
    -------
    int
        ``0`` done; ``1`` times not finite or not increasing, or inputs or flows not finite;
        ``2`` not a symmetric 2-state RC model; ``3`` a singular steady state.
    """
    n_t = t.shape[0]
    nf = N.shape[0]
    p = B0.shape[1]
    for k in range(n_t):
        if not abs(t[k]) < math.inf or (k > 0 and not t[k] > t[k - 1]):
            return 1
        for j in range(p):
            if not abs(u[k, j]) < math.inf:
                return 1
        for f in range(nf):
            if not abs(m[k, f]) < math.inf:
                return 1
    if not symmetric_rc2(A0, N, cap, rtol):
        return 2
    s0 = math.sqrt(cap[0])
    s1 = math.sqrt(cap[1])
    is0 = 1.0 / s0
    is1 = 1.0 / s1
    if x0.shape[0] == 2:
        x[0, 0], x[0, 1] = x0[0], x0[1]
    else:
        # steady state: A(m0) x = -B(m0) u0
        a, a01, a10, d = flow_matrix(A0, N, m, 0)
        r0 = r1 = 0.0
        for j in range(p):
            b0, b1 = flow_column(B0, M, m, 0, j)
            r0 -= b0 * u[0, j]
            r1 -= b1 * u[0, j]
        det = a * d - a01 * a10
        if not (det != 0.0 and abs(det) < math.inf):
            return 3
        x[0, 0] = (r0 * d - a01 * r1) / det
        x[0, 1] = (a * r1 - a10 * r0) / det
    G0 = np.zeros((2, p))
    G1 = np.zeros((2, p))
    f00 = f01 = f10 = f11 = 0.0
    for k in range(n_t - 1):
        fresh = k == 0 or t[k + 1] - t[k] != t[k] - t[k - 1]
        for f in range(nf):
            fresh = fresh or m[k, f] != m[k - 1, f]
        if fresh:
            a, a01, a10, d = flow_matrix(A0, N, m, k)
            mt = rc2_discretize(Rc2Model(a, a01, a10, d, s0, s1, is0, is1), t[k + 1] - t[k], 0.0, 0.0, foh)
            f00, f01, f10, f11 = mt.phi00, mt.phi01, mt.phi10, mt.phi11
            for j in range(p):
                b0, b1 = flow_column(B0, M, m, k, j)
                G0[0, j] = mt.h0_00 * b0 + mt.h0_01 * b1
                G0[1, j] = mt.h0_10 * b0 + mt.h0_11 * b1
                G1[0, j] = mt.h1_00 * b0 + mt.h1_01 * b1
                G1[1, j] = mt.h1_10 * b0 + mt.h1_11 * b1
        xn0 = f00 * x[k, 0] + f01 * x[k, 1]
        xn1 = f10 * x[k, 0] + f11 * x[k, 1]
        for j in range(p):
            xn0 += G0[0, j] * u[k, j]
            xn1 += G0[1, j] * u[k, j]
        if foh:
            for j in range(p):
                xn0 += G1[0, j] * u[k + 1, j]
                xn1 += G1[1, j] * u[k + 1, j]
        x[k + 1, 0] = xn0
        x[k + 1, 1] = xn1
    for k in range(n_t):
        for i in range(C.shape[0]):
            v = C[i, 0] * x[k, 0] + C[i, 1] * x[k, 1]
            for j in range(p):
                v += D[i, j] * u[k, j]
            y[k, i] = v
    return 0


@njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})
def filter_rc2(
    dyn: Dynamics, obs: Observation, prior: FilterStart, series: Series, foh: bool, trace: FilterTrace
) -> tuple[float, int]:
    """The Kalman filter of a 2-state, 1-output model over given discrete matrices, every intermediate result kept.

    The general filter (:func:`rczone.kernels.kalman.kalman_filter` without derivatives and with
    a full trace) unrolled for two states and one output, as the forward pass of
    :func:`rczone.kernels.adjoint.nll_rc2_adjoint`: the same measurement update ``s = c'Pc + r``,
    ``g = Pc``, ``x += g e/s``, ``P -= g g'/s`` and time update ``x = Phi x + G0 u_k (+ G1
    u_k+1)``, ``P = Phi P Phi' + Qd`` [1]_. It runs the recursion to the end (no steady state),
    so its results equal the general filter's within that filter's steady-state tolerance. A
    small kernel of its own: what a 2-state model's prediction bands need costs a second of
    compilation instead of the general filter's twenty (``docs/performance.md``).

    Parameters
    ----------
    dyn : Dynamics
        ``Phi, G0, G1, Qd`` of each distinct interval, shapes (K, 2, 2), (K, 2, p), (K, 2, p), (K, 2, 2).
    obs : Observation
        ``C`` (1, 2), ``D`` (1, p), ``r`` (1,); the derivatives are not read.
    prior : FilterStart
        Mean (2,) and covariance (2, 2) of the state at the first sample; the derivatives are not read.
    series : Series
        Inputs (N, p), outputs (N, 1) (NaN where missing), the interval of each step (N - 1,).
    foh : bool
        First-order hold of the inputs.
    trace : FilterTrace
        Receives, each with N rows: the innovations ``e`` (N, 1) (left as they are where ``y`` is
        missing), predicted states ``xp`` (N, 2), filtered states ``xf`` (N, 2), predicted
        covariances ``Pp`` (N, 2, 2), innovation variances ``S`` (N, 1, 1) (also where ``y`` is
        missing), filtered covariances ``Pf`` (N, 2, 2); ``de`` is not written.

    Returns
    -------
    nll : float
        ``sum 0.5 (log s + e^2/s)`` over the observed samples (without ``0.5 n log 2 pi``); NaN
        for a non-positive innovation variance.
    n_obs : int
        Observed samples; -1 for an invalid model.

    References
    ----------
    .. [1] H. Madsen, *Time Series Analysis*, Chapman & Hall/CRC, 2007, section 10.3 (the Kalman filter).
    """
    u, y, which = series
    c0, c1, r = obs.C[0, 0], obs.C[0, 1], obs.r[0]
    n_t = y.shape[0]
    p = u.shape[1]
    x_0, x_1 = prior.x0[0], prior.x0[1]
    p00, p01, p11 = prior.P0[0, 0], 0.5 * (prior.P0[0, 1] + prior.P0[1, 0]), prior.P0[1, 1]
    nll = 0.0
    n_obs = 0
    for k in range(n_t):
        trace.xp[k, 0], trace.xp[k, 1] = x_0, x_1
        trace.Pp[k, 0, 0], trace.Pp[k, 0, 1], trace.Pp[k, 1, 0], trace.Pp[k, 1, 1] = p00, p01, p01, p11
        g0 = p00 * c0 + p01 * c1
        g1 = p01 * c0 + p11 * c1
        s = r + c0 * g0 + c1 * g1
        trace.S[k, 0, 0] = s
        yk = y[k, 0]
        if yk == yk:
            e = yk - c0 * x_0 - c1 * x_1
            for j in range(p):
                e -= obs.D[0, j] * u[k, j]
            if not s > 0.0:
                return math.nan, -1
            inv = 1.0 / s
            m = correct_rc2(Moments2(x_0, x_1, p00, p01, p11), g0, g1, e, inv)
            x_0, x_1, p00, p01, p11 = m.x0, m.x1, m.p00, m.p01, m.p11
            nll += 0.5 * (math.log(s) + e * e * inv)
            n_obs += 1
            trace.e[k, 0] = e
        trace.xf[k, 0], trace.xf[k, 1] = x_0, x_1
        trace.Pf[k, 0, 0], trace.Pf[k, 0, 1], trace.Pf[k, 1, 0], trace.Pf[k, 1, 1] = p00, p01, p01, p11
        if k == n_t - 1:
            break
        m = predict_rc2(dyn, which[k], u, k, foh, Moments2(x_0, x_1, p00, p01, p11))
        x_0, x_1, p00, p01, p11 = m.x0, m.x1, m.p00, m.p01, m.p11
    return nll, n_obs
