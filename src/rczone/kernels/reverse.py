"""The gradient of the general filter's likelihood by one reverse pass: a few likelihoods, whatever the parameters.

Forward sensitivities (:func:`rczone.kernels.kalman.kalman_filter` with derivatives) carry ``dx``
and ``dP`` along each of ``q`` parameter directions through every sample, about ``2.5 n^3`` per
direction and sample. Reverse mode [1]_ runs the filter of :func:`rczone.kernels.kalman.kalman_filter`
once (the same steps: sequential scalar updates of the observed outputs [2]_, missing outputs
skipped, the steady-state shortcut), keeps what the backward steps need, then runs the steps
backward with the adjoints ``a = dJ/dx`` and ``A = dJ/dP`` (kept symmetric: every use of ``P`` is
a symmetric function of it). It returns **matrix cotangents**: ``dJ/dPhi``, ``dJ/dG0``, ``dJ/dG1``
and ``dJ/dQd`` of each distinct interval, ``dJ/dr`` per output, ``dJ/dx0`` and ``dJ/dP0``.
:func:`contract` turns them into the gradient in the parameters with the derivatives of those few
matrices (:func:`rczone.kernels.discretize.rc_interval_derivatives`, once per distinct interval,
not per sample) and of the prior and noise. The backward pass costs about ``2.5 n^3`` per sample
before the steady state and ``O(n^2)`` after it, once for all parameters.

Backward steps (adjoints of matrix products as in Giles [3]_):

* scalar update of output ``o`` (``c = C[o]``, ``g = P c``, ``s = c'g + r``, ``e = y - c'x - d'u``,
  ``x+ = x + g e/s``, ``P+ = P - g g'/s``, the term ``0.5 (log s + e^2/s)``), given ``(b, B)`` of
  ``(x+, P+)``: ``e_bar = (e + b'g)/s``, ``s_bar = 0.5/s - 0.5 e^2/s^2 - (b'g) e/s^2 + g'Bg/s^2``,
  ``g_bar = b e/s - 2 B g/s``; then ``x_bar = b - e_bar c``, ``P_bar = B + sym(g_bar c') + s_bar c c'``
  and ``r_bar += s_bar``;
* time step ``x- = Phi x+ + G0 u_k + G1 u_k+1``, ``P- = Phi P+ Phi' + Qd`` with ``(a, A)`` of its
  results: ``b = Phi' a``, ``B = Phi' A Phi``; ``Phi_bar += a x+' + 2 A Phi P+``, ``G0_bar += a u_k'``,
  ``G1_bar += a u_k+1'``, ``Qd_bar += A``.

The steady state is differentiated as the filter computes it: once the predicted covariance after
sample ``f`` repeats (``steady_rtol``), the samples of the stretch use the gains ``k_o = g_o/s_o``
and variances ``s_o`` of sample ``f`` and never touch the covariance. Backward, a stretch
accumulates the adjoints of those frozen gains and variances (``k_bar += b e``,
``s_bar += 0.5/s - 0.5 e^2/s^2``), which join sample ``f``'s update (``g_bar += k_bar/s``,
``s_bar -= k_bar'g/s^2``). Where the stretch ends, the filter goes on from a covariance computed at
sample ``f``: the prediction after ``f`` when only the observed outputs change, the filtered
covariance of ``f`` when the interval changes; the adjoint of that covariance is held across the
stretch and added there. Everything else is the recursion's own chain rule, so the gradient is the
exact derivative of the computed likelihood.

References
----------
.. [1] A. Griewank, A. Walther, *Evaluating Derivatives: Principles and Techniques of
   Algorithmic Differentiation*, 2nd ed., SIAM, 2008, chapter 3 (the reverse mode).
.. [2] J. Durbin, S. J. Koopman, *Time Series Analysis by State Space Methods*, 2nd ed.,
   Oxford University Press, 2012, section 6.4 (univariate treatment of multivariate series).
.. [3] M. B. Giles, "Collected matrix derivative results for forward and reverse mode
   algorithmic differentiation", in *Advances in Automatic Differentiation*, Springer, 2008,
   pp. 35-44 (adjoints of matrix products).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from rczone.kernels.arrays import (
    AssembledDerivatives,
    Dynamics,
    DynamicsDerivatives,
    FilterOptions,
    FilterStart,
    Observation,
    Series,
)
from rczone.kernels.kalman import (
    FAST,
    advance,
    correct,
    drive,
    innovation,
    phi_times,
    stationary,
    times_phi_plus,
)


class Adjoints(NamedTuple):
    """The adjoints (derivatives of ``-log L``) of the filter's inputs, zeroed by the caller."""

    Phi: np.ndarray  #: (K, n, n)
    G0: np.ndarray  #: (K, n, p)
    G1: np.ndarray  #: (K, n, p)
    Qd: np.ndarray  #: (K, n, n)
    x0: np.ndarray  #: (n,)
    P0: np.ndarray  #: (n, n)
    r: np.ndarray  #: (ny,)


