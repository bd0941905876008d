"""The weighted output errors of the exact simulation and their exact Jacobian, in one compiled pass.

The least-squares cost of :mod:`rczone.kernels.problem` is the trapezoid rule on the open-loop
output errors ``e = y - C x`` (K^2 s): an interval counts when both of its end samples are
measured. Written per sample, each measured output carries the weight ``w = (h_before + h_after) / 2``
of the counted intervals it closes and opens, so ``J_LS = sum w e^2 = sum r^2`` with the residuals
``r = sqrt(w) e`` (zero where an output is not counted). Gauss-Newton and trust-region methods
work on ``r`` and its Jacobian, and converge in a few steps where a search on ``J_LS`` alone
needs hundreds [1]_.

The Jacobian comes from forward sensitivities of the exact discrete simulation [2]_: the
discrete matrices of each distinct interval and their derivatives along the ``q`` free
parameters (:func:`rczone.kernels.discretize.interval_derivatives`), then, sample by sample,

``x' = Phi x + G0 u_k + G1 u_k+1``, ``dx_j' = Phi dx_j + dPhi_j x + dG0_j u_k + dG1_j u_k+1``

(``G1 = 0`` for a zero-order hold), started from the initial state and its derivatives
(:func:`rczone.kernels.problem.assembled`), with ``dr_j = -sqrt(w) C dx_j``. The pass is the
open-loop branch of the compiled filter (:func:`rczone.kernels.kalman.kalman_filter`), the
simulation the cost kernels run, so ``sum r^2`` is the cost the fit minimizes; it skips the
``dPhi`` and ``dG`` terms of directions that leave the dynamics unchanged (an initial state).

References
----------
.. [1] J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, chapter 10
   (Gauss-Newton, Levenberg-Marquardt, the residual Jacobian).
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 10.3 (output-error models: the gradient of the predictor by the sensitivity
   equations).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from rczone.kernels.arrays import (
    Discretization,
    Dynamics,
    DynamicsDerivatives,
    FilterOptions,
    FilterStart,
    Observation,
    Series,
)
from rczone.kernels.discretize import interval_derivatives
from rczone.kernels.kalman import kalman_filter, outputs
from rczone.kernels.problem import assembled


class Residuals(NamedTuple):
    """Weighted output errors and their derivatives; row ``k ny + j`` is output ``j`` at sample ``k``."""

    r: np.ndarray  #: (N ny,) ``sqrt(w) (y - y_hat)``, K s^0.5; 0 where the output is not counted
    jac: np.ndarray  #: (N ny, q) ``dr / dtheta``
    valid: bool  #: False where the parameters are invalid (``r`` then NaN)


@njit(cache=True, error_model="numpy")
def trapezoid_weights(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``(N, ny)`` weights ``w`` with ``sum w e^2`` the trapezoid rule over intervals with both ends measured."""
    N, ny = y.shape
    w = np.zeros((N, ny))
    for k in range(N - 1):
        h = 0.5 * (t[k + 1] - t[k])
        for j in range(ny):
            if y[k, j] == y[k, j] and y[k + 1, j] == y[k + 1, j]:
                w[k, j] += h
                w[k + 1, j] += h
    return w


