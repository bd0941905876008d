"""A compiled Levenberg-Marquardt search on the residuals of a packed least-squares problem, within a box.

The search runs on the optimizer variables ``eta`` of the problem's box
(:class:`rczone.kernels.arrays.SearchBox`: ``theta = exp(eta)`` for log-transformed parameters), one
residual and Jacobian pass (:func:`rczone.kernels.residuals.residuals`) per trial point and no
return to Python. Each step solves

``(J'J + mu diag(D^2)) s = -J'r``

with ``D`` the largest column norms of ``J`` seen so far (Moré's scaling [1]_, which makes the
search invariant to the units of each parameter), takes the step projected onto the box, and
keeps it when the cost falls; ``mu`` follows the gain ratio of the actual to the predicted
decrease (Nielsen's update [2]_). Parameters on a bound whose gradient points out of the box are
held for the step (an active set), so a bound optimum does not stall the others. The tests of
convergence are MINPACK's [1]_: the relative decrease of the cost, the relative step, and the
largest cosine between the residuals and a column of ``J``.

References
----------
.. [1] J. J. Moré, "The Levenberg-Marquardt algorithm: implementation and theory", in *Numerical
   Analysis*, Lecture Notes in Mathematics 630, Springer 1978, 105-116.
.. [2] K. Madsen, H. B. Nielsen, O. Tingleff, *Methods for Non-Linear Least Squares Problems*, 2nd ed.,
   IMM, Technical University of Denmark, 2004, section 3.2.
.. [3] C. Kanzow, N. Yamashita, M. Fukushima, "Levenberg-Marquardt methods with strong local
   convergence properties for solving nonlinear equations with convex constraints", J. Comput.
   Appl. Math. 172 (2004) 375-397 (the projected step).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from rczone.kernels.residuals import residuals

#: Statuses of :class:`SearchOutcome`.
BUDGET, COST, STEP, GRADIENT, INVALID = 0, 1, 2, 3, -1


class Tolerances(NamedTuple):
    """When the search stops."""

    ftol: float  #: relative decrease of the cost in an accepted step
    xtol: float  #: relative size of the step in ``eta``
    gtol: float  #: largest cosine between the residuals and a free column of the Jacobian
    max_evals: int  #: residual and Jacobian passes


class SearchOutcome(NamedTuple):
    """Where a search ended."""

    eta: np.ndarray  #: end point, inside the box
    cost: float  #: ``sum r^2`` there
    n_evals: int  #: residual and Jacobian passes
    status: (
        int  #: :data:`COST`, :data:`STEP`, :data:`GRADIENT` (converged), :data:`BUDGET` or :data:`INVALID`
    )


@njit(cache=True, error_model="numpy")
def _pass(eta: np.ndarray, prob) -> tuple[np.ndarray, np.ndarray, bool]:
    """Residuals and their Jacobian in ``eta`` (``dtheta/deta = theta`` for log parameters)."""
    logp = prob.box.log
    theta = np.empty(eta.shape[0])
    for i in range(eta.shape[0]):
        theta[i] = math.exp(eta[i]) if logp[i] else eta[i]
    res = residuals(theta, prob)
    jac = res.jac
    for i in range(eta.shape[0]):
        if logp[i]:
            for k in range(jac.shape[0]):
                jac[k, i] *= theta[i]
    return res.r, jac, res.valid


@njit(cache=True, error_model="numpy")
def _normal_equations(r: np.ndarray, jac: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """``J'J``, ``J'r`` and ``r'r``."""
    m, d = jac.shape
    A = np.zeros((d, d))
    g = np.zeros(d)
    f = 0.0
    for k in range(m):
        rk = r[k]
        f += rk * rk
        for i in range(d):
            a = jac[k, i]
            if a != 0.0:
                g[i] += a * rk
                for j in range(i, d):
                    A[i, j] += a * jac[k, j]
    for i in range(d):
        for j in range(i):
            A[i, j] = A[j, i]
    return A, g, f


