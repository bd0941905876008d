"""Nelder–Mead over the compiled cost of a packed estimation problem, without leaving compiled code.

A fit of the paper's reduced model spends a few hundred cost evaluations of ~30 us each;
driven from Python (SciPy's Nelder–Mead, parameter mappings) every evaluation costs several
times that again. :func:`nelder_mead` is the Nelder–Mead simplex method [1]_ with the
standard coefficients (reflection 1, expansion 2, contraction 1/2, shrink 1/2) and the
stopping rule of :func:`scipy.optimize.minimize` (every vertex within ``xatol`` of the best in
every coordinate and every value within ``fatol`` of the best), on
:func:`rczone.kernels.problem.value_kernel` (at ``theta_of_z(z)``) divided by ``scale`` with
non-finite values replaced by ``1e300``, as the Python path of
:func:`rczone.estimation.optimize.minimize_from`. On the same function it takes SciPy's steps exactly, budget handling included; against the Python path
the iterates differ by rounding (``math.tanh`` and NumPy's differ in the last bit) and where
vertices tie exactly (the sort here is stable, NumPy's is not), so the two end at the same
minimum within the tolerances, not bit for bit.

The search takes its cost function as an argument (numba specializes a function on the compiled
function it is given) and is compiled once per cost kernel (:func:`_search_fused`,
:func:`_search_general`): :func:`nelder_mead` runs the one of the problem, so a 2-state fit
never compiles the general filter, nor a general fit the fused kernel.

References
----------
.. [1] J. A. Nelder, R. Mead, "A simplex method for function minimization", Computer
   Journal 7 (1965) 308-313.
.. [2] J. C. Lagarias, J. A. Reeds, M. H. Wright, P. E. Wright, "Convergence properties of
   the Nelder-Mead simplex method in low dimensions", SIAM J. Optim. 9 (1998) 112-147.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rczone.kernels.problem import theta_of_z, value_fused, value_general

#: Value handed to the simplex at invalid points (as the Python path).
BIG = 1e300


@njit(cache=True, error_model="numpy", inline="always")
def _scaled(cost, z: np.ndarray, prob, scale: float) -> float:
    lo, hi, logp = prob.box
    v = cost(theta_of_z(z, lo, hi, logp), prob)
    v = v / scale if math.isfinite(v) else math.inf
    return min(v, BIG)


@njit(cache=True, error_model="numpy")
def _sort(sim: np.ndarray, fsim: np.ndarray) -> None:
    """Order the vertices by value, best first (stable for equal values).

    An insertion sort: d + 1 rows, nearly sorted after each step, and a fraction of the compile
    time of ``np.argsort`` with fancy indexing.
    """
    n_v, d = sim.shape
    row = np.empty(d)
    for k in range(1, n_v):
        f = fsim[k]
        for i in range(d):
            row[i] = sim[k, i]
        j = k - 1
        while j >= 0 and fsim[j] > f:
            fsim[j + 1] = fsim[j]
            for i in range(d):
                sim[j + 1, i] = sim[j, i]
            j -= 1
        fsim[j + 1] = f
        for i in range(d):
            sim[j + 1, i] = row[i]


@njit(cache=True, error_model="numpy")
def _combine(a: float, x: np.ndarray, b: float, y: np.ndarray) -> np.ndarray:
    """``a x + b y``, element by element (loops compile faster than array expressions)."""
    out = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        out[i] = a * x[i] + b * y[i]
    return out


# inlined into one compiled search per cost below: a compiled function taking another as an argument
# is not reloaded from numba's disk cache, it would compile again in every process
@njit(cache=True, error_model="numpy", inline="always")
def _search(
    cost, sim: np.ndarray, prob, scale: float, xatol: float, fatol: float, max_evals: int
) -> tuple[np.ndarray, float, int, int]:
    """Minimize ``cost(theta_of_z(z), prob) / scale`` from the initial simplex ``sim`` (d + 1 rows).

    Returns
    -------
    z : ndarray
        Best vertex.
    f : float
        Its scaled cost.
    n_evals : int
    status : int
        0 converged, 1 evaluation budget exhausted.
    """
    n_v, d = sim.shape
    sim = sim.copy()
    fsim = np.full(n_v, math.inf)
    n_evals = 0
    for k in range(n_v):
        if n_evals >= max_evals:
            break
        fsim[k] = _scaled(cost, sim[k], prob, scale)
        n_evals += 1
    _sort(sim, fsim)
    status = 1
    last = n_v - 1
    while n_evals < max_evals:
        xdev = 0.0
        fdev = 0.0
        for k in range(1, n_v):
            fdev = max(fdev, abs(fsim[0] - fsim[k]))
            for i in range(d):
                xdev = max(xdev, abs(sim[k, i] - sim[0, i]))
        if xdev <= xatol and fdev <= fatol:
            status = 0
            break
        xbar = np.zeros(d)
        for k in range(last):
            for i in range(d):
                xbar[i] += sim[k, i]
        for i in range(d):
            xbar[i] /= d
        worst = sim[last].copy()
        # a x + (-b) y is a x - b y exactly: the same vertices as the array expressions
        xr = _combine(2.0, xbar, -1.0, worst)
        fxr = _scaled(cost, xr, prob, scale)
        n_evals += 1
        # the new vertex and its value; an evaluation the budget does not allow ends the search
        # before the step that needed it, as SciPy's does
        xn = xr
        fn = fxr
        if fxr < fsim[0]:
            if n_evals >= max_evals:
                break
            xe = _combine(3.0, xbar, -2.0, worst)
            fxe = _scaled(cost, xe, prob, scale)
            n_evals += 1
            if fxe < fxr:
                xn = xe
                fn = fxe
        elif fxr >= fsim[last - 1]:
            if n_evals >= max_evals:
                break
            if fxr < fsim[last]:  # outside contraction
                xn = _combine(1.5, xbar, -0.5, worst)
                fn = _scaled(cost, xn, prob, scale)
                n_evals += 1
                shrink = not fn <= fxr
            else:  # inside contraction
                xn = _combine(0.5, xbar, 0.5, worst)
                fn = _scaled(cost, xn, prob, scale)
                n_evals += 1
                shrink = not fn < fsim[last]
            if shrink:
                for k in range(1, n_v):
                    if n_evals >= max_evals:
                        break
                    for i in range(d):
                        sim[k, i] = sim[0, i] + 0.5 * (sim[k, i] - sim[0, i])
                    fsim[k] = _scaled(cost, sim[k], prob, scale)
                    n_evals += 1
                _sort(sim, fsim)
                continue
        for i in range(d):
            sim[last, i] = xn[i]
        fsim[last] = fn
        _sort(sim, fsim)
    return sim[0].copy(), fsim[0], n_evals, status


@njit(cache=True, error_model="numpy")
def _search_fused(sim, prob, scale, xatol, fatol, max_evals):
    return _search(value_fused, sim, prob, scale, xatol, fatol, max_evals)


@njit(cache=True, error_model="numpy")
def _search_general(sim, prob, scale, xatol, fatol, max_evals):
    return _search(value_general, sim, prob, scale, xatol, fatol, max_evals)


def nelder_mead(
    sim: np.ndarray, prob, scale: float, xatol: float, fatol: float, max_evals: int
) -> tuple[np.ndarray, float, int, int]:
    """Minimize the cost of the packed problem ``prob`` (:func:`rczone.kernels.problem.value_kernel`).

    From the initial simplex ``sim`` (d + 1 rows of direct-search variables ``z``), on the cost
    divided by ``scale``; see the module notes. Returns ``(z, f, n_evals, status)`` as
    :func:`_search`.
    """
    search = _search_fused if prob.consts.fused else _search_general
    return search(sim, prob, scale, xatol, fatol, max_evals)