@njit(cache=True, error_model="numpy")
def open_loop_two_states(
    dyn: Dynamics, ddyn: DynamicsDerivatives, x0: np.ndarray, dx0: np.ndarray, series: Series, foh: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The open-loop states of a 2-state model, (N, 2), and their derivatives, (q, N, 2), one direction at a time.

    The same recursions as the open-loop filter, ``x' = Phi x + G0 u_k + G1 u_k+1`` and
    ``dx_j' = Phi dx_j + dPhi_j x + dG0_j u_k + dG1_j u_k+1`` (the ``dPhi``, ``dG`` terms only where
    they are not zero), with the two states as scalars and the states of every sample kept, so each
    direction is one tight loop over the samples: several times faster than the general loop,
    whose innermost loops run over two states.
    """
    Phi, G0, G1, _ = dyn
    dPhi, dG0, dG1, _ = ddyn
    u, which = series.u, series.which
    N, p = u.shape
    q = dx0.shape[0]
    X = np.empty((N, 2))
    a, b = x0[0], x0[1]
    for k in range(N):
        X[k, 0] = a
        X[k, 1] = b
        if k == N - 1:
            break
        w = which[k]
        na = Phi[w, 0, 0] * a + Phi[w, 0, 1] * b
        nb = Phi[w, 1, 0] * a + Phi[w, 1, 1] * b
        for j in range(p):
            na += G0[w, 0, j] * u[k, j]
            nb += G0[w, 1, j] * u[k, j]
            if foh:
                na += G1[w, 0, j] * u[k + 1, j]
                nb += G1[w, 1, j] * u[k + 1, j]
        a, b = na, nb
    dX = np.empty((q, N, 2))
    for d in range(q):
        moves = False
        for w in range(Phi.shape[0]):
            for i in range(2):
                moves = moves or dPhi[w, d, i, 0] != 0.0 or dPhi[w, d, i, 1] != 0.0
                for j in range(p):
                    moves = moves or dG0[w, d, i, j] != 0.0 or dG1[w, d, i, j] != 0.0
        a, b = dx0[d, 0], dx0[d, 1]
        for k in range(N):
            dX[d, k, 0] = a
            dX[d, k, 1] = b
            if k == N - 1:
                break
            w = which[k]
            na = Phi[w, 0, 0] * a + Phi[w, 0, 1] * b
            nb = Phi[w, 1, 0] * a + Phi[w, 1, 1] * b
            if moves:
                x0k, x1k = X[k, 0], X[k, 1]
                na += dPhi[w, d, 0, 0] * x0k + dPhi[w, d, 0, 1] * x1k
                nb += dPhi[w, d, 1, 0] * x0k + dPhi[w, d, 1, 1] * x1k
                for j in range(p):
                    na += dG0[w, d, 0, j] * u[k, j]
                    nb += dG0[w, d, 1, j] * u[k, j]
                    if foh:
                        na += dG1[w, d, 0, j] * u[k + 1, j]
                        nb += dG1[w, d, 1, j] * u[k + 1, j]
            a, b = na, nb
    return X, dX


@njit(cache=True, error_model="numpy")
def residuals(theta: np.ndarray, prob) -> Residuals:
    """Residuals of a packed least-squares problem at physical values ``theta`` and their Jacobian in ``theta``.

    Parameters
    ----------
    theta : ndarray, shape (q,)
        Free parameter values (physical units, the order of the problem's slots).
    prob : rczone.kernels.arrays.Problem
        A packed problem (:func:`rczone.estimation.compiled.compiled_problem`) of kind LS.

    Returns
    -------
    Residuals
        ``sum r^2`` is the problem's ``J_LS`` (K^2 s); NaN residuals and ``valid = False`` where
        the values are invalid (:func:`rczone.kernels.problem.assembled`) or the simulation
        overflows.
    """
    q = theta.shape[0]
    t, u, y, keys, which = prob.data.t, prob.data.u, prob.data.y, prob.data.keys, prob.data.which
    N, ny = y.shape
    out = Residuals(np.zeros(N * ny), np.zeros((N * ny, q)), True)
    mod, der, ok = assembled(theta, prob, q)
    if not ok:
        for i in range(N * ny):
            out.r[i] = math.nan
        return Residuals(out.r, out.jac, False)
    foh = prob.consts.foh
    dyn, ddyn = interval_derivatives(mod, der, Discretization(keys, np.sqrt(mod.cap), foh, False))
    n = mod.A0.shape[0]
    w = trapezoid_weights(t, y)
    state = prob.form.output_state
    if n == 2:
        X, dX = open_loop_two_states(dyn, ddyn, mod.x0, der.dx0, Series(u, y, which), foh)
        for k in range(N):
            for j in range(ny):
                if w[k, j] > 0.0:
                    c = math.sqrt(w[k, j])
                    row = k * ny + j
                    out.r[row] = c * (y[k, j] - X[k, state[j]])
                    for d in range(q):
                        out.jac[row, d] = -c * dX[d, k, state[j]]
    else:
        p = mod.B0.shape[1]
        obs = Observation(mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, q, n)), np.zeros((ny, q, p)), der.dr)
        trace = outputs(N, n, ny, q, True, False)
        kalman_filter(
            dyn,
            ddyn,
            obs,
            FilterStart(mod.x0, mod.P0, der.dx0, der.dP0),
            Series(u, y, which),
            FilterOptions(foh, True, 0.0),
            trace,
        )
        for k in range(N):
            for j in range(ny):
                if w[k, j] > 0.0:
                    c = math.sqrt(w[k, j])
                    row = k * ny + j
                    out.r[row] = c * trace.e[k, j]
                    for d in range(q):
                        out.jac[row, d] = c * trace.de[k, j, d]
    finite = True
    for i in range(N * ny):
        finite = finite and abs(out.r[i]) < math.inf
    return Residuals(out.r, out.jac, finite)
