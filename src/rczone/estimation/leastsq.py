"""The default search of a least-squares fit: trust-region Gauss-Newton on the exact residual Jacobian.

``J_LS`` is a sum of squares, ``sum r^2`` (:mod:`rczone.kernels.residuals`), and the Jacobian of
the residuals comes with them from one compiled pass (forward sensitivities of the exact
simulation). A Gauss-Newton step uses ``J' J`` as the Hessian, which is exact at a zero-residual
fit and close to it at a good one, so the local search converges in a handful of steps where a
quasi-Newton search on ``J_LS`` alone builds its curvature from hundreds of gradients [1]_. The
local method is Levenberg-Marquardt, a trust-region Gauss-Newton method [2]_, compiled with the residual
kernel (:func:`rczone.kernels.levmar.levenberg_marquardt`: no return to Python between steps) on
``eta`` (the fit's optimizer variables: logs of the R and C) within the box of bounds, its variables
scaled by the Jacobian's column norms. SciPy's ``least_squares`` (trust-region reflective, the
same Jacobian) needs the same number of passes from a good start but spends several times the
pass's cost in Python per step, as much as the whole search here.

The global part follows :func:`rczone.estimation.search.global_search` and uses its rules: the
cost is sampled over the box, local searches start from the model's values and from the best
sampled points that are not near a used one, and the search stops once the best optimum has been
reached from two starts (with the same safety conditions: enough searches for the number of
parameters, no sampled point left unused below it, few optima unseen, no R or C at a bound).
Searches from sampled points run in stages of :data:`STAGE` evaluations and stop when, after a
stage, they are still above the best optimum. An optimum reached by one start only is confirmed
by the same search from a point displaced by :data:`rczone.estimation.search.DISPLACEMENT` of the
box; where the search from the model's values converged, that restart is the second start (run in
full), so two agreeing starts can end the search before any sampled start.

It applies to problems that pack into arrays (:func:`rczone.estimation.compiled.compiled_problem`);
the others (a free gain such as a solar aperture, massless nodes, ties that are sums) keep the
general search with L-BFGS on ``J_LS``. The name of the local method in results is :data:`NAME`.

References
----------
.. [1] J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, sections 10.3
   (Gauss-Newton) and 10.4 (its convergence on small-residual problems).
.. [2] J. J. Moré, "The Levenberg-Marquardt algorithm: implementation and theory", in *Numerical
   Analysis*, Lecture Notes in Mathematics 630, Springer 1978, 105-116 (LM as a trust-region method).
"""

from __future__ import annotations

import math

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import Objective
from rczone.estimation.optimize import INSIDE, StartOutcome
from rczone.estimation.parameters import ParameterSpec
from rczone.estimation.search import (
    LINK_RADIUS,
    MAX_AUTO_STARTS,
    POLISH_ROUNDS,
    SearchSummary,
    cost_tolerance,
    displaced,
    merge_optima,
    restart_second,
    sample_points,
    settled,
)
from rczone.kernels.levmar import BUDGET, COST, GRADIENT, INVALID, STEP, Tolerances, levenberg_marquardt

#: The name of the local method in results and reasons.
NAME = "gauss-newton"
#: Evaluations (one residual and Jacobian pass each) of one stage of a search from a sampled point.
STAGE = 10
#: Most stages of a search from a sampled point that stays below the best optimum found so far.
MAX_STAGES = 4
#: Relative tolerances on the cost decrease, the step and the gradient (MINPACK's and SciPy's
#: defaults): two end points of one optimum then agree far inside the LS tolerance of
#: :data:`rczone.estimation.methods.REGISTRY`, 1e-5 of the cost.
TOLERANCE = 1e-8
#: Messages of the statuses of :func:`rczone.kernels.levmar.levenberg_marquardt`.
STATUS = {
    COST: "converged: the relative decrease of the cost is below the tolerance",
    STEP: "converged: the relative step is below the tolerance",
    GRADIENT: "converged: the residuals are orthogonal to the Jacobian's columns",
    BUDGET: "stopped: evaluation budget exhausted",
    INVALID: "the residuals are not finite",
}


def applies(objective: Objective) -> bool:
    """Whether ``objective`` is a least-squares problem that packs into arrays (its residuals compile)."""
    problem = objective.compiled
    return problem is not None and problem.kind == 0 and objective.spec.n_free > 0