@njit(cache=True, error_model="numpy")
def zero_adjoints(K: int, n: int, p: int, ny: int) -> Adjoints:
    """:class:`Adjoints` of zeros for ``K`` intervals, ``n`` states, ``p`` inputs and ``ny`` outputs."""
    return Adjoints(
        np.zeros((K, n, n)),
        np.zeros((K, n, p)),
        np.zeros((K, n, p)),
        np.zeros((K, n, n)),
        np.zeros(n),
        np.zeros((n, n)),
        np.zeros(ny),
    )


class _Tape(NamedTuple):
    """What the forward pass keeps for the backward one."""

    xf: np.ndarray  #: (N, n) filtered state after the updates of each sample
    g: np.ndarray  #: (N, ny, n) ``P c`` of each update computed in full
    es: np.ndarray  #: (N, 2 ny) innovation and its variance of each observed output
    T: np.ndarray  #: (N, n, n) ``Phi P+`` of each time step that predicts the covariance


#: Steps of the forward pass, recorded per sample ``k`` (bit flags of ``flags[k]``).
_COV = 1  # the time step after k predicts the covariance
_RESTORED = 2  # ... from the filtered covariance of the stretch's first sample (the interval changed)
_FROZE = 4  # ... and the covariance is stationary from there on (k is a stretch's first sample)


@njit(cache=True, error_model="numpy", fastmath=FAST)
def nll_reverse(
    dyn: Dynamics, obs: Observation, prior: FilterStart, series: Series, opts: FilterOptions, bars: Adjoints
) -> tuple[float, int, int]:
    """``-log L`` (without ``0.5 n log 2 pi``) of the general filter and the adjoints of its inputs.

    Parameters
    ----------
    dyn : Dynamics
        Discrete matrices of each distinct interval.
    obs : Observation
        Output matrices and measurement variances; its derivatives are not used (``C`` and ``D``
        get no adjoints).
    prior : FilterStart
        Mean and covariance at the first sample; its derivatives are not used.
    series : Series
        Inputs, outputs (NaN where missing) and the interval of each step.
    opts : FilterOptions
        ``open_loop`` must be False (least squares keeps the forward sensitivities).
    bars : Adjoints
        Zeroed by the caller (:func:`zero_adjoints`); receives ``dJ/dPhi``, ``dJ/dG0``, ``dJ/dG1``,
        ``dJ/dQd`` per interval, ``dJ/dx0``, ``dJ/dP0`` and ``dJ/dr`` per output.

    Returns
    -------
    nll : float
        As :func:`rczone.kernels.kalman.kalman_filter` computes it without derivatives (the same
        steps and steady state); NaN for a non-positive innovation variance.
    n_obs : int
        Observed scalars; -1 for an invalid model.
    n_steady : int
        Samples whose updates used the frozen gains of a steady state.
    """
    Phi, G0, G1, Qd = dyn
    C, D, r = obs.C, obs.D, obs.r
    u, y, which = series
    foh, steady_rtol = opts.foh, opts.steady_rtol
    N, ny = y.shape
    n = prior.x0.shape[0]
    tape = _Tape(np.empty((N, n)), np.empty((N, ny, n)), np.empty((N, 2 * ny)), np.empty((N, n, n)))
    flags = np.zeros(N, dtype=np.int64)
    src = np.full(N, -1, dtype=np.int64)  # a steady sample: the stretch's first sample, whose gains it uses
    x = prior.x0.copy()
    P = prior.P0.copy()
    pc = np.empty(n)
    xn = np.empty(n)
    kg = np.zeros((ny, n))
    sg = np.ones(ny)
    lg = np.zeros(ny)
    P_prev = np.empty((n, n))
    P_filt = np.empty((n, n))
    no_dP = np.empty((0, n, n))
    steady = False
    steady_key = -1
    steady_mask = -1
    prev_key = -1
    prev_mask = -1
    first = -1
    nll = 0.0
    n_obs = 0
    n_steady = 0
    for k in range(N):
        mask = 0
        for j in range(ny):
            if y[k, j] == y[k, j]:
                mask |= 1 << j
        if steady and mask != steady_mask:
            steady = False
        if steady:
            src[k] = first
            n_steady += 1
        else:
            for i in range(n):
                for j in range(n):
                    P_prev[i, j] = P[i, j]
        for o in range(ny):
            if not mask & (1 << o):
                continue
            e = innovation(k, o, y, u, D, C, x)
            if not steady:
                # the scalar update of kalman_filter (written in place there too: as a call it costs)
                s = r[o]
                for i in range(n):
                    acc = 0.0
                    for j in range(n):
                        acc += P[i, j] * C[o, j]
                    pc[i] = acc
                    s += C[o, i] * acc
                if not s > 0.0:
                    return math.nan, -1, 0
                inv = 1.0 / s
                for i in range(n):
                    kg[o, i] = pc[i] * inv
                    tape.g[k, o, i] = pc[i]
                for i in range(n):
                    ki = kg[o, i]
                    for j in range(i, n):
                        v = P[i, j] - ki * pc[j]
                        P[i, j] = v
                        P[j, i] = v
                sg[o] = s
                lg[o] = math.log(s)
            s = sg[o]
            correct(o, e, kg, x)
            inv = 1.0 / s
            nll += 0.5 * (lg[o] + e * e * inv)
            n_obs += 1
            tape.es[k, 2 * o] = e
            tape.es[k, 2 * o + 1] = s
        if not steady:
            for i in range(n):
                for j in range(n):
                    P_filt[i, j] = P[i, j]
        for i in range(n):
            tape.xf[k, i] = x[i]
        if k == N - 1:
            break
        w = which[k]
        drive(w, k, G0, G1, u, foh, xn)
        advance(w, Phi, x, xn)
        if steady and w != steady_key:
            # leave the steady state from the filtered covariance of the stretch's first sample
            steady = False
            flags[k] |= _RESTORED
            for i in range(n):
                for j in range(n):
                    P[i, j] = P_filt[i, j]
        if steady:
            prev_key = w
            prev_mask = mask
            continue
        # P = Phi P Phi' + Qd, keeping T = Phi P
        flags[k] |= _COV
        T = tape.T[k]
        phi_times(w, Phi, P, T)
        times_phi_plus(w, T, Phi, Qd, P)
        if steady_rtol > 0.0 and w == prev_key and mask == prev_mask:
            steady = stationary(P, no_dP, P_prev, no_dP, steady_rtol)
            if steady:
                steady_key = w
                steady_mask = mask
                first = k
                flags[k] |= _FROZE
        prev_key = w
        prev_mask = mask
    _backward(dyn, obs, series, foh, tape, flags, src, bars)
    return nll, n_obs, n_steady


