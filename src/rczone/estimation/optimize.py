"""Minimizing an identification cost: direct search, L-BFGS-B, multistart.

* ``"nelder-mead"`` and ``"powell"`` (SciPy) are the direct searches the paper uses.
  They run on ``z = logit((eta - lo) / (hi - lo))`` (see
  :meth:`~rczone.estimation.parameters.ParameterSpec.to_z`), so the bounds are enforced
  by the transform: no point outside them is evaluated and nothing is clipped.
* ``"lbfgs"``: L-BFGS-B on ``eta`` with its own box constraints and the exact gradient of
  :meth:`~rczone.estimation.costs.Objective.value_and_gradient` (one evaluation per step); a
  plain callable cost gets a central-difference gradient (:func:`central_gradient`).
* Multistart (the global search, :mod:`rczone.estimation.search`) calls :func:`minimize_from`
  from each of its starts.

References
----------
.. [1] J. A. Nelder, R. Mead, "A simplex method for function minimization", Computer
   Journal 7 (1965) 308-313.
.. [2] M. J. D. Powell, "An efficient method for finding the minimum of a function of
   several variables without calculating derivatives", Computer Journal 7 (1964) 155-162.
.. [3] R. H. Byrd, P. Lu, J. Nocedal, C. Zhu, "A limited memory algorithm for bound
   constrained optimization", SIAM J. Sci. Comput. 16 (1995) 1190-1208.
.. [4] J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006,
   section 8.1 (finite-difference step choice).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import Objective
from rczone.estimation.parameters import ParameterSpec

OPTIMIZERS = ("nelder-mead", "powell", "lbfgs")

#: Cost handed to the optimizers at points where the model is invalid.
_BIG = 1e300

#: Relative step of the central-difference gradient, about eps^(1/3).
GRADIENT_STEP = 1e-5

#: L-BFGS phases that may end on their budget and restart with rescaled variables (see ``_lbfgs``).
LBFGS_RESCALES = 2

#: L-BFGS-B's stopping tolerance on the relative decrease of the cost (scaled to 1 at the start)
#: in the global search's local searches: a night's likelihood (start about 1e4) then stops within
#: 1e-8 of its minimum; 1e-15 took 7 % more gradients there, and in 22 dimensions a restart crawled
#: along a flat valley for 14,000 evaluations (the four-zone fit: 10 s instead of 1).
LBFGS_FTOL = 1e-12

#: A phase that L-BFGS-B ends as converged while a Newton step (diagonal curvature) would still lower
#: the cost by more than this fraction of the cost at the start is not at a minimum
#: (:func:`decrement`): a new phase continues, at most :data:`LBFGS_RECHECKS` times after the last.
#: Converged ends measured: 3e-15 to 4e-7 (a 2-state fit of the shipped data C, the five-zone floor);
#: false ends: 0.7 and 793 (restarts on the floor, one stopped with -log L at +506, its optimum -461).
FALSE_CONVERGENCE = 1e-4
LBFGS_RECHECKS = 3

#: The tolerance of the last search, from the best end found (``global_search``'s polish): on the
#: flat likelihoods of rich models (the Bacher-Madsen family with noise on every state) a search
#: stopped by :data:`LBFGS_FTOL` can lie up to 0.9 in -log L short of the minimum (TiTmThTsn:
#: -3506.5 against -3507.4), enough to change which model ``select`` takes.
FINAL_FTOL = 1e-15

#: Largest |z| of a start: a start exactly on a bound (z infinite) begins this far inside it.
Z_LIMIT = 30.0

#: Fraction of each parameter's range (in eta) by which an L-BFGS end point stays inside its bounds.
INSIDE = 1e-9

#: Nelder-Mead stopping tolerance on the cost (scaled to 1 at the start).
FATOL = 1e-12

_NM_MESSAGES = (
    "Optimization terminated successfully.",
    "Maximum number of function evaluations has been exceeded.",
)


def central_gradient(
    f: Callable[[np.ndarray], float], x: np.ndarray, step: float = GRADIENT_STEP, f0: float | None = None
) -> tuple[np.ndarray, int]:
    """Central-difference gradient with step ``h_i = step * max(1, |x_i|)``.

    The step balances truncation error (order ``h^2``) against rounding error (order
    ``eps |f| / h``); with ``x = eta`` (log parameters of order 1-20) the default
    ``1e-5 ~ eps^(1/3)`` is near the optimum for smooth costs [4]_. Where one side is
    not finite (an invalid model), the one-sided difference with ``f0 = f(x)`` is used.

    Returns
    -------
    grad : ndarray
    n_evals : int
    """
    x = np.asarray(x, dtype=float)
    g = np.empty_like(x)
    n = 0
    for i in range(x.size):
        h = step * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        fp, fm = f(xp), f(xm)
        n += 2
        if math.isfinite(fp) and math.isfinite(fm):
            g[i] = (fp - fm) / (xp[i] - xm[i])  # the step actually taken in floating point
            continue
        if f0 is None:
            f0 = f(x)
            n += 1
        if math.isfinite(fp):
            g[i] = (fp - f0) / (xp[i] - x[i])
        elif math.isfinite(fm):
            g[i] = (f0 - fm) / (x[i] - xm[i])
        else:
            g[i] = 0.0
    return g, n


@dataclass(frozen=True)
class StartOutcome:
    """What one start of the optimizer produced.

    Attributes
    ----------
    start, end : ndarray
        Start and end parameter values (theta, physical units).
    cost : float
        Cost at ``end``.
    converged : bool
    n_evals : int
        Cost evaluations (gradient evaluations included).
    message : str
    hessian : ndarray or None
        Hessian of the cost in eta at ``end``, where the search computed it (a global search's
        first gradient search: it scales the restart that confirms it,
        :func:`rczone.estimation.search.global_search`); None otherwise.
    """

    start: np.ndarray
    end: np.ndarray
    cost: float
    converged: bool
    n_evals: int
    message: str
    hessian: np.ndarray | None = None


class Remembered:
    """A cost whose value-and-gradient calls remember their last few points (exact repeats are free).

    A gradient search asks for the same point more than once: its start value, the curvature scaling
    at that start (:func:`~rczone.estimation.uncertainty.curvature_from_gradient` begins there), the
    end point again for the outcome's cost and for the next phase's scaling, a budgeted search's next
    stage at the previous one's end. The cost is a pure function of ``eta``, so a repeated point
    returns the stored value and gradient (bit for bit what the cost would return); only points
    equal in every bit are repeats. Attributes other than the value and gradient are the cost's.

    Parameters
    ----------
    cost : Objective or callable
        The cost, with ``value_and_gradient(eta)``.
    size : int
        Points remembered (the most recent).
    """

    def __init__(self, cost: Callable[[np.ndarray], float], size: int = 4) -> None:
        self.cost, self.size = cost, size
        self._seen: dict[bytes, tuple[float, np.ndarray]] = {}

    def __getattr__(self, name: str):
        return getattr(self.cost, name)

    def __call__(self, eta: np.ndarray) -> float:
        return self.cost(eta)

    def value_and_gradient(self, eta: np.ndarray) -> tuple[float, np.ndarray]:
        """The cost's value and gradient at ``eta``, computed once per distinct point.

        Parameters
        ----------
        eta : ndarray, shape (d,)
            Optimizer values.

        Returns
        -------
        value : float
        gradient : ndarray, shape (d,)
            A copy: changing it does not change what is remembered.
        """
        key = np.asarray(eta, dtype=float).tobytes()
        hit = self._seen.get(key)
        if hit is None:
            hit = self.cost.value_and_gradient(eta)
            if len(self._seen) >= self.size:
                self._seen.pop(next(iter(self._seen)))  # the oldest
            self._seen[key] = hit
        return hit[0], hit[1].copy()


def remembered(cost: Callable[[np.ndarray], float]) -> Callable[[np.ndarray], float]:
    """``cost`` as a :class:`Remembered` where it has an exact gradient (else unchanged).

    Parameters
    ----------
    cost : callable
        A cost of ``eta``, with or without ``value_and_gradient``; one already remembered is
        returned as it is.

    Returns
    -------
    callable
    """
    if isinstance(cost, Remembered) or getattr(cost, "value_and_gradient", None) is None:
        return cost
    return Remembered(cost)


class _Counted:
    """Wrap a cost to count evaluations and scale it (no state outside the instance)."""

    def __init__(self, f: Callable[[np.ndarray], float], scale: float) -> None:
        self.f, self.scale, self.n = f, scale, 0

    def __call__(self, x: np.ndarray) -> float:
        self.n += 1
        v = self.f(x)
        return v / self.scale if math.isfinite(v) else math.inf


def minimize_from(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    theta0: np.ndarray,
    optimizer: str = "nelder-mead",
    max_evals: int | None = None,
    tol: float = 1e-7,
    *,
    curvature: np.ndarray | None = None,
    ftol: float | None = None,
) -> StartOutcome:
    """Minimize ``cost(eta)`` from physical values ``theta0``.

    Parameters
    ----------
    cost : callable
        Cost as a function of ``eta`` (e.g. an :class:`~rczone.estimation.costs.Objective`).
    spec : ParameterSpec
    theta0 : ndarray
        Start, strictly inside the bounds.
    optimizer : {"nelder-mead", "powell", "lbfgs"}
    max_evals : int, optional
        Evaluation budget; default ``2000 * n_free``.
    tol : float
        Tolerance on the parameters in eta (or z) units: about the relative precision of
        the estimates (1e-7 is far below any standard error and saves half the evaluations
        of a tighter setting).
    curvature : ndarray, optional
        ``"lbfgs"``: the diagonal curvature (in eta) that scales the first phase, known already
        (the Hessian's diagonal at a nearby optimum); default computed at the start.
    ftol : float, optional
        ``"lbfgs"``: the stopping tolerance on the relative decrease of the cost (default
        :data:`LBFGS_FTOL`; the global search's final polish uses :data:`FINAL_FTOL`).

    Returns
    -------
    StartOutcome
    """
    if optimizer not in OPTIMIZERS:
        raise ParameterError(f"optimizer must be one of {OPTIMIZERS}, got {optimizer!r}")
    theta0 = np.asarray(theta0, dtype=float)
    d = spec.n_free
    max_evals = max_evals or 2000 * d
    eta0 = spec.to_eta(theta0)
    if optimizer == "lbfgs":
        cost = remembered(cost)
    value = _value_of(cost, optimizer)
    f0 = value(eta0)
    if not math.isfinite(f0):
        raise ParameterError(f"the cost is not finite at the start {dict(zip(spec.names, theta0))}")
    # a cost of order one makes the absolute and relative tolerances meaningful
    counted = _Counted(cost, max(abs(f0), 1e-300))
    if optimizer == "lbfgs":
        eta, converged, message = _lbfgs(cost, spec, eta0, counted, max_evals, curvature, ftol or LBFGS_FTOL)
    else:

        def fz(z: np.ndarray) -> float:
            return min(counted(spec.from_z(z)), _BIG)

        z0 = np.clip(spec.to_z(eta0), -Z_LIMIT, Z_LIMIT)  # a start on a bound: just inside it
        simplex = z0 + np.vstack([np.zeros(d), 0.5 * np.eye(d)])
        problem = cost.compiled if optimizer == "nelder-mead" and isinstance(cost, Objective) else None
        if problem is not None:
            from rczone.kernels.neldermead import nelder_mead

            # the same search without leaving compiled code
            z, _, n, status = nelder_mead(simplex, problem, counted.scale, tol, FATOL, max_evals)
            eta = spec.from_z(z)
            theta = spec.to_theta(eta)
            message = _NM_MESSAGES[status]
            return StartOutcome(theta0, theta, float(cost(eta)), status == 0, n + 2, message)
        from scipy import optimize  # imported here: 0.2 s of start-up a compiled search never needs

        if optimizer == "nelder-mead":
            opts = {"xatol": tol, "fatol": FATOL, "maxfev": max_evals, "initial_simplex": simplex}
            res = optimize.minimize(fz, z0, method="Nelder-Mead", options=opts)
        else:
            opts = {"xtol": tol, "ftol": 1e-15, "maxfev": max_evals}
            res = optimize.minimize(fz, z0, method="Powell", options=opts)
        eta = spec.from_z(res.x)
        converged, message = bool(res.success), str(res.message)
    theta = spec.to_theta(eta)
    return StartOutcome(theta0, theta, float(value(eta)), converged, counted.n + 2, message)


def _value_of(cost: Callable[[np.ndarray], float], optimizer: str) -> Callable[[np.ndarray], float]:
    """The cost as an L-BFGS search with an adjoint gradient evaluates it: from that one kernel.

    The search itself evaluates nothing else, so a first fit compiles one kernel; the values agree
    with the value kernel's to its steady-state tolerance (:mod:`rczone.kernels.adjoint`).
    """
    if optimizer == "lbfgs" and getattr(cost, "adjoint_gradient", False):
        return lambda eta: cost.value_and_gradient(eta)[0]
    return cost


def _lbfgs(
    cost,
    spec: ParameterSpec,
    eta0: np.ndarray,
    counted: _Counted,
    max_evals: int,
    first: np.ndarray | None,
    ftol: float,
) -> tuple:
    """L-BFGS-B on ``eta`` in phases, each on variables scaled by the cost's curvature at its start.

    With :meth:`~rczone.estimation.costs.Objective.value_and_gradient` the exact gradient
    comes with every evaluation (one evaluation per step). L-BFGS starts from a multiple of
    the identity as its Hessian model, which is poor when the curvatures of the parameters
    differ by orders of magnitude (a resistance known to 0.3 % beside a noise level known to
    30 %: condition numbers of 1e5 and hundreds of iterations). So each phase optimizes
    ``xi = eta * sqrt(c)`` with ``c`` the diagonal curvature of
    :meth:`~rczone.estimation.costs.Objective.curvature` (Fisher information or Gauss-Newton;
    diagonal scaling keeps the box bounds boxes; where the gradient is the adjoint pass, the diagonal
    of the Hessian from differences of gradients,
    :func:`~rczone.estimation.uncertainty.curvature_from_gradient`), and a phase that runs out of its budget
    (``20 + 2 d`` evaluations, at most :data:`LBFGS_RESCALES` times) restarts with the curvature
    where it ended [1]_. ``first``, where given, is the first phase's curvature. A plain
    callable cost gets a central-difference gradient and no scaling.

    Returns ``(eta, converged, message)``.

    References
    ----------
    .. [1] J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006,
       sections 7.2 (L-BFGS, the initial matrix) and 2.2 (scaling).
    """
    exact = getattr(cost, "value_and_gradient", None)
    curvature = getattr(cost, "curvature", None)
    if getattr(cost, "adjoint_gradient", False):
        # differences of the adjoint gradient (d + 1 of them): no forward-sensitivity kernel to compile
        from rczone.estimation.uncertainty import curvature_from_gradient

        def curvature(eta: np.ndarray) -> np.ndarray:
            return curvature_from_gradient(exact, eta)

    d = spec.n_free
    eta = np.asarray(eta0, dtype=float)
    phases = [*(20 + 2 * d,) * LBFGS_RESCALES, None] if curvature is not None else [None]
    rechecks = LBFGS_RECHECKS
    for k, budget in enumerate(phases):
        left = max_evals - counted.n
        if left <= 0:  # before the curvature: d gradients for a phase that would not run
            break
        if curvature is None:
            scale = np.ones(d)
        else:
            scale = _variable_scale(first if k == 0 and first is not None else curvature(eta))

        def fun(x: np.ndarray, scale: np.ndarray = scale) -> tuple[float, np.ndarray]:
            e = x / scale
            if exact is not None:
                counted.n += 1
                fe, ge = exact(e)
                fe, ge = fe / counted.scale, ge / counted.scale
            else:
                fe = counted(e)
                ge = None
            if not math.isfinite(fe):  # invalid point: a huge finite value makes the line search back off
                return _BIG, np.zeros_like(e)
            if ge is None:
                ge = central_gradient(counted, e, f0=fe)[0]
            return fe, ge / scale

        res = lbfgsb(
            fun,
            eta * scale,
            spec.eta_lower * scale,
            spec.eta_upper * scale,
            maxfun=min(left, budget or left),
            ftol=ftol,
            gtol=1e-9,
            maxiter=max_evals,
        )
        # strictly inside the box, as the direct searches' transform keeps every point: an estimate
        # exactly on a bound could not start a later fit (starts must lie inside the bounds)
        inside = INSIDE * (spec.eta_upper - spec.eta_lower)
        end = np.clip(res.x / scale, spec.eta_lower, spec.eta_upper)
        eta = np.clip(end, spec.eta_lower + inside, spec.eta_upper - inside)
        if res.success and curvature is not None and exact is not None:
            n, g_end = counted.n, fun(res.x)[1]
            counted.n = n  # the end point was evaluated: its repeat (remembered) is not counted
            low, high = spec.eta_lower * scale, spec.eta_upper * scale
            if decrement(g_end, res.x, low, high, counted.scale) > FALSE_CONVERGENCE:
                # L-BFGS-B's relative-reduction test can stop where its line search crawled (a memory
                # of poor curvature pairs), the gradient far from zero: a fresh phase goes on
                if k == len(phases) - 1 and rechecks > 0 and counted.n < max_evals:
                    rechecks -= 1
                    phases.append(None)
                if k < len(phases) - 1:
                    continue
                return eta, False, f"{res.message} (but the gradient is far from zero)"
        converged = bool(res.success) or (
            "ABNORMAL" in str(res.message) and _is_stationary(fun(res.x)[1] * scale, end, spec)
        )
        if converged:
            return eta, True, str(res.message)
    return eta, False, str(res.message)


class LbfgsbResult(NamedTuple):
    """The end of :func:`lbfgsb`: the fields of SciPy's ``OptimizeResult`` that the searches read."""

    x: np.ndarray  #: the end point
    fun: float  #: the cost there
    nfev: int  #: distinct points evaluated
    success: bool  #: stopped by a convergence test
    message: str  #: SciPy's status and task message, e.g. ``"CONVERGENCE: RELATIVE REDUCTION OF F <= ..."``


def lbfgsb(
    fun: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    maxfun: int,
    ftol: float,
    gtol: float,
    maxiter: int,
) -> LbfgsbResult:
    """``scipy.optimize.minimize(fun, x0, jac=True, method="L-BFGS-B", ...)`` without its per-step wrapping.

    The same L-BFGS-B iteration [3]_ (SciPy's ``setulb``, called with the arguments and in the
    loop of SciPy's ``_minimize_lbfgsb``: memory 10, 20 line-search steps, the stopping tests on
    ``maxfun`` and ``maxiter`` at each new iterate), so the same iterates bit for bit
    (``tests/unit/estimation/test_optimize.py`` compares them with ``minimize``), but without
    SciPy's ``ScalarFunction`` around ``fun``: that wrapping (copies, comparisons, bookkeeping)
    cost about 15 us per evaluation, a third of a 2-state likelihood gradient. Where the
    installed SciPy has another ``setulb`` (a private function), ``minimize`` itself is called.

    Parameters
    ----------
    fun : callable
        ``x -> (f, gradient)``.
    x0 : ndarray
        Start (clipped into the box, as SciPy does).
    lower, upper : ndarray
        Finite bounds.
    maxfun, maxiter : int
        Most evaluations and iterations (SciPy's options of the same names).
    ftol, gtol : float
        SciPy's stopping tolerances (relative decrease of ``f``, projected gradient).

    Returns
    -------
    LbfgsbResult
    """
    lower = np.asarray(lower, dtype=np.float64)
    upper = np.asarray(upper, dtype=np.float64)
    x = np.array(np.clip(np.asarray(x0, dtype=np.float64).ravel(), lower, upper), dtype=np.float64)
    setulb = _setulb()
    if setulb is None:
        from scipy import optimize

        res = optimize.minimize(
            fun,
            x,
            jac=True,
            method="L-BFGS-B",
            bounds=list(zip(lower, upper)),
            options={"maxfun": maxfun, "ftol": ftol, "gtol": gtol, "maxiter": maxiter},
        )
        return LbfgsbResult(res.x, float(res.fun), int(res.nfev), bool(res.success), str(res.message))
    n, m = x.size, _MAXCOR
    factr = ftol / np.finfo(float).eps
    nbd = np.full(n, 2, dtype=np.int32)  # both bounds
    f = 0.0
    g = np.zeros(n, dtype=np.float64)
    wa = np.zeros(2 * m * n + 5 * n + 11 * m * m + 8 * m, np.float64)
    iwa = np.zeros(3 * n, dtype=np.int32)
    task = np.zeros(2, dtype=np.int32)
    ln_task = np.zeros(2, dtype=np.int32)
    lsave = np.zeros(4, dtype=np.int32)
    isave = np.zeros(44, dtype=np.int32)
    dsave = np.zeros(29, dtype=np.float64)
    # SciPy evaluates at the start first and then only at points that differ from the last one
    f, g = fun(x.copy())
    last = x.copy()
    nfev, n_iterations = 1, 0
    while True:
        g = np.array(g, dtype=np.float64)  # a copy, as SciPy's loop passes
        setulb(
            m, x, lower, upper, nbd, f, g, factr, gtol, wa, iwa, task, lsave, isave, dsave, _MAXLS, ln_task
        )
        if task[0] == 3:
            if not np.array_equal(x, last):
                f, g = fun(x.copy())
                last = x.copy()
                nfev += 1
        elif task[0] == 1:
            n_iterations += 1
            if n_iterations >= maxiter:
                task[0], task[1] = 5, 504
            elif nfev > maxfun:
                task[0], task[1] = 5, 502
        else:
            break
    from scipy.optimize._lbfgsb_py import status_messages, task_messages

    message = status_messages[int(task[0])] + ": " + task_messages[int(task[1])]
    return LbfgsbResult(x, float(f), nfev, bool(task[0] == 4), message)


#: L-BFGS-B's memory and line-search steps: SciPy's defaults (``maxcor``, ``maxls``).
_MAXCOR = 10
_MAXLS = 20


def _setulb():
    """SciPy's compiled L-BFGS-B step, where it has the signature :func:`lbfgsb` calls (else None)."""
    try:
        from scipy.optimize import _lbfgsb
    except ImportError:
        return None
    setulb = getattr(_lbfgsb, "setulb", None)
    doc = getattr(setulb, "__doc__", "") or ""
    if not doc.startswith("setulb(m,x,l,u,nbd,f,g,factr,pgtol,wa,iwa,task,lsave,isave,dsave,maxls,ln_task)"):
        return None
    return setulb


def _variable_scale(curv: np.ndarray) -> np.ndarray:
    """``sqrt(curvature)``, with non-positive or non-finite entries set to the geometric mean of the others."""
    c = np.asarray(curv, dtype=float)
    ok = np.isfinite(c) & (c > 0)
    if not ok.any():
        return np.ones(c.size)
    s = np.sqrt(np.where(ok, c, 1.0))
    return np.where(ok, s, float(np.exp(np.mean(np.log(s[ok])))))


def decrement(g: np.ndarray, x: np.ndarray, lower: np.ndarray, upper: np.ndarray, size: float) -> float:
    """The decrease a Newton step would still make, relative to the cost's size at the start.

    ``g`` is the gradient of the cost divided by ``size`` in variables scaled so that the cost's
    curvature is about one along each (``_lbfgs``'s phases); the components that push out of the box
    at a bound are dropped. In the cost's own units the diagonal Newton model predicts
    ``0.5 size^2 |g|^2`` [1]_, which is ``0.5 size |g|^2`` of ``size``.

    References
    ----------
    .. [1] S. Boyd, L. Vandenberghe, *Convex Optimization*, Cambridge University Press 2004,
       section 9.5.1 (the Newton decrement).
    """
    out = ((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0))
    g = np.where(out, 0.0, g)
    return float(0.5 * size * np.dot(g, g))


def _is_stationary(g: np.ndarray, eta: np.ndarray, spec: ParameterSpec) -> bool:
    """L-BFGS-B line-search failures at a point whose projected gradient ``g`` is tiny count as converged."""
    at_lo = (eta <= spec.eta_lower) & (g > 0)
    at_hi = (eta >= spec.eta_upper) & (g < 0)
    g = np.where(at_lo | at_hi, 0.0, g)
    return bool(np.max(np.abs(g)) < 1e-6)
