"""The gradient of a packed likelihood by one backward (adjoint) pass: a few evaluations, whatever the parameters.

Forward sensitivities (:func:`rczone.kernels.kalman.kalman_filter`) carry ``dx`` and ``dP`` along
every parameter direction through every sample: the gradient of ``q`` parameters costs about
``q`` times the work of the likelihood. Reverse mode [1]_ runs the filter once, keeps what each
step produced (filtered state and covariance, innovation, its variance, ``P c``), then runs the
steps backward with the adjoints ``x_bar = dJ/dx`` and ``P_bar = dJ/dP``, accumulating the
adjoints of the discrete matrices of each distinct interval (``Phi, G0, G1, Qd``), of the
measurement variance and of the prior. The gradient in the parameters is then their contraction
with the derivatives of those few matrices (:func:`rczone.kernels.discretize.rc_interval_derivatives`, the spectral
formulas of :func:`rczone.kernels.discretize.spectral_derivatives` once per distinct interval; for two states
the same formulas written out, :func:`rczone.kernels.discretize.spectral_derivatives2`) and of the prior, so it
costs about three likelihoods for any number of parameters.

The backward step of one sample, for a scalar output ``y = c'x`` with ``e = y - c'x-``,
``s = c'P-c + r``, ``g = P-c``, ``x+ = x- + g e/s``, ``P+ = P- - g g'/s`` and the term
``0.5 (log s + e^2/s)``, given the adjoints ``(b, B)`` of ``(x+, P+)``:

* ``e_bar = e/s + b'g/s``, ``s_bar = 0.5/s - 0.5 e^2/s^2 - (b'g) e/s^2 + g'Bg/s^2``,
  ``g_bar = b e/s - (B + B') g/s``;
* ``x-_bar = b - e_bar c``, ``P-_bar = B + g_bar c' + s_bar c c'``, ``r_bar += s_bar``.

The time step ``x- = Phi x+ + G0 u_k + G1 u_k+1``, ``P- = Phi P+ Phi' + Qd`` with adjoints
``(a, A)`` of its results gives ``b = Phi' a``, ``B = Phi' A Phi`` and adds ``a x+' + (A + A') Phi P+``
to ``Phi_bar``, ``a u_k'`` to ``G0_bar``, ``a u_k+1'`` to ``G1_bar`` and ``A`` to ``Qd_bar`` [2]_.

The recursion runs to the end (no steady state): the value differs from that of the fused
value kernel (:func:`rczone.kernels.rc2.nll_rc2`) by at most its steady-state tolerance.

:func:`gradient_general` does the same for any packed likelihood (any number of states and
outputs, missing outputs, several flows, ZOH or FOH, MAP) with the reverse pass of the general
filter, :func:`rczone.kernels.reverse.nll_reverse`, steady state included; both entry points
contract the adjoints with the discretization's derivatives by :func:`rczone.kernels.reverse.contract`.

References
----------
.. [1] A. Griewank, A. Walther, *Evaluating Derivatives: Principles and Techniques of
   Algorithmic Differentiation*, 2nd ed., SIAM, 2008, chapter 3 (the reverse mode).
.. [2] M. B. Giles, "Collected matrix derivative results for forward and reverse mode
   algorithmic differentiation", in *Advances in Automatic Differentiation*, Springer, 2008,
   pp. 35-44 (adjoints of matrix products).
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
    FilterOptions,
    FilterStart,
    ModelAdjoints,
    Moments2,
    Observation,
    Series,
)
from rczone.kernels.discretize import rc2_interval_derivatives, rc_interval_derivatives, rc_interval_matrices
from rczone.kernels.discretize_adjoint import discretization_adjoints
from rczone.kernels.problem import LS, MAP, assembled, bound_kernel, with_prior
from rczone.kernels.rc2 import correct_rc2, predict_rc2
from rczone.kernels.reverse import Adjoints, contract, nll_reverse, zero_adjoints

_LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def nll_rc2_adjoint(
    Phi: np.ndarray,
    G0: np.ndarray,
    G1: np.ndarray,
    Qd: np.ndarray,
    which: np.ndarray,
    c: np.ndarray,
    r: float,
    x0: np.ndarray,
    P0: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    foh: bool,
    bars: Adjoints,
    innovations: np.ndarray,
) -> tuple[float, int]:
    """``-log L`` (without ``0.5 n log 2 pi``) of a 2-state, 1-output model and the adjoints of its inputs.

    Parameters
    ----------
    Phi, G0, G1, Qd : ndarray, shapes (K, 2, 2), (K, 2, p), (K, 2, p), (K, 2, 2)
        Discrete matrices of each distinct interval; interval ``k`` uses ``which[k]``.
    c : ndarray, shape (2,)
        Output row.
    r : float
        Measurement-noise variance.
    x0, P0 : ndarray, shapes (2,), (2, 2)
        The state at the first sample (:class:`~rczone.kernels.arrays.FilterStart`).
    u, y : ndarray, shapes (N, p), (N,)
        Inputs; measurements (NaN where missing).
    foh : bool
    bars : Adjoints
        ``(Phi, G0, G1, Qd, x0, P0, r)`` adjoints of shapes (K, 2, 2),
        (K, 2, p), (K, 2, p), (K, 2, 2), (2,), (2, 2), (1,), zeroed by the caller; they receive
        the derivatives of ``-log L``.
    innovations : ndarray, shape (N,)
        Receives the one-step-ahead prediction errors ``e`` (NaN where ``y`` is missing).

    Returns
    -------
    nll : float
        NaN for a non-positive innovation variance.
    n_obs : int
        Observed samples; -1 for an invalid model.
    """
    Phi_bar, G0_bar, G1_bar, Qd_bar = bars.Phi, bars.G0, bars.G1, bars.Qd
    x0_bar, P0_bar, r_bar = bars.x0, bars.P0, bars.r
    n_t = y.shape[0]
    p = u.shape[1]
    c0, c1 = c[0], c[1]
    # forward: the filter, keeping the filtered state and covariance, e, s and g = P- c of each sample
    xf = np.empty((n_t, 2))
    pf = np.empty((n_t, 3))
    es = np.empty((n_t, 4))  # e, s, g0, g1
    x_0, x_1 = x0[0], x0[1]
    p00, p01, p11 = P0[0, 0], 0.5 * (P0[0, 1] + P0[1, 0]), P0[1, 1]
    dyn = Dynamics(Phi, G0, G1, Qd)
    nll = 0.0
    n_obs = 0
    for k in range(n_t):
        yk = y[k]
        if yk == yk:
            e = yk - c0 * x_0 - c1 * x_1
            g0 = p00 * c0 + p01 * c1
            g1 = p01 * c0 + p11 * c1
            s = r + c0 * g0 + c1 * g1
            if not s > 0.0:
                return math.nan, -1
            inv = 1.0 / s
            m = correct_rc2(Moments2(x_0, x_1, p00, p01, p11), g0, g1, e, inv)
            x_0, x_1, p00, p01, p11 = m.x0, m.x1, m.p00, m.p01, m.p11
            nll += 0.5 * (math.log(s) + e * e * inv)
            n_obs += 1
            es[k, 0], es[k, 1], es[k, 2], es[k, 3] = e, s, g0, g1
            innovations[k] = e
        else:
            innovations[k] = math.nan
        xf[k, 0], xf[k, 1] = x_0, x_1
        pf[k, 0], pf[k, 1], pf[k, 2] = p00, p01, p11
        if k == n_t - 1:
            break
        m = predict_rc2(dyn, which[k], u, k, foh, Moments2(x_0, x_1, p00, p01, p11))
        x_0, x_1, p00, p01, p11 = m.x0, m.x1, m.p00, m.p01, m.p11
    # backward: (a, A) adjoints of the predicted state and covariance of sample k + 1
    a_0 = a_1 = 0.0
    A00 = A01 = A10 = A11 = 0.0
    for k in range(n_t - 1, -1, -1):
        if k < n_t - 1:
            w = which[k]
            f00, f01, f10, f11 = Phi[w, 0, 0], Phi[w, 0, 1], Phi[w, 1, 0], Phi[w, 1, 1]
            q00, q01, q11 = pf[k, 0], pf[k, 1], pf[k, 2]
            # Phi_bar += a x+' + (A + A') Phi P+
            s00, s01, s10, s11 = A00 + A00, A01 + A10, A10 + A01, A11 + A11
            t00 = f00 * q00 + f01 * q01  # Phi P+
            t01 = f00 * q01 + f01 * q11
            t10 = f10 * q00 + f11 * q01
            t11 = f10 * q01 + f11 * q11
            Phi_bar[w, 0, 0] += a_0 * xf[k, 0] + s00 * t00 + s01 * t10
            Phi_bar[w, 0, 1] += a_0 * xf[k, 1] + s00 * t01 + s01 * t11
            Phi_bar[w, 1, 0] += a_1 * xf[k, 0] + s10 * t00 + s11 * t10
            Phi_bar[w, 1, 1] += a_1 * xf[k, 1] + s10 * t01 + s11 * t11
            for j in range(p):
                G0_bar[w, 0, j] += a_0 * u[k, j]
                G0_bar[w, 1, j] += a_1 * u[k, j]
                if foh:
                    G1_bar[w, 0, j] += a_0 * u[k + 1, j]
                    G1_bar[w, 1, j] += a_1 * u[k + 1, j]
            Qd_bar[w, 0, 0] += A00
            Qd_bar[w, 0, 1] += A01
            Qd_bar[w, 1, 0] += A10
            Qd_bar[w, 1, 1] += A11
            # b = Phi' a, B = Phi' A Phi
            b_0 = f00 * a_0 + f10 * a_1
            b_1 = f01 * a_0 + f11 * a_1
            m00 = A00 * f00 + A01 * f10  # A Phi
            m01 = A00 * f01 + A01 * f11
            m10 = A10 * f00 + A11 * f10
            m11 = A10 * f01 + A11 * f11
            B00 = f00 * m00 + f10 * m10
            B01 = f00 * m01 + f10 * m11
            B10 = f01 * m00 + f11 * m10
            B11 = f01 * m01 + f11 * m11
        else:
            b_0 = b_1 = 0.0
            B00 = B01 = B10 = B11 = 0.0
        yk = y[k]
        if yk == yk:
            e, s, g0, g1 = es[k, 0], es[k, 1], es[k, 2], es[k, 3]
            inv = 1.0 / s
            bg = b_0 * g0 + b_1 * g1
            gBg = g0 * (B00 * g0 + B01 * g1) + g1 * (B10 * g0 + B11 * g1)
            e_bar = e * inv + bg * inv
            s_bar = 0.5 * inv - 0.5 * e * e * inv * inv - bg * e * inv * inv + gBg * inv * inv
            gb0 = b_0 * e * inv - ((B00 + B00) * g0 + (B01 + B10) * g1) * inv
            gb1 = b_1 * e * inv - ((B10 + B01) * g0 + (B11 + B11) * g1) * inv
            a_0 = b_0 - e_bar * c0
            a_1 = b_1 - e_bar * c1
            A00 = B00 + gb0 * c0 + s_bar * c0 * c0
            A01 = B01 + gb0 * c1 + s_bar * c0 * c1
            A10 = B10 + gb1 * c0 + s_bar * c1 * c0
            A11 = B11 + gb1 * c1 + s_bar * c1 * c1
            r_bar[0] += s_bar
        else:
            a_0, a_1 = b_0, b_1
            A00, A01, A10, A11 = B00, B01, B10, B11
    x0_bar[0], x0_bar[1] = a_0, a_1
    P0_bar[0, 0], P0_bar[0, 1], P0_bar[1, 0], P0_bar[1, 1] = A00, A01, A10, A11
    return nll, n_obs


@njit(cache=True, error_model="numpy", inline="always")
def _discretized(mod: Assembled, der: AssembledDerivatives, keys: np.ndarray, foh: bool):
    """The discrete matrices of each distinct interval and their derivatives, by the spectral formulas only."""
    return rc_interval_derivatives(mod, der, Discretization(keys, np.sqrt(mod.cap), foh, True))


@njit(cache=True, error_model="numpy", inline="always")
def _total(
    nll: float, n_obs: int, theta: np.ndarray, prob, bars: Adjoints, dmats, der: AssembledDerivatives, grad
) -> tuple[float, np.ndarray]:
    """``J_ML`` (or ``J_MAP``) from ``nll`` and ``grad`` from the adjoints; ``(inf, zeros)`` for an invalid model."""
    if n_obs < 0:
        return math.inf, grad
    contract(bars, dmats, der, prob.consts.foh, grad)
    return _with_prior(nll, n_obs, theta, prob, grad)


@njit(cache=True, error_model="numpy", inline="always")
def _with_prior(
    nll: float, n_obs: int, theta: np.ndarray, prob, grad: np.ndarray
) -> tuple[float, np.ndarray]:
    """``J_ML`` from ``nll``, and for MAP the prior added to it and to ``grad``."""
    j = nll + 0.5 * n_obs * _LOG_2PI
    if prob.kind == MAP:
        j = with_prior(j, theta, prob.penalty, grad, np.zeros(theta.shape[0]), True)
    return j, grad


@njit(cache=True, error_model="numpy")
def contract_assembled(
    bars: Adjoints, model: ModelAdjoints, der: AssembledDerivatives, grad: np.ndarray
) -> None:
    """Add to ``grad`` the adjoints of the continuous model contracted with its derivatives.

    ``grad[i] += <A0_bar, dA0_i> + sum_f <N_f_bar, dN_f,i> + <B0_bar, dB0_i> + sum_f <M_f_bar, dM_f,i>
    + qc_bar'dqc_i + sum_o r_bar_o dr_o,i + x0_bar'dx0_i + <P0_bar, dP0_i>``, ``model`` from
    :func:`rczone.kernels.discretize_adjoint.discretization_adjoints`.
    """
    Asum, Bsum, qcbar = model.A, model.B, model.qc
    q, n = der.dqc.shape
    nf, p = der.dN.shape[1], der.dB0.shape[2]
    ny = bars.r.shape[0]
    for i in range(q):
        acc = 0.0
        for o in range(ny):
            acc += bars.r[o] * der.dr[o, i]
        for a in range(n):
            acc += bars.x0[a] * der.dx0[i, a] + qcbar[a] * der.dqc[i, a]
            for c in range(n):
                acc += bars.P0[a, c] * der.dP0[i, a, c] + Asum[0, a, c] * der.dA0[i, a, c]
                for f in range(nf):
                    acc += Asum[1 + f, a, c] * der.dN[i, f, a, c]
            for j in range(p):
                acc += Bsum[0, a, j] * der.dB0[i, a, j]
                for f in range(nf):
                    acc += Bsum[1 + f, a, j] * der.dM[i, f, a, j]
        grad[i] += acc


@njit(cache=True, error_model="numpy")
def gradient_fused(theta: np.ndarray, prob) -> tuple[float, np.ndarray]:
    """``J_ML`` or ``J_MAP`` of a packed 2-state, 1-output problem and its gradient in ``theta``, by the adjoint pass.

    ``(inf, zeros)`` where the model is invalid. Least squares is not handled here (the caller
    takes :func:`rczone.kernels.problem.value_and_gradient`). The one-step-ahead prediction errors
    are left in ``prob.scratch``.
    """
    grad = np.zeros(theta.shape[0])
    mod, der, ok = assembled(theta, prob, theta.shape[0])
    if not ok or prob.kind == LS:
        return math.inf, grad
    u, y, keys, which = prob.data.u, prob.data.y, prob.data.keys, prob.data.which
    foh = prob.consts.foh
    mats, dmats = rc2_interval_derivatives(mod, der, Discretization(keys, np.sqrt(mod.cap), foh, True))
    Phi, G0, G1, Qd = mats
    bars = zero_adjoints(keys.shape[0], 2, mod.B0.shape[1], 1)
    nll, n_obs = nll_rc2_adjoint(
        Phi, G0, G1, Qd, which, mod.C[0], mod.r[0], mod.x0, mod.P0, u, y[:, 0], foh, bars, prob.scratch
    )
    return _total(nll, n_obs, theta, prob, bars, dmats, der, grad)


@njit(cache=True, error_model="numpy")
def gradient_general(theta: np.ndarray, prob) -> tuple[float, np.ndarray]:
    """``J_ML`` or ``J_MAP`` of a packed problem (any number of states and outputs) and its gradient in ``theta``.

    By the reverse pass of the general filter (:func:`rczone.kernels.reverse.nll_reverse`), whose
    matrix adjoints are contracted with the derivatives of each distinct interval's discrete
    matrices (:func:`rczone.kernels.discretize.rc_interval_derivatives`) and of the noise and
    prior (:func:`rczone.kernels.problem.assembled`): about three likelihoods' work plus the
    discretization derivatives, whatever the number of parameters. The value is that of
    :func:`rczone.kernels.problem.value_general` (the same filter steps and steady state; within
    its steady-state tolerance where that takes the modal filter). ``(inf, zeros)`` where the model
    is invalid; least squares is not handled here (:func:`rczone.kernels.problem.value_and_gradient`).
    """
    grad = np.zeros(theta.shape[0])
    mod, der, ok = assembled(theta, prob, theta.shape[0])
    if not ok or prob.kind == LS:
        return math.inf, grad
    foh, _, steady_rtol, _ = prob.consts
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    ny = mod.C.shape[0]
    keys = prob.data.keys
    bars = zero_adjoints(keys.shape[0], n, p, ny)
    obs = Observation(
        mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, 0, n)), np.zeros((ny, 0, p)), np.zeros((ny, 0))
    )
    prior = FilterStart(mod.x0, mod.P0, np.zeros((0, n)), np.zeros((0, n, n)))
    series = Series(prob.data.u, prob.data.y, prob.data.which)
    options = FilterOptions(foh, False, steady_rtol)
    if foh:  # the forward derivatives of the discrete matrices, G1's included
        mats, dmats = _discretized(mod, der, keys, foh)
        nll, n_obs, _ = nll_reverse(mats, obs, prior, series, options, bars)
        return _total(nll, n_obs, theta, prob, bars, dmats, der, grad)
    # zero-order hold: the adjoints carried back through the discretization, once per interval
    mats = rc_interval_matrices(mod, Discretization(keys, np.sqrt(mod.cap), False, True))
    nll, n_obs, _ = nll_reverse(mats, obs, prior, series, options, bars)
    if n_obs < 0:
        return math.inf, grad
    contract_assembled(bars, discretization_adjoints(mod, keys, bars), der, grad)
    return _with_prior(nll, n_obs, theta, prob, grad)


def gradient_kernel(prob, *, fused: bool):
    """The adjoint gradient of a packed likelihood, :func:`gradient_fused` or :func:`gradient_general`, bound to ``prob``.

    As :func:`rczone.kernels.problem.value_kernel` for values
    (:func:`rczone.kernels.problem.bound_kernel`): the compiled specialization is resolved once, so
    a call does not pay numba's typing of the packed problem (about 6 us of a 2-state gradient's
    130 us; an ML fit asks for about 76 gradients).

    Parameters
    ----------
    prob : rczone.kernels.arrays.Problem
        The packed problem.
    fused : bool
        The unrolled 2-state pass (:func:`gradient_fused`) rather than the general reverse pass.

    Returns
    -------
    callable
        ``gradient(theta, prob) -> (J, grad)``, as the kernel.
    """
    return bound_kernel(gradient_fused if fused else gradient_general, prob)
