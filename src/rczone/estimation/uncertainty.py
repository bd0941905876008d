"""Uncertainty of estimates: Hessian, standard errors, correlations, profile likelihood.

The Hessian of the cost is taken in ``eta`` (where the cost is closest to quadratic) by
central finite differences (of the exact gradient where it costs a few values, the adjoint of
:mod:`rczone.kernels.adjoint`; of the value otherwise), and mapped to physical units by the delta method:
``cov_theta = J cov_eta J`` with ``J = diag(d theta / d eta)``.

* For ``J_ML`` and ``J_MAP`` (negative log-likelihood / log-posterior):
  ``cov_eta = H^{-1}``.
* For ``J_LS = int e^2 dt`` (not a likelihood) the residuals are treated as white with
  variance ``sigma^2 = J / tau`` (tau = integrated time) sampled every ``dt_mean``, so
  ``-log L ~ J / (2 sigma^2 dt_mean)`` and ``cov_eta = 2 sigma^2 dt_mean H^{-1}``. This is
  approximate: open-loop errors are usually correlated, which makes it optimistic.

References
----------
.. [1] Y. Pawitan, *In All Likelihood*, Oxford University Press 2001, sections 2.9
   (profile likelihood) and 4.7 (delta method).
.. [2] P. E. Gill, W. Murray, M. H. Wright, *Practical Optimization*, 1981, section
   8.6 (finite-difference step sizes for second derivatives).
.. [3] J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, section 8.1
   (approximating the Hessian by differences of exact gradients).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from scipy.special import chdtri

from rczone.errors import ParameterError
from rczone.estimation.parameters import ParameterSpec

#: Relative step of the finite-difference Hessian, about eps^(1/4).
HESSIAN_STEP = 1e-4
#: Relative step of the Hessian from central differences of exact gradients, about eps^(1/3).
GRADIENT_HESSIAN_STEP = 1e-5
#: Relative step of the diagonal curvature from forward differences of exact gradients, about sqrt(eps).
CURVATURE_STEP = 1e-6


def hessian(f: Callable[[np.ndarray], float], x: np.ndarray, step: float = HESSIAN_STEP) -> np.ndarray:
    """Central finite-difference Hessian with steps ``h_i = step * max(1, |x_i|)``.

    Diagonal: ``(f(x+h e_i) - 2 f(x) + f(x-h e_i)) / h^2``; off-diagonal: the four-point
    formula. Error ``O(h^2)`` from truncation and ``O(eps |f| / h^2)`` from rounding,
    balanced near ``h ~ eps^(1/4)`` [2]_.

    Returns
    -------
    ndarray, shape (d, d), symmetric
    """
    x = np.asarray(x, dtype=float)
    d = x.size
    h = step * np.maximum(1.0, np.abs(x))
    f0 = f(x)
    H = np.empty((d, d))

    def at(*moves: tuple[int, float]) -> float:
        xx = x.copy()
        for i, s in moves:
            xx[i] += s * h[i]
        return f(xx)

    for i in range(d):
        H[i, i] = (at((i, 1)) - 2 * f0 + at((i, -1))) / h[i] ** 2
        for j in range(i):
            v = (at((i, 1), (j, 1)) - at((i, 1), (j, -1)) - at((i, -1), (j, 1)) + at((i, -1), (j, -1))) / (
                4 * h[i] * h[j]
            )
            H[i, j] = H[j, i] = v
    return H


def hessian_from_gradient(
    value_and_gradient: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x: np.ndarray,
    step: float = GRADIENT_HESSIAN_STEP,
) -> np.ndarray:
    """Hessian from central differences of an exact gradient, symmetrized.

    Column ``i`` is ``(g(x + h_i e_i) - g(x - h_i e_i)) / (2 h_i)`` with ``h_i = step * max(1, |x_i|)``:
    ``2 d`` gradients instead of the ``2 d^2`` values of :func:`hessian`, and one order of
    differentiation fewer, so rounding is ``O(eps |g| / h)`` and the step can be smaller [3]_. Where
    one side is invalid (a non-finite value) the one-sided difference with ``g(x)`` is taken.

    Parameters
    ----------
    value_and_gradient : callable
        ``x -> (value, gradient)``, e.g. :meth:`~rczone.estimation.costs.Objective.value_and_gradient`.
    x : ndarray, shape (d,)
        Where (eta of the optimum).
    step : float
        Relative step, about ``eps^(1/3)``.

    Returns
    -------
    ndarray, shape (d, d), symmetric
    """
    x = np.asarray(x, dtype=float)
    d = x.size
    H = np.empty((d, d))
    g0 = None
    for i in range(d):
        h = step * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        (fp, gp), (fm, gm) = value_and_gradient(xp), value_and_gradient(xm)
        if math.isfinite(fp) and math.isfinite(fm):
            H[:, i] = (gp - gm) / (xp[i] - xm[i])
            continue
        if g0 is None:
            g0 = value_and_gradient(x)[1]
        H[:, i] = (gp - g0) / (xp[i] - x[i]) if math.isfinite(fp) else (g0 - gm) / (x[i] - xm[i])
    return 0.5 * (H + H.T)


def curvature_from_gradient(
    value_and_gradient: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x: np.ndarray,
    step: float = CURVATURE_STEP,
) -> np.ndarray:
    """Diagonal of the Hessian from forward differences of an exact gradient (``d + 1`` gradients).

    ``(g_i(x + h_i e_i) - g_i(x)) / h_i`` with ``h_i = step * max(1, |x_i|)`` (backward where the
    forward point is invalid) [3]_: a variable scaling for a gradient search
    (:func:`rczone.estimation.optimize.minimize_from`), which needs the orders of magnitude only.
    Entries may be negative or non-finite away from a minimum.

    Parameters
    ----------
    value_and_gradient : callable
        ``x -> (value, gradient)``.
    x : ndarray, shape (d,)
    step : float
        Relative step, about ``sqrt(eps)``.

    Returns
    -------
    ndarray, shape (d,)
    """
    x = np.asarray(x, dtype=float)
    f0, g0 = value_and_gradient(x)
    c = np.full(x.size, np.nan)
    if not math.isfinite(f0):
        return c
    for i in range(x.size):
        for sign in (1.0, -1.0):
            xs = x.copy()
            xs[i] += sign * step * max(1.0, abs(x[i]))
            fs, gs = value_and_gradient(xs)
            if math.isfinite(fs):
                c[i] = (gs[i] - g0[i]) / (xs[i] - x[i])
                break
    return c


@dataclass(frozen=True, eq=False)
class Uncertainty:
    """Standard errors and correlations of the free parameters.

    Attributes
    ----------
    hessian_eta : ndarray, shape (d, d)
        Hessian of the cost in eta.
    cov_eta, cov_theta : ndarray, shape (d, d)
        Covariance in eta and (delta method) in theta; NaN if the Hessian is not
        positive definite.
    std_error : ndarray, shape (d,)
        Standard errors in theta (physical units).
    correlation : ndarray, shape (d, d)
    positive_definite : bool
    """

    hessian_eta: np.ndarray
    cov_eta: np.ndarray
    cov_theta: np.ndarray
    std_error: np.ndarray
    correlation: np.ndarray
    positive_definite: bool


def covariance(
    spec: ParameterSpec,
    theta_hat: np.ndarray,
    H_eta: np.ndarray,
    scale: float = 1.0,
    held: np.ndarray | None = None,
) -> Uncertainty:
    """Covariances from the Hessian of the cost in eta (``cov_eta = scale * H^{-1}``).

    ``held`` marks parameters at a bound of their box: the estimate there is not a stationary
    point, so they are treated as fixed (their rows and columns are dropped from ``H``, their
    standard errors are NaN) and the others' covariance is the inverse of the remaining block,
    the usual treatment of a boundary estimate (Pawitan 2001, section 4.7).
    """
    d = spec.n_free
    keep = np.ones(d, dtype=bool) if held is None else ~np.asarray(held, dtype=bool)
    Hk = H_eta[np.ix_(keep, keep)]
    nan = np.full((d, d), np.nan)
    if not keep.any():
        return Uncertainty(H_eta, nan, nan, np.full(d, np.nan), nan, True)
    try:
        np.linalg.cholesky(Hk)
        pd = True
    except np.linalg.LinAlgError:
        pd = False
    if not pd:
        return Uncertainty(H_eta, nan, nan, np.full(d, np.nan), nan, False)
    cov_eta = nan.copy()
    ck = scale * np.linalg.inv(Hk)
    cov_eta[np.ix_(keep, keep)] = 0.5 * (ck + ck.T)
    J = spec.jacobian(spec.to_eta(theta_hat))
    cov_theta = cov_eta * np.outer(J, J)
    se = np.sqrt(np.diag(cov_theta))
    sd_eta = np.sqrt(np.diag(cov_eta))
    corr = cov_eta / np.outer(sd_eta, sd_eta)
    return Uncertainty(H_eta, cov_eta, cov_theta, se, corr, True)


def fix_parameter(spec: ParameterSpec, name: str, value: float) -> ParameterSpec:
    """A copy of ``spec`` with ``name`` removed from the free set and fixed at ``value``."""
    if name not in spec.names:
        from rczone.errors import did_you_mean

        raise ParameterError(f"{name!r} is not a free parameter; " + did_you_mean(name, spec.names))
    keep = np.array([n != name for n in spec.names])
    if not keep.any():
        raise ParameterError("cannot profile the only free parameter: nothing is left to re-optimize")
    fixed = dict(spec.fixed)
    fixed[name] = float(value)
    return ParameterSpec(
        names=tuple(n for n in spec.names if n != name),
        kinds=tuple(k for n, k in zip(spec.names, spec.kinds) if n != name),
        log=spec.log[keep],
        start=spec.start[keep],
        lower=spec.lower[keep],
        upper=spec.upper[keep],
        construction=spec.construction[keep],
        fixed=MappingProxyType(fixed),
    )


@dataclass(frozen=True, eq=False)
class Profile:
    """Profile of the cost along one parameter.

    Attributes
    ----------
    name : str
    values : ndarray, shape (k,)
        Grid of the profiled parameter (theta).
    cost : ndarray, shape (k,)
        Minimum of the cost over the other free parameters at each grid value.
    others : ndarray, shape (k, d-1)
        The re-optimized other parameters.
    interval : tuple of float
        Where ``cost - min(cost)`` crosses ``chi2(1).ppf(level) / 2`` by linear
        interpolation (NaN where the grid does not reach it); meaningful for ML/MAP.
    """

    name: str
    values: np.ndarray
    cost: np.ndarray
    others: np.ndarray
    interval: tuple[float, float]


def profile(
    objective,
    theta_hat: np.ndarray,
    name: str,
    grid: Sequence[float] | np.ndarray,
    optimizer: str = "nelder-mead",
    level: float = 0.95,
) -> Profile:
    """Profile likelihood of parameter ``name``: re-optimize the others at each grid value.

    Parameters
    ----------
    objective : Objective
        The cost of the fit (its spec gives the free parameters).
    theta_hat : ndarray
        The optimum (start of every re-optimization).
    name : str
        Free parameter to profile.
    grid : array_like
        Values (theta) of the profiled parameter, inside its bounds.
    optimizer : str
    level : float
        Confidence level of the interval.
    """
    from rczone.estimation.optimize import minimize_from

    spec = objective.spec
    if name not in spec.names:
        from rczone.errors import did_you_mean

        raise ParameterError(
            f"cannot profile {name!r}: not a free parameter; " + did_you_mean(name, spec.names)
        )
    i = spec.names.index(name)
    grid = np.asarray(grid, dtype=float)
    if np.any(grid <= spec.lower[i]) or np.any(grid >= spec.upper[i]):
        raise ParameterError(
            f"profile grid of {name!r} must lie inside its bounds ({spec.lower[i]:g}, {spec.upper[i]:g})"
        )
    rest = np.delete(np.asarray(theta_hat, dtype=float), i)
    costs, others = np.empty(grid.size), np.empty((grid.size, spec.n_free - 1))
    for k, v in enumerate(grid):
        sub = fix_parameter(spec, name, v)
        sub_obj = dataclasses.replace(objective, spec=sub)
        out = minimize_from(sub_obj, sub, rest, optimizer)
        costs[k], others[k] = out.cost, out.end
    thr = costs.min() + 0.5 * chdtri(1, 1.0 - level)  # chi2(1) quantile
    return Profile(name, grid, costs, others, _crossings(grid, costs, thr))


def _crossings(x: np.ndarray, c: np.ndarray, thr: float) -> tuple[float, float]:
    k0 = int(np.argmin(c))
    lo = hi = math.nan
    for k in range(k0, 0, -1):
        if c[k - 1] >= thr > c[k] or c[k - 1] > thr >= c[k]:
            lo = float(np.interp(thr, [c[k], c[k - 1]], [x[k], x[k - 1]]))
            break
    for k in range(k0, x.size - 1):
        if c[k + 1] >= thr > c[k] or c[k + 1] > thr >= c[k]:
            hi = float(np.interp(thr, [c[k], c[k + 1]], [x[k], x[k + 1]]))
            break
    return lo, hi
