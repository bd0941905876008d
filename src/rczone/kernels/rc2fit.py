"""Compiled identification of a 2-state RC model: the cost of the optimizer's variables, and
Nelder–Mead over it, in one compiled call.

A fit of the paper's reduced model spends a few hundred cost evaluations of ~30 us each
in the likelihood kernel; driven from Python (SciPy's Nelder–Mead, parameter mappings,
dictionaries of values) every evaluation costs several times that again. Here the whole
loop runs compiled:

* :func:`cost_z` maps the unbounded direct-search variables ``z`` to the physical values
  (``eta = lo + (hi - lo) (1 + tanh(z/2))/2``, ``theta = exp(eta)`` for log parameters, as
  :meth:`rczone.estimation.parameters.ParameterSpec.from_z`), every resistor, capacity and
  noise level to ``k * theta[i]`` or a constant (:func:`rczone.network.parameters.proportional_base`),
  and evaluates ``J_LS`` (trapezoid rule on the open-loop errors), ``J_ML`` (``-log L``) or
  ``J_MAP`` (tempered likelihood plus log-normal prior) with
  :func:`rczone.kernels.kalman.nll_rc2_from_values`;
* :func:`nelder_mead` is the Nelder–Mead simplex method [1]_ with the standard
  coefficients (reflection 1, expansion 2, contraction 1/2, shrink 1/2) and the stopping
  rule of :func:`scipy.optimize.minimize` (every vertex within ``xatol`` of the best in every
  coordinate and every value within ``fatol`` of the best), on the cost divided by
  ``scale`` with non-finite values replaced by ``1e300``, as the Python path of
  :func:`rczone.estimation.optimize.minimize_from`. On the same function it takes SciPy's
  steps exactly, budget handling included; against the Python path the iterates differ
  by rounding (``math.tanh`` and NumPy's differ in the last bit) and where vertices tie
  exactly (the sort here is stable, NumPy's is not), so the two end at the same minimum
  within the tolerances, not bit for bit.

The problem is a tuple of arrays built by :func:`rczone.estimation.compiled.compiled_problem`
(see there for the layout); :func:`cost_z` on it equals
:class:`rczone.estimation.costs.Objective` at ``from_z(z)`` to rounding.

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

from rczone.kernels.kalman import nll_rc2_from_values

#: Problem kinds.
LS, ML, MAP = 0, 1, 2

#: Value handed to the simplex at invalid points (as the Python path).
BIG = 1e300

_LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True, error_model="numpy")
def _slot(theta: np.ndarray, idx: int, k: float) -> float:
    return k * theta[idx] if idx >= 0 else k


@njit(cache=True, error_model="numpy")
def theta_of_z(z: np.ndarray, lo: np.ndarray, hi: np.ndarray, logp: np.ndarray) -> np.ndarray:
    """Physical values from direct-search variables (bounds enforced by the transform)."""
    theta = np.empty(z.shape[0])
    for i in range(z.shape[0]):
        eta = lo[i] + (hi[i] - lo[i]) * (0.5 * (1.0 + math.tanh(0.5 * z[i])))
        theta[i] = math.exp(eta) if logp[i] else eta
    return theta


@njit(cache=True, error_model="numpy")
def cost_theta(theta: np.ndarray, prob) -> float:
    """The cost at physical values ``theta``; ``inf`` where the model is invalid."""
    (
        kind,
        form,
        data,
        slots,
        _transform,
        prior,
        consts,
        e,
    ) = prob
    L, P, E, Gb0, Nf, Mf, iout = form
    t, m, u, y, groups = data
    res_idx, res_k, cap_idx, cap_k, noise_idx, noise_k = slots
    prior_idx, prior_logc, spread, weight = prior
    foh, phi2, rtol = consts
    res = np.empty(res_idx.shape[0])
    for s in range(res_idx.shape[0]):
        res[s] = _slot(theta, res_idx[s], res_k[s])
        if not (res[s] > 0.0 and res[s] < math.inf):
            return math.inf
    cap = np.empty(2)
    for s in range(2):
        cap[s] = _slot(theta, cap_idx[s], cap_k[s])
        if not (cap[s] > 0.0 and cap[s] < math.inf):
            return math.inf
    # noise slots: sigma_v, sigma_w (2), sigma_x0 (2)
    sig = np.empty(5)
    for s in range(5):
        sig[s] = _slot(theta, noise_idx[s], noise_k[s])
        if not (sig[s] >= 0.0 and sig[s] < math.inf):
            return math.inf
    P0 = np.zeros((2, 2))
    Qc = np.zeros((2, 2))
    if kind == LS:
        r = 1.0
        for k in range(e.shape[0]):
            e[k] = math.nan
        out = e
    else:
        r = sig[0] * sig[0]
        for i in range(2):
            Qc[i, i] = sig[1 + i] * sig[1 + i]
            P0[i, i] = sig[3 + i] * sig[3 + i]
        out = e[:0]
    nll, n_obs = nll_rc2_from_values(
        L, P, E, Gb0, Nf, Mf, res, cap, iout, t, m, u, y, P0, Qc, r, foh, phi2, rtol, out, groups
    )
    if n_obs < 0:
        return math.inf
    if kind == LS:
        sse = 0.0
        for k in range(e.shape[0] - 1):
            seg = 0.5 * (e[k] * e[k] + e[k + 1] * e[k + 1]) * (t[k + 1] - t[k])
            if math.isfinite(seg):
                sse += seg
        return sse
    j = nll + 0.5 * n_obs * _LOG_2PI
    if kind == MAP:
        pen = 0.0
        for i in range(prior_idx.shape[0]):
            d = (math.log(theta[prior_idx[i]]) - prior_logc[i]) / spread
            pen += d * d
        j = weight * j + 0.5 * pen
    return j


@njit(cache=True, error_model="numpy")
def cost_z(z: np.ndarray, prob) -> float:
    """The cost at direct-search variables ``z`` (:func:`theta_of_z`, then :func:`cost_theta`)."""
    lo, hi, logp = prob[4]
    return cost_theta(theta_of_z(z, lo, hi, logp), prob)


@njit(cache=True, error_model="numpy")
def _scaled(z: np.ndarray, prob, scale: float) -> float:
    v = cost_z(z, prob)
    v = v / scale if math.isfinite(v) else math.inf
    return min(v, BIG)


@njit(cache=True, error_model="numpy")
def _sort(sim: np.ndarray, fsim: np.ndarray) -> None:
    """Order the vertices by value, best first (stable for equal values)."""
    order = np.argsort(fsim, kind="mergesort")
    sim[:] = sim[order]
    fsim[:] = fsim[order]


@njit(cache=True, error_model="numpy")
def nelder_mead(
    sim: np.ndarray, prob, scale: float, xatol: float, fatol: float, max_evals: int
) -> tuple[np.ndarray, float, int, int]:
    """Minimize :func:`cost_z` ``/ scale`` from the initial simplex ``sim`` (d + 1 rows).

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
        fsim[k] = _scaled(sim[k], prob, scale)
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
            xbar += sim[k]
        xbar /= d
        worst = sim[last].copy()
        xr = 2.0 * xbar - worst
        fxr = _scaled(xr, prob, scale)
        n_evals += 1
        # the new vertex and its value; an evaluation the budget does not allow ends the search
        # before the step that needed it, as SciPy's does
        xn = xr
        fn = fxr
        if fxr < fsim[0]:
            if n_evals >= max_evals:
                break
            xe = 3.0 * xbar - 2.0 * worst
            fxe = _scaled(xe, prob, scale)
            n_evals += 1
            if fxe < fxr:
                xn = xe
                fn = fxe
        elif fxr >= fsim[last - 1]:
            if n_evals >= max_evals:
                break
            if fxr < fsim[last]:  # outside contraction
                xn = 1.5 * xbar - 0.5 * worst
                fn = _scaled(xn, prob, scale)
                n_evals += 1
                shrink = not fn <= fxr
            else:  # inside contraction
                xn = 0.5 * xbar + 0.5 * worst
                fn = _scaled(xn, prob, scale)
                n_evals += 1
                shrink = not fn < fsim[last]
            if shrink:
                for k in range(1, n_v):
                    if n_evals >= max_evals:
                        break
                    sim[k] = sim[0] + 0.5 * (sim[k] - sim[0])
                    fsim[k] = _scaled(sim[k], prob, scale)
                    n_evals += 1
                _sort(sim, fsim)
                continue
        sim[last] = xn
        fsim[last] = fn
        _sort(sim, fsim)
    return sim[0].copy(), fsim[0], n_evals, status
