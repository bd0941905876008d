"""A fit by minimization: the global search on an objective, its uncertainty and its flags.

The methods that search (:mod:`rczone.estimation.methods`: ``ls``, ``ml``, ``map``, and any
plug-in whose objective is an :class:`~rczone.estimation.costs.Objective`) end here: the search
(Gauss-Newton on the residual Jacobian where least squares packs into arrays, else the global
search of :mod:`rczone.estimation.search`), the Hessian's standard errors and correlations, and
the flags that say when a result should not be trusted; the frozen
:class:`~rczone.estimation.result.FitResult` comes out.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   (eq. 8: output-error least squares; eq. 9: Kalman-filter maximum likelihood).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np

from rczone.estimation import leastsq
from rczone.estimation.costs import Objective, filter_arrays, simulate_output, trapezoid_sse
from rczone.estimation.data import Dataset
from rczone.estimation.engines import general_cost
from rczone.estimation.kalman import kalman_innovations_fast
from rczone.estimation.methods import FitProblem, Method, method_of
from rczone.estimation.optimize import StartOutcome
from rczone.estimation.result import FitResult
from rczone.estimation.search import COST_TIE, SearchSummary, global_search
from rczone.estimation.uncertainty import covariance, hessian, hessian_from_gradient
from rczone.network import RCNetwork
from rczone.network.stochastic import unit_of as stochastic_unit
from rczone.results import Estimate


def minimize_fit(problem: FitProblem, objective: Objective, rng: np.random.Generator) -> FitResult:
    """Minimize ``objective`` over ``problem``'s free parameters, with uncertainty and flags.

    Parameters
    ----------
    problem : FitProblem
        The network, data set, free parameters and search budget.
    objective : Objective
        The cost the method minimizes (its kernel, prior and tempering set by the method).
    rng : numpy.random.Generator
        Draws the global phase.

    Returns
    -------
    FitResult
    """
    meth = method_of(problem.method)
    data, spec = problem.data, problem.spec
    scale = trapezoid_sse(data.t, data.y - np.nanmean(data.y, axis=0)) if meth.kernel == "ls" else 0.0
    optimizer = problem.optimizer
    if optimizer == "auto" and leastsq.applies(objective):  # Gauss-Newton on the residual Jacobian
        optimizer = leastsq.NAME
        outcomes, search = leastsq.leastsq_search(
            objective, rng, problem.n_starts, problem.max_evals, scale, progress=problem.progress
        )
    else:
        optimizer = "lbfgs" if optimizer == "auto" else optimizer  # every Objective has its exact gradient
        outcomes, search = global_search(
            objective,
            spec,
            problem.method,
            rng,
            optimizer,
            problem.n_starts,
            problem.max_evals,
            scale=scale,
            progress=problem.progress,
        )
    best = winning_end(outcomes, search.optima[0].starts)
    win = outcomes[best]
    theta = win.end
    near = spec.near_bound(theta)
    unc = _uncertainty(problem, objective, meth, win) if problem.uncertainty else None
    flags = _flags(problem, theta, near, search, unc)
    values = spec.values(theta)
    se = unc.std_error if unc is not None else np.full(spec.n_free, np.nan)
    return FitResult(
        parameters=estimates(problem, theta, se, near),
        correlation=unc.correlation if unc is not None else np.full((spec.n_free, spec.n_free), np.nan),
        objective_value=win.cost,
        method=problem.method,
        engine=objective.engine,
        optimizer=optimizer,
        hold=problem.hold,
        converged=search.converged,
        n_evals=search.n_sampled + sum(o.n_evals for o in outcomes),
        starts=tuple(outcomes),
        best_start=best,
        rmse_K=_rmse(objective, theta, values),
        rmse_kind=meth.rmse_kind,
        llf=log_likelihood(problem.network, values, data, meth, problem.hold, win.cost),
        nobs=int(np.isfinite(data.y).sum()),
        fixed={k: v for k, v in values.items() if k not in spec.names},
        flags=tuple(flags.flags),
        search=search,
        notes=tuple(flags.notes),
        issues=tuple(dict.fromkeys(flags.issues)),
    )


class _Uncertainty(NamedTuple):
    """Standard errors and correlation of the estimates, and whether the Hessian was positive definite."""

    std_error: np.ndarray
    correlation: np.ndarray
    positive_definite: bool


def _uncertainty(problem: FitProblem, objective: Objective, meth: Method, win: StartOutcome) -> _Uncertainty:
    """The covariance of the winning end from the objective's Hessian in ``eta`` (estimates at a bound held)."""
    spec, data, theta = problem.spec, problem.data, win.end
    if win.hessian is not None:  # the search computed it at this end (search.global_search)
        H = win.hessian
    elif objective.backward_gradient:
        # 2 d gradients of a few likelihoods each, not 2 d^2 values, and one differentiation fewer
        H = hessian_from_gradient(objective.value_and_gradient, spec.to_eta(theta))
    else:
        H = hessian(objective, spec.to_eta(theta))
    scale = 1.0
    if meth.kernel == "ls":  # sigma^2 of the output error from the cost, per sample interval
        dt = np.diff(data.t)
        obs = np.isfinite(data.y).all(axis=1)
        tau = float(np.sum(dt[obs[:-1] & obs[1:]]))
        scale = 2.0 * win.cost / tau * float(np.mean(dt)) if tau > 0 else math.nan
    unc = covariance(spec, theta, H, scale, held=spec.near_bound(theta))
    return _Uncertainty(unc.std_error, unc.correlation, unc.positive_definite)