@njit(error_model="numpy", fastmath=FAST, inline="always")
def _backward(
    dyn: Dynamics, obs: Observation, series: Series, foh: bool, tape: _Tape, flags, src, bars: Adjoints
) -> None:
    """The backward pass of :func:`nll_reverse` over its tape (see the module's notes)."""
    Phi = dyn.Phi
    C = obs.C
    u, y, which = series
    N, ny = y.shape
    n = C.shape[1]
    p = u.shape[1]
    a = np.zeros(n)  # adjoint of the predicted state of the sample after the current one
    b = np.zeros(n)
    A = np.zeros((n, n))  # adjoint of the predicted covariance of the sample after the current one
    B = np.zeros((n, n))
    M = np.empty((n, n))
    held_pred = np.zeros((n, n))  # adjoint of the prediction after a stretch's first sample
    held_filt = np.zeros((n, n))  # adjoint of the filtered covariance of a stretch's first sample
    kbar = np.zeros((ny, n))  # adjoints of a stretch's frozen gains and variances
    sbar = np.zeros(ny)
    Bg = np.empty(n)
    gbar = np.empty(n)
    for k in range(N - 1, -1, -1):
        for i in range(n):
            for j in range(n):
                B[i, j] = 0.0
        if k < N - 1:
            w = which[k]
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += Phi[w, j, i] * a[j]
                    bars.Phi[w, i, j] += a[i] * tape.xf[k, j]
                b[i] = acc
                for j in range(p):
                    bars.G0[w, i, j] += a[i] * u[k, j]
                    if foh:
                        bars.G1[w, i, j] += a[i] * u[k + 1, j]
            if flags[k] & _COV:
                if flags[k] & _FROZE:
                    # the prediction after a stretch's first sample is used where the stretch ends
                    for i in range(n):
                        for j in range(n):
                            A[i, j] += held_pred[i, j]
                            held_pred[i, j] = 0.0
                T = tape.T[k]
                # Qd_bar += A, Phi_bar += 2 A T, B = Phi' A Phi
                for i in range(n):
                    for j in range(n):
                        bars.Qd[w, i, j] += A[i, j]
                        acc = 0.0
                        acc2 = 0.0
                        for m in range(n):
                            acc += A[i, m] * T[m, j]
                            acc2 += A[i, m] * Phi[w, m, j]
                        bars.Phi[w, i, j] += 2.0 * acc
                        M[i, j] = acc2
                for i in range(n):
                    for j in range(i, n):
                        acc = 0.0
                        for m in range(n):
                            acc += Phi[w, m, i] * M[m, j]
                        B[i, j] = acc
                        B[j, i] = acc
                if flags[k] & _RESTORED:
                    for i in range(n):
                        for j in range(n):
                            held_filt[i, j] += B[i, j]
                            B[i, j] = 0.0
        else:
            for i in range(n):
                b[i] = 0.0
        if src[k] >= 0:
            # a steady sample: frozen gains and variances, the covariance untouched
            f = src[k]
            for o in range(ny - 1, -1, -1):
                if y[k, o] != y[k, o]:
                    continue
                e = tape.es[k, 2 * o]
                s = tape.es[k, 2 * o + 1]
                bk = 0.0
                for i in range(n):
                    bk += b[i] * tape.g[f, o, i]
                ebar = (e + bk) / s
                for i in range(n):
                    kbar[o, i] += b[i] * e
                    b[i] -= ebar * C[o, i]
                sbar[o] += 0.5 / s - 0.5 * e * e / (s * s)
            for i in range(n):
                a[i] = b[i]
                for j in range(n):
                    A[i, j] = 0.0  # the sample leaves its predicted covariance unused
            continue
        froze = flags[k] & _FROZE
        if froze:
            for i in range(n):
                for j in range(n):
                    B[i, j] += held_filt[i, j]
                    held_filt[i, j] = 0.0
        for o in range(ny - 1, -1, -1):
            if y[k, o] != y[k, o]:
                continue
            e = tape.es[k, 2 * o]
            s = tape.es[k, 2 * o + 1]
            inv = 1.0 / s
            g = tape.g[k, o]
            bg = 0.0
            gBg = 0.0
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += B[i, j] * g[j]
                Bg[i] = acc
                gBg += g[i] * acc
                bg += b[i] * g[i]
            ebar = (e + bg) * inv
            sb = 0.5 * inv - 0.5 * e * e * inv * inv - bg * e * inv * inv + gBg * inv * inv
            for i in range(n):
                gbar[i] = b[i] * e * inv - 2.0 * Bg[i] * inv
            if froze:
                kg_g = 0.0
                for i in range(n):
                    kg_g += kbar[o, i] * g[i]
                    gbar[i] += kbar[o, i] * inv
                    kbar[o, i] = 0.0
                sb += sbar[o] - kg_g * inv * inv
                sbar[o] = 0.0
            bars.r[o] += sb
            for i in range(n):
                b[i] -= ebar * C[o, i]
            for i in range(n):
                for j in range(i, n):
                    v = B[i, j] + 0.5 * (gbar[i] * C[o, j] + C[o, i] * gbar[j]) + sb * C[o, i] * C[o, j]
                    B[i, j] = v
                    B[j, i] = v
        for i in range(n):
            a[i] = b[i]
            for j in range(n):
                A[i, j] = B[i, j]
        if k > 0 and not flags[k - 1] & _COV:
            # a stretch ends here because the observed outputs changed: this prediction was made after its first sample
            for i in range(n):
                for j in range(n):
                    held_pred[i, j] += A[i, j]
                    A[i, j] = 0.0
    for i in range(n):
        bars.x0[i] = a[i]
        for j in range(n):
            bars.P0[i, j] = A[i, j]