@njit(cache=True, error_model="numpy")
def _damped_step(A: np.ndarray, g: np.ndarray, D2: np.ndarray, mu: float, held: np.ndarray) -> np.ndarray:
    """``s`` solving ``(A + mu diag(D2)) s = -g`` over the free parameters (Cholesky); 0 for held ones."""
    d = g.shape[0]
    L = np.zeros((d, d))
    b = np.zeros(d)
    for i in range(d):
        for j in range(d):
            L[i, j] = 0.0 if held[i] or held[j] else A[i, j]
        L[i, i] = 1.0 if held[i] else A[i, i] + mu * D2[i]
        b[i] = 0.0 if held[i] else -g[i]
    for j in range(d):  # in place: lower triangle of L becomes the Cholesky factor
        s = L[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not s > 0.0:
            return np.zeros(d)
        L[j, j] = math.sqrt(s)
        for i in range(j + 1, d):
            s = L[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / L[j, j]
    for i in range(d):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * b[k]
        b[i] = s / L[i, i]
    for i in range(d - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, d):
            s -= L[k, i] * b[k]
        b[i] = s / L[i, i]
    return b


@njit(cache=True, error_model="numpy")
def levenberg_marquardt(eta0: np.ndarray, prob, tol: Tolerances, inside: float) -> SearchOutcome:
    """Minimize ``sum r^2`` of the packed LS problem ``prob`` from ``eta0`` within ``prob.box`` (module notes).

    Parameters
    ----------
    eta0 : ndarray, shape (d,)
        Start, inside the box.
    prob : rczone.kernels.arrays.Problem
        A packed problem of kind LS.
    tol : Tolerances
    inside : float
        Fraction of each parameter's range by which every point stays inside the box.

    Returns
    -------
    SearchOutcome
    """
    d = eta0.shape[0]
    lo = np.empty(d)
    hi = np.empty(d)
    for i in range(d):
        w = inside * (prob.box.eta_upper[i] - prob.box.eta_lower[i])
        lo[i] = prob.box.eta_lower[i] + w
        hi[i] = prob.box.eta_upper[i] - w
    x = np.minimum(np.maximum(eta0, lo), hi)
    r, jac, ok = _pass(x, prob)
    n = 1
    if not ok:
        return SearchOutcome(x, math.inf, n, INVALID)
    A, g, f = _normal_equations(r, jac)
    D2 = np.zeros(d)
    for i in range(d):
        D2[i] = max(A[i, i], 1e-300)
    mu = 1e-3
    nu = 2.0
    held = np.zeros(d, dtype=np.bool_)
    xn = np.empty(d)
    while True:
        # convergence by the gradient: the largest cosine of the residuals with a free column
        cosine = 0.0
        for i in range(d):
            held[i] = (x[i] <= lo[i] and g[i] > 0.0) or (x[i] >= hi[i] and g[i] < 0.0)
            if not held[i] and A[i, i] > 0.0 and f > 0.0:
                cosine = max(cosine, abs(g[i]) / math.sqrt(A[i, i] * f))
        if cosine <= tol.gtol:
            return SearchOutcome(x, f, n, GRADIENT)
        if n >= tol.max_evals:
            return SearchOutcome(x, f, n, BUDGET)
        s = _damped_step(A, g, D2, mu, held)
        step = 0.0
        size = 0.0
        for i in range(d):
            xn[i] = min(max(x[i] + s[i], lo[i]), hi[i])
            s[i] = xn[i] - x[i]
            step += s[i] * s[i]
            size += x[i] * x[i]
        if math.sqrt(step) <= tol.xtol * (tol.xtol + math.sqrt(size)):
            return SearchOutcome(x, f, n, STEP)
        # the model's decrease for the projected step: -(2 g's + s'As)
        predicted = 0.0
        for i in range(d):
            acc = 2.0 * g[i]
            for j in range(d):
                acc += A[i, j] * s[j]
            predicted -= s[i] * acc
        rn, jn, okn = _pass(xn, prob)
        n += 1
        fn = math.inf
        if okn:
            fn = 0.0
            for k in range(rn.shape[0]):
                fn += rn[k] * rn[k]
        rho = (f - fn) / predicted if predicted > 0.0 else -1.0
        if okn and fn < f and rho > 0.0:
            decrease = f - fn
            x = xn.copy()
            A, g, f = _normal_equations(rn, jn)
            for i in range(d):
                D2[i] = max(D2[i], A[i, i])
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
            if decrease <= tol.ftol * (f + decrease) and rho > 0.25:
                return SearchOutcome(x, f, n, COST)
        else:
            mu *= nu
            nu *= 2.0