class _Flags(NamedTuple):
    """What makes a result untrustworthy (``flags`` with their ``issues`` codes), and plain ``notes``."""

    flags: list[str]
    notes: list[str]
    issues: list[str]


def _flags(
    problem: FitProblem, theta: np.ndarray, near: np.ndarray, search: SearchSummary, unc: _Uncertainty | None
) -> _Flags:
    """The flags of a minimum: Hessian, missing standard errors, bounds, convergence, disagreeing starts."""
    spec = problem.spec
    names = spec.names
    out = _Flags([], [], [])
    if unc is not None:
        if not unc.positive_definite:
            out.issues.append("hessian")
            out.flags.append(
                "Hessian not positive definite: the parameters are not identifiable from these data"
            )
        missing = [n for n, v, b in zip(names, unc.std_error, near) if not math.isfinite(v) and not b]
        if missing and unc.positive_definite:
            out.issues.append("std_error")
            out.flags.append(f"no standard error for {', '.join(missing)}")
    eta = spec.to_eta(theta)
    lower_side = eta - spec.eta_lower <= spec.eta_upper - eta
    for n, b, low, kind in zip(names, near, lower_side, spec.kinds):
        if not b:
            continue
        if kind == "noise" and low:
            out.notes.append(
                f"{n} is at its lower bound {spec.lower[names.index(n)]:.3g}: that noise is negligible"
            )
        else:
            out.issues.append("at_bound")
            out.flags.append(f"{n} is at a bound")
    if not search.converged:
        out.issues.append("not_converged")
        out.flags.append(f"not converged: {search.reason}")
    for n, kind in zip(names, spec.kinds):
        lo_v, hi_v = search.spread[n]
        if kind in ("resistance", "capacitance", "gain") and search.n_best >= 2:
            rel = (hi_v / lo_v if lo_v > 0 else math.inf) if kind != "gain" else abs(hi_v - lo_v)
            wide = rel > 1.1 if kind != "gain" else rel > 0.1 * max(abs(hi_v), 1e-12)
            if wide:
                out.issues.append("starts_disagree")
                out.flags.append(
                    f"starts that reach the same cost disagree on {n} ({lo_v:.3g} to {hi_v:.3g}):"
                    " the data do not determine it"
                )
    return out


def point_result(
    problem: FitProblem,
    theta: np.ndarray,
    *,
    cost: float,
    n_evals: int,
    converged: bool,
    optimizer: str,
    message: str = "",
) -> FitResult:
    """The :class:`~rczone.estimation.result.FitResult` of a method that found one point by its own means.

    For a plug-in method (docs/extending.md) that runs its own optimizer: the estimates at
    ``theta`` with their bounds and construction values, no standard errors (NaN; a method that
    has them builds its result itself), the flags of a minimum (estimates at a bound, not
    converged), the RMSE of the method's kernel and the log-likelihood of a stochastic method.

    Parameters
    ----------
    problem : FitProblem
    theta : ndarray, shape (d,)
        The estimates, physical units, in the order of ``problem.spec.names``.
    cost : float
        The method's objective at ``theta``.
    n_evals : int
        Objective evaluations.
    converged : bool
        Whether the method's own search converged.
    optimizer : str
        What found ``theta``, for the result's record.
    message : str
        The optimizer's message.

    Returns
    -------
    FitResult
    """
    meth = method_of(problem.method)
    spec = problem.spec
    theta = np.asarray(theta, dtype=float)
    near = spec.near_bound(theta)
    start = StartOutcome(spec.start, theta, float(cost), bool(converged), int(n_evals), message)
    flags, issues = [], []
    for n, b in zip(spec.names, near):
        if b:
            issues.append("at_bound")
            flags.append(f"{n} is at a bound")
    if not converged:
        issues.append("not_converged")
        flags.append(f"not converged: {message or optimizer}")
    values = spec.values(theta)
    d = spec.n_free
    return FitResult(
        parameters=estimates(problem, theta, np.full(d, np.nan), near),
        correlation=np.full((d, d), np.nan),
        objective_value=float(cost),
        method=problem.method,
        engine="plug-in",
        optimizer=optimizer,
        hold=problem.hold,
        converged=bool(converged),
        n_evals=int(n_evals),
        starts=(start,),
        best_start=0,
        rmse_K=rmse_of(problem.network, values, problem.data, problem.method, problem.hold),
        rmse_kind=meth.rmse_kind,
        llf=log_likelihood(problem.network, values, problem.data, meth, problem.hold, float(cost)),
        nobs=int(np.isfinite(problem.data.y).sum()),
        fixed={k: v for k, v in values.items() if k not in spec.names},
        flags=tuple(flags),
        issues=tuple(dict.fromkeys(issues)),
    )