@njit(cache=True, error_model="numpy")
def contract(
    bars: Adjoints, dmats: DynamicsDerivatives, der: AssembledDerivatives, foh: bool, grad: np.ndarray
) -> None:
    """Add to ``grad`` the adjoints contracted with the derivatives of the discrete matrices and the prior.

    ``grad[i] += sum_w <Phi_bar_w, dPhi_w,i> + <G0_bar_w, dG0_w,i> + <G1_bar_w, dG1_w,i> (FOH)
    + <Qd_bar_w, dQd_w,i> + sum_o r_bar_o dr_o,i + x0_bar'dx0_i + <P0_bar, dP0_i>``.
    """
    dPhi, dG0, dG1, dQd = dmats
    K, q, n, p = dG0.shape
    ny = bars.r.shape[0]
    for i in range(q):
        acc = 0.0
        for o in range(ny):
            acc += bars.r[o] * der.dr[o, i]
        for a in range(n):
            acc += bars.x0[a] * der.dx0[i, a]
            for c in range(n):
                acc += bars.P0[a, c] * der.dP0[i, a, c]
        for w in range(K):
            for a in range(n):
                for c in range(n):
                    acc += bars.Phi[w, a, c] * dPhi[w, i, a, c] + bars.Qd[w, a, c] * dQd[w, i, a, c]
                for j in range(p):
                    acc += bars.G0[w, a, j] * dG0[w, i, a, j]
                    if foh:
                        acc += bars.G1[w, a, j] * dG1[w, i, a, j]
        grad[i] += acc