def gauss_newton(objective: Objective, theta0: np.ndarray, max_evals: int | None = None) -> StartOutcome:
    """One Levenberg-Marquardt search from physical values ``theta0``, compiled (see the module notes).

    Parameters
    ----------
    objective : Objective
        A problem for which :func:`applies` holds.
    theta0 : ndarray
        Start, inside the bounds.
    max_evals : int, optional
        Most residual and Jacobian passes; default ``100 * n_free``.

    Returns
    -------
    StartOutcome
        Its cost is the objective's at the end point; converged when a test of convergence of
        :func:`rczone.kernels.levmar.levenberg_marquardt` stopped it.

    Raises
    ------
    ParameterError
        When the residuals are not finite at the start.
    """
    spec = objective.spec
    theta0 = np.asarray(theta0, dtype=float)
    limits = Tolerances(TOLERANCE, TOLERANCE, TOLERANCE, int(max_evals or 100 * spec.n_free))
    out = levenberg_marquardt(
        np.asarray(spec.to_eta(theta0), dtype=np.float64), objective.compiled, limits, INSIDE
    )
    if out.status == INVALID:
        raise ParameterError(f"the cost is not finite at the start {dict(zip(spec.names, theta0))}")
    return StartOutcome(
        theta0,
        spec.to_theta(out.eta),
        float(objective(out.eta)),
        out.status > 0,
        out.n_evals,
        STATUS[out.status],
    )


def staged(
    objective: Objective, start: np.ndarray, best: float, tol: float, max_evals: int | None
) -> StartOutcome:
    """A search from a sampled point in stages of :data:`STAGE` evaluations, given up above ``best``.

    Most points of a box spanning decades lie in poor regions; a search from there still above the
    best optimum after a stage is stopped (its outcome says it did not converge). One below it
    continues, so a better basin is never given up.
    """
    stage = min(STAGE, max_evals) if max_evals else STAGE
    out = gauss_newton(objective, start, stage)
    n = out.n_evals
    for _ in range(MAX_STAGES - 1):
        if out.converged or not out.cost < best - tol:
            break
        out = gauss_newton(objective, out.end, stage)
        n += out.n_evals
    return StartOutcome(np.asarray(start, dtype=float), out.end, out.cost, out.converged, n, out.message)


def leastsq_search(
    objective: Objective,
    rng: np.random.Generator,
    n_starts: int | None = None,
    max_evals: int | None = None,
    scale: float = 0.0,
    progress=None,
) -> tuple[list[StartOutcome], SearchSummary]:
    """Minimize ``J_LS`` from spread starts by Gauss-Newton (see the module notes).

    Parameters
    ----------
    objective : Objective
        A least-squares problem for which :func:`applies` holds.
    rng : numpy.random.Generator
        Draws the sampled points and the displaced confirmation.
    n_starts : int, optional
        ``1``: one search from the model's values (no sampling); ``k > 1``: exactly ``k``
        searches; default adaptive, as :func:`rczone.estimation.search.global_search`.
    max_evals : int, optional
        Evaluation budget per local search.
    scale : float
        The data's squared variation (K^2 s), for :func:`rczone.estimation.search.cost_tolerance`.
    progress : object, optional
        Told ``progress.advance(done, most)`` after each search, as by
        :func:`rczone.estimation.search.global_search`.

    Returns
    -------
    outcomes : list of StartOutcome
        Every local search, in the order run.
    summary : SearchSummary
    """
    if n_starts is not None and (not isinstance(n_starts, int) or n_starts < 1):
        raise ParameterError(f"n_starts must be a positive integer (or None for automatic), got {n_starts!r}")
    spec = objective.spec
    starts, start_costs, n_sampled = spread_starts(objective, rng, n_starts)
    adaptive = n_starts is None
    outcomes: list[StartOutcome] = []

    lower_left = False
    restart = -1  # the early-agreement restart runs in full, as the confirmation it replaces
    for k, s in enumerate(starts):
        finite = [o.cost for o in outcomes if math.isfinite(o.cost)]
        try:
            if finite and k != restart:
                tol = cost_tolerance("ls", min(finite), scale)
                outcomes.append(staged(objective, s, min(finite), tol, max_evals))
            else:
                outcomes.append(gauss_newton(objective, s, max_evals))
        except ParameterError:
            if k == 0 and len(starts) > 1:  # the model's own values may be invalid for these data
                continue
            raise
        if progress is not None:
            progress.advance(k + 1, len(starts))
        if k == 0 and adaptive and outcomes[-1].converged:
            # early agreement, as global_search's gradient search: the second start is the restart near
            # the first optimum a single start would get as its confirmation anyway
            restart_second(starts, start_costs, spec, outcomes[-1].end, rng)
            restart = 1
        if adaptive and len(outcomes) >= 2:
            optima, _ = merge_optima(outcomes, "ls", scale)
            lower_left = bool(optima and any(c < optima[0].cost for c in start_costs[k + 1 :]))
            if optima and _settled(spec, outcomes, optima, lower_left):
                break
    optima, _ = merge_optima(outcomes, "ls", scale)
    if not optima:
        raise ParameterError("every local search ended at a point where the cost is not finite")
    confirmed_by = None
    if optima[0].count >= 2:
        reason = f"the best optimum was reached from {optima[0].count} of {len(outcomes)} starts"
    else:
        confirmed_by, reason = _confirm(objective, outcomes, rng, max_evals, scale)
    return outcomes, _summary(spec, outcomes, scale, n_sampled, n_starts, lower_left, confirmed_by, reason)