def estimates(
    problem: FitProblem, theta: np.ndarray, se: np.ndarray, near: np.ndarray
) -> dict[str, Estimate]:
    """One :class:`~rczone.results.Estimate` per free parameter, in the spec's order.

    Parameters
    ----------
    problem : FitProblem
    theta : ndarray, shape (d,)
        The estimates, physical units.
    se : ndarray, shape (d,)
        Their standard errors (NaN where unavailable).
    near : ndarray of bool, shape (d,)
        Whether each is at a bound.
    """
    spec = problem.spec
    return {
        n: Estimate(
            name=n,
            value=float(v),
            std_error=float(e),
            lower=float(lo),
            upper=float(hi),
            construction=float(c),
            at_bound=bool(b),
            unit=unit_of(problem.network, n),
            kind=k,
            log_scale=bool(lg),
        )
        for n, v, e, lo, hi, c, b, k, lg in zip(
            spec.names, theta, se, spec.lower, spec.upper, spec.construction, near, spec.kinds, spec.log
        )
    }


def rmse_of(network: RCNetwork, values: Mapping[str, float], data: Dataset, method: str, hold: str) -> float:
    """Open-loop RMSE (an ``"ls"`` kernel) or one-step-ahead RMSE (an ``"ml"`` kernel), K."""
    if method_of(method).kernel == "ls":
        e = data.y - simulate_output(network, values, data, hold)[1]
    else:
        e = kalman_innovations_fast(filter_arrays(network, values, data, hold))
    return float(np.sqrt(np.nanmean(e**2)))


def _rmse(objective: Objective, theta: np.ndarray, values: Mapping[str, float]) -> float:
    """The fit's RMSE (:func:`rmse_of`), from the compiled kernel's own errors where it keeps them.

    A 2-state likelihood fit takes the one-step errors from the adjoint kernel's forward pass
    (:meth:`~rczone.estimation.costs.Objective.innovations`), a 2-state least-squares fit the
    open-loop errors from the fused value kernel (:meth:`~rczone.estimation.costs.Objective.output_errors`),
    instead of a general filter or simulation (0.5 ms of a 4 ms least-squares fit).
    """
    eta = objective.spec.to_eta(theta)
    e = objective.innovations(eta) if objective.adjoint_gradient else objective.output_errors(eta)
    if e is None:
        return rmse_of(objective.network, values, objective.data, objective.method, objective.hold)
    return float(np.sqrt(np.nanmean(e**2)))


def winning_end(outcomes: Sequence[StartOutcome], starts: Sequence[int]) -> int:
    """The end of the best optimum that a fit reports: the lowest, or one tied with it that has its Hessian.

    Among ends whose costs agree to :data:`COST_TIE`, the one whose Hessian the search computed
    (:attr:`~rczone.estimation.optimize.StartOutcome.hessian`) is taken, so the standard errors
    need no second Hessian.

    Parameters
    ----------
    outcomes : sequence of StartOutcome
        Every local search of the fit.
    starts : sequence of int
        Indices of the searches that reached the best optimum.

    Returns
    -------
    int
        An index of ``starts``' searches into ``outcomes``.
    """
    lowest = min(starts, key=lambda i: outcomes[i].cost)
    floor = outcomes[lowest].cost
    tied = [i for i in starts if outcomes[i].cost - floor <= COST_TIE * max(abs(floor), 1.0)]
    return next((i for i in tied if outcomes[i].hessian is not None), lowest)


def log_likelihood(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, kind: Method, hold: str, objective: float
) -> float:
    """The log-likelihood at the estimate: ``-objective`` where that is the negative log-likelihood (ML).

    Recomputed for any other stochastic method (MAP without prior or tempering, a plug-in's own
    criterion); NaN for a method without a noise model (least squares has no likelihood of its own).
    """
    if not kind.stochastic:
        return math.nan
    if kind.objective.startswith("negative log-likelihood"):
        return -float(objective)
    return -float(general_cost(network, values, data, hold, "ml", ())[0])


def unit_of(network: RCNetwork, name: str) -> str:
    """SI unit of a free parameter, for tables."""
    if name in network.parameters:
        return network.parameters[name].unit or ""
    return stochastic_unit(name) or ""