def _confirm(
    objective: Objective,
    outcomes: list[StartOutcome],
    rng: np.random.Generator,
    max_evals: int | None,
    scale: float,
) -> tuple[str | None, str]:
    """Confirm an optimum reached by one start by a restart near it (appended to ``outcomes``).

    Where the restart finds lower, the next round restarts near that (a few rounds at most).
    Returns the confirming method (None when the rounds kept finding lower) and the reason.
    """
    n_runs = len(outcomes)
    for _ in range(POLISH_ROUNDS):
        best = merge_optima(outcomes, "ls", scale)[0][0]
        check = gauss_newton(objective, displaced(objective.spec, best.theta, rng), max_evals)
        outcomes.append(check)
        if check.cost >= best.cost - cost_tolerance("ls", best.cost, scale):
            return NAME, (
                f"the best optimum was reached from 1 of {n_runs} starts and a restart of {NAME} near it found"
                " nothing better"
            )
    return None, (
        f"the best optimum was reached from only 1 of {n_runs} starts and restarts of {NAME} near it kept"
        f" finding lower costs ({POLISH_ROUNDS} rounds): the search has not settled"
    )


def spread_starts(
    objective: Objective, rng: np.random.Generator, n_starts: int | None
) -> tuple[list[np.ndarray], list[float], int]:
    """The model's values, then the best sampled points not near a chosen start; their costs; points sampled."""
    spec = objective.spec
    if n_starts == 1:
        return [spec.start], [math.nan], 0
    d = spec.n_free
    n_sample = int(min(256, max(32, 16 * d)))
    pts = sample_points(spec, n_sample, rng)
    vals = np.array([objective.theta_cost(p) for p in pts])  # not finite where invalid
    most = n_starts if n_starts is not None else min(MAX_AUTO_STARTS, 4 + d // 2)
    lo, hi = spec.eta_lower, spec.eta_upper
    starts, costs = [spec.start], [math.nan]
    chosen = [(spec.to_eta(spec.start) - lo) / (hi - lo)]
    for i in np.argsort(np.where(np.isfinite(vals), vals, np.inf)):
        if len(starts) >= most or not math.isfinite(vals[i]):
            break
        u = (spec.to_eta(pts[i]) - lo) / (hi - lo)
        if all(np.max(np.abs(u - c)) > LINK_RADIUS for c in chosen):
            starts.append(pts[i])
            costs.append(float(vals[i]))
            chosen.append(u)
    return starts, costs, n_sample


def _settled(spec: ParameterSpec, outcomes: list[StartOutcome], optima: tuple, lower_left: bool) -> bool:
    """:func:`rczone.estimation.search.settled`, with optima counted as found only where a search
    converged: a search from a sampled point stopped above the best optimum found no minimum."""
    found = sum(any(outcomes[i].converged for i in o.starts) for o in optima)
    return settled(spec, len(outcomes), optima, lower_left, found)


def _summary(
    spec: ParameterSpec,
    outcomes: list[StartOutcome],
    scale: float,
    n_sampled: int,
    n_starts: int | None,
    lower_left: bool,
    confirmed_by: str | None,
    reason: str,
) -> SearchSummary:
    """The :class:`~rczone.estimation.search.SearchSummary`; converged unless ``reason`` is a failure or a check below fails."""
    optima, tol = merge_optima(outcomes, "ls", scale)
    best = optima[0]
    converged = best.count >= 2 or confirmed_by is not None
    if converged and not any(outcomes[i].converged for i in best.starts):
        converged = False
        reason += f", but every search that reached it stopped early ({outcomes[best.starts[0]].message})"
    if lower_left and converged:
        converged = False
        reason += ", but a sampled point not used as a start has a lower cost (raise the number of starts)"
    ends = np.array([outcomes[i].end for i in best.starts])
    spread = {n: (float(ends[:, j].min()), float(ends[:, j].max())) for j, n in enumerate(spec.names)}
    strategy = "global" if n_starts != 1 else "local"
    return SearchSummary(
        strategy, n_sampled, len(outcomes), optima, spread, confirmed_by, converged, reason, tol
    )
