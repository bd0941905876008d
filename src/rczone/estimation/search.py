"""Global search: the default way rczone minimizes an identification cost.

Identification costs of grey-box building models are not convex: a single local search from
construction values can stop in a worse optimum (a resistance 60x off) and still report that it
converged. The search here is a two-phase stochastic method [1]_:

1. **Global phase.** The cost is evaluated at a Latin hypercube of points spread over the whole
   box of bounds, in the optimizer's variables ``eta`` (log space for resistances, capacities and
   noise levels).
2. **Local phase.** Local searches start from the model's own start values and from the best
   sampled points that are not near a better one already used (single linkage in the unit box).
   They run until the best optimum has been reached from two starts, no sampled point left
   unused has a lower cost than it, few optima remain unseen (:func:`few_unseen`) and no
   resistance, capacity or gain of that optimum sits at a bound (such degenerate optima attract
   many starts) - at least :func:`min_local_searches` runs (two up to 7 free parameters, more
   beyond), at most ``max_local`` - or, with a fixed number of starts, that many runs.
3. **Merge and confirm.** End points whose costs agree within a tolerance are one optimum; the
   distinct optima, how many starts reached each, and the spread of the estimates among the starts
   that reached the best one are reported. The result is *converged* only when the best optimum
   was reached from more than one start, or when a second local method started at it finds nothing
   better (where it does find lower, the first method continues from there and the check repeats,
   a few rounds at most). A gradient search (``"lbfgs"``, the default of
   :func:`~rczone.estimation.fit.fit`) is checked by itself from a point displaced by
   :data:`DISPLACEMENT` of the box (:func:`displaced`): a second start near the optimum, which a
   stalled search does not come back from, and no derivative-free sweep. That restart runs in
   stages (:func:`budgeted_search`) and is the adaptive search's second start: where the model's
   own start converged, two agreeing starts (with the rules above) end the search early, before
   any sampled start.

Nelder-Mead searches are restarted at their end point while that still lowers the cost. Searches
from sampled points run in stages (:func:`budgeted_search`): :data:`GRADIENT_STAGE` evaluations for
a gradient search (each step uses the exact gradient), the fewest a finished search took for a
direct search.

References
----------
.. [1] A. H. G. Rinnooy Kan, G. T. Timmer, "Stochastic global optimization methods. Part I:
   Clustering methods", Mathematical Programming 39 (1987) 27-56.
.. [2] M. D. McKay, R. J. Beckman, W. J. Conover, "A comparison of three methods for selecting
   values of input variables in the analysis of output from a computer code", Technometrics 21
   (1979) 239-245.
.. [3] W. H. Press, S. A. Teukolsky, W. T. Vetterling, B. P. Flannery, *Numerical Recipes*, 3rd
   ed., Cambridge University Press, 2007, section 10.5 (restarting the downhill simplex at a
   claimed minimum).
.. [4] C. G. E. Boender, A. H. G. Rinnooy Kan, "Bayesian stopping rules for multistart global
   optimization methods", Mathematical Programming 37 (1987) 59-80.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.methods import method_of
from rczone.estimation.optimize import FINAL_FTOL, StartOutcome, minimize_from, remembered
from rczone.estimation.parameters import ParameterSpec

#: Costs of two end points closer than ``abs_tol + rel_tol * |cost| + SCALE_TOL * scale`` are the
#: same optimum (``abs_tol``, ``rel_tol`` of the method, :data:`rczone.estimation.methods.REGISTRY`).
#: For likelihood costs 0.01 is far below any difference that matters (a likelihood-ratio test
#: needs about 2); for least squares the relative part decides, and the part relative to the data's
#: own variation (``scale``) merges end points of a near-perfect fit.
SCALE_TOL = 1e-9
#: Sampled points closer than this (in the unit box of eta) to a better chosen start are not starts.
LINK_RADIUS = 0.1
#: Most local searches of the automatic search (``4 + n_free // 2`` below this).
MAX_AUTO_STARTS = 8
#: Evaluation budget of one stage of a local search from a sampled point: the fewest evaluations a
#: finished search took (at least :data:`MIN_BUDGET`); a search continues for up to
#: :data:`MAX_STAGES` stages only while it is below the best optimum found so far.
MIN_BUDGET = 100
MAX_STAGES = 4
#: Evaluation budget of one stage of a gradient search (L-BFGS, one evaluation per step) from a sampled
#: point: each step uses the exact gradient, so this many take a search much further than
#: :data:`MIN_BUDGET` direct-search evaluations; a search still above the best optimum by then is stopped.
GRADIENT_STAGE = 50
#: Displacement (fraction of each parameter's range in eta) of the restart that confirms a gradient
#: search's optimum found by one start: a second start, not a second method.
DISPLACEMENT = 0.05
#: Restarts of Nelder-Mead from its own end point (a fresh simplex) while they still lower the cost.
NM_RESTARTS = 2
#: Rounds of the polish (second method, then the first again) of an optimum found by one start.
POLISH_ROUNDS = 3
#: The second method used to confirm an optimum found by one start only.
SECOND_METHOD = {"nelder-mead": "powell", "powell": "nelder-mead", "lbfgs": "lbfgs"}


@dataclass(frozen=True)
class Optimum:
    """One distinct end point of the local searches.

    Attributes
    ----------
    cost : float
    theta : ndarray
        Estimates at the best start of this optimum (physical units).
    starts : tuple of int
        Indices (into the fit's ``starts``) of the local searches that ended here.
    """

    cost: float
    theta: np.ndarray
    starts: tuple[int, ...]

    @property
    def count(self) -> int:
        return len(self.starts)


@dataclass(frozen=True)
class SearchSummary:
    """How the optimum was found, and how sure the search is of it.

    Attributes
    ----------
    strategy : str
        ``"global"`` (sample + local searches) or ``"local"`` (one start).
    n_sampled : int
        Cost evaluations of the global phase.
    n_local : int
        Local searches run (the confirmation included).
    optima : tuple of Optimum
        Distinct optima, best first.
    spread : dict of name to (float, float)
        Smallest and largest estimate among the starts that reached the best optimum.
    confirmed_by : str or None
        The second method that found nothing better, when the best optimum was reached once.
    converged : bool
        Reached from two starts, or confirmed, and the winning local search converged.
    reason : str
        Why it is or is not converged, in words.
    tolerance : float
        Cost difference below which two end points are one optimum.
    """

    strategy: str
    n_sampled: int
    n_local: int
    optima: tuple[Optimum, ...]
    spread: dict[str, tuple[float, float]]
    confirmed_by: str | None
    converged: bool
    reason: str
    tolerance: float

    @property
    def n_best(self) -> int:
        """How many local searches reached the best optimum."""
        return self.optima[0].count if self.optima else 0

    def to_dict(self, names: tuple[str, ...]) -> dict:
        return {
            "strategy": self.strategy,
            "n_sampled": self.n_sampled,
            "n_local": self.n_local,
            "n_best": self.n_best,
            "converged": self.converged,
            "reason": self.reason,
            "confirmed_by": self.confirmed_by,
            "tolerance": self.tolerance,
            "optima": [
                {
                    "cost": _num(o.cost),
                    "count": o.count,
                    "starts": list(o.starts),
                    "estimates": dict(zip(names, map(float, o.theta))),
                }
                for o in self.optima
            ],
            "spread": {k: [float(a), float(b)] for k, (a, b) in self.spread.items()},
        }


def _num(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def cost_tolerance(method: str, cost: float, scale: float = 0.0) -> float:
    """Largest cost difference between end points that are the same optimum (see :data:`SCALE_TOL`)."""
    m = method_of(method)
    return m.abs_tol + m.rel_tol * abs(cost) + SCALE_TOL * abs(scale)


def latin_hypercube(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points of a Latin hypercube in the unit cube ``[0, 1)^d`` [2]_ (scipy's ``qmc``).

    Each coordinate takes one value in each of the ``n`` equal strata, at a uniform position
    inside it, in an independent random order.
    """
    from scipy.stats import qmc

    return qmc.LatinHypercube(d=d, rng=rng).random(n)


def sample_points(spec: ParameterSpec, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points (theta) of a Latin hypercube over the whole box of bounds, in eta, strictly inside."""
    unit = latin_hypercube(n, spec.n_free, rng)
    unit = 1e-6 + (1 - 2e-6) * unit
    lo, hi = spec.eta_lower, spec.eta_upper
    return spec.to_theta(lo + unit * (hi - lo))


def _sampled_costs(cost: Callable[[np.ndarray], float], spec: ParameterSpec, pts: np.ndarray) -> np.ndarray:
    """The cost at each sampled point (theta); ``inf`` where it is not finite.

    An :class:`~rczone.estimation.costs.Objective` is asked at the physical values directly
    (``theta_cost``, as :func:`rczone.estimation.leastsq.spread_starts` does), without the round
    trip through ``eta`` (about 7 us of Python per point, as much as half a 2-state likelihood).
    """
    at_theta = getattr(cost, "theta_cost", None)
    if at_theta is None:
        return np.array([cost(spec.to_eta(p)) for p in pts])
    vals = np.array([at_theta(p) for p in pts], dtype=float)
    return np.where(np.isfinite(vals), vals, math.inf)


def _unit(spec: ParameterSpec, theta: np.ndarray) -> np.ndarray:
    lo, hi = spec.eta_lower, spec.eta_upper
    return (spec.to_eta(theta) - lo) / (hi - lo)


def _physical_at_bound(spec: ParameterSpec, theta: np.ndarray) -> bool:
    """An R, C or gain at a bound: degenerate optima (a wall cut off, a capacity vanishing) attract
    many starts in flat regions, so the search does not stop early on one."""
    physical = np.array([k in ("resistance", "capacitance", "gain") for k in spec.kinds], dtype=bool)
    return bool(np.any(spec.near_bound(theta) & physical))


def settled(spec: ParameterSpec, n_runs: int, optima: tuple, lower_left: bool, n_found: int) -> bool:
    """The adaptive stop rule: the best optimum reached from two starts, enough searches for the number
    of parameters, no sampled point left unused below it, few optima unseen (:func:`few_unseen` of
    ``n_found`` optima in ``n_runs`` searches) and no R, C or gain at a bound."""
    return bool(
        optima
        and optima[0].count >= 2
        and n_runs >= min_local_searches(spec.n_free)
        and not lower_left
        and few_unseen(n_runs, n_found)
        and not _physical_at_bound(spec, optima[0].theta)
    )


def restart_second(
    starts: list[np.ndarray],
    start_costs: list[float],
    spec: ParameterSpec,
    end: np.ndarray,
    rng: np.random.Generator,
) -> None:
    """Early agreement: make the restart near the first search's end (:func:`displaced`) the second start.

    It is the confirmation a single start would get anyway; the sampled starts follow only where
    :func:`settled` is not yet met (a sampled point below it, more searches for more parameters).
    """
    starts.insert(1, displaced(spec, end, rng))
    start_costs.insert(1, math.nan)


def displaced(spec: ParameterSpec, theta: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``theta`` moved by :data:`DISPLACEMENT` of each parameter's range in eta, in random directions, inside the box.

    The start of the restart that confirms a gradient search's optimum: a search that stalled
    short of a minimum (a flat stretch, a line-search failure) does not come back to the same
    point from there; a minimum does.
    """
    eta = spec.to_eta(theta)
    lo, hi = spec.eta_lower, spec.eta_upper
    step = DISPLACEMENT * (hi - lo) * rng.choice([-1.0, 1.0], eta.size)
    out = np.where((eta + step > lo) & (eta + step < hi), eta + step, eta - step)
    return spec.to_theta(np.clip(out, lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo)))


def min_local_searches(n_free: int) -> int:
    """Local searches the adaptive search runs at least before it may stop: ``max(2, n_free // 2 - 1)``.

    Two searches that agree are enough evidence on the small problems rczone is mostly used for
    (a 2-state paper fit has 4 free parameters, a TiTe fit with heater and sun 7): on every shipped
    and real data set the default then reaches the optimum of 32 starts. Landscapes of more
    parameters have more basins: on a 12-parameter single-zone model of the virtual building
    (process noise on every node) the first two searches agreed on an optimum 8.5 log-likelihood
    units worse than the one the fifth search found.
    """
    return max(2, n_free // 2 - 1)


def few_unseen(n_runs: int, n_optima: int) -> bool:
    """Whether the local searches have probably found every optimum worth finding.

    With up to two distinct optima the answer is yes (the best one reached twice is then the
    usual stopping point). With more, the posterior expected number of optima of Boender and
    Rinnooy Kan, ``w (n - 1) / (n - w - 2)`` for ``n`` runs that found ``w`` distinct optima, must
    be below ``w + 1/2`` [4]_: a landscape where most runs end somewhere new needs more runs.
    """
    n, w = n_runs, n_optima
    if w <= 2:
        return True
    return n - w - 2 > 0 and w * (n - 1) / (n - w - 2) < w + 0.5


def local_search(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    start: np.ndarray,
    optimizer: str,
    max_evals: int | None,
    tol_of: Callable[[float], float],
    *,
    curvature: np.ndarray | None = None,
) -> StartOutcome:
    """One local search; Nelder-Mead is restarted from its end point while that lowers the cost.

    A Nelder-Mead simplex can collapse before it reaches a minimum, the more so the more parameters
    there are; restarting with a fresh simplex at the claimed minimum is the standard remedy [3]_.
    The outcome keeps the first start and sums the evaluations. ``curvature`` scales a gradient
    search's first phase (:func:`~rczone.estimation.optimize.minimize_from`).
    """
    out = minimize_from(cost, spec, start, optimizer, max_evals, curvature=curvature)
    if optimizer != "nelder-mead":
        return out
    n = out.n_evals
    for _ in range(NM_RESTARTS):
        again = minimize_from(cost, spec, out.end, optimizer, max_evals)
        n += again.n_evals
        improved = again.cost < out.cost - tol_of(out.cost)
        if again.cost <= out.cost:
            out = again
        if not improved:
            break
    return StartOutcome(np.asarray(start, dtype=float), out.end, out.cost, out.converged, n, out.message)


def restart_search(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    start: np.ndarray,
    max_evals: int | None,
    tol_of: Callable[[float], float],
    best: float,
    *,
    curvature: np.ndarray | None = None,
) -> StartOutcome:
    """A gradient search restarted near the best end (cost ``best``): one stage, then in full unless it came back.

    Back within the tolerance of ``best`` after :data:`GRADIENT_STAGE` evaluations, it has
    confirmed that end (the cheap, usual case). Otherwise it goes on to its own end whether it is
    above or below ``best``: from near a stalled search's end point the minimum beyond may take many
    steps, and given up while still above that point (as a sampled start is) it was missed.
    """
    stage = GRADIENT_STAGE if max_evals is None else min(GRADIENT_STAGE, max_evals)
    out = local_search(cost, spec, start, "lbfgs", stage, tol_of, curvature=curvature)
    if out.converged or abs(out.cost - best) <= tol_of(best):
        return out
    more = local_search(cost, spec, out.end, "lbfgs", max_evals, tol_of)
    return StartOutcome(
        np.asarray(start, dtype=float),
        more.end,
        more.cost,
        more.converged,
        out.n_evals + more.n_evals,
        more.message,
    )


def budgeted_search(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    start: np.ndarray,
    optimizer: str,
    max_evals: int | None,
    tol_of: Callable[[float], float],
    done: list[StartOutcome],
    *,
    curvature: np.ndarray | None = None,
) -> StartOutcome:
    """A local search from a sampled point, in stages of the evaluations the easiest finished search took.

    Most points of a box of bounds spanning decades in every parameter lie in poor regions; a search
    from there that has not settled after as much work as the first search needed, and is still
    above the best optimum found, is stopped (its outcome says so). One that is below continues, so a
    better basin is never given up. ``curvature`` scales the first stage's gradient search.
    """
    if optimizer == "lbfgs":
        stage = GRADIENT_STAGE
    else:
        stage = max(MIN_BUDGET, min(o.n_evals for o in done))
    if max_evals is not None:
        stage = min(stage, max_evals)
    best = (
        min(o.cost for o in done if math.isfinite(o.cost))
        if any(math.isfinite(o.cost) for o in done)
        else math.inf
    )
    out = local_search(cost, spec, start, optimizer, stage, tol_of, curvature=curvature)
    n = out.n_evals
    for _ in range(MAX_STAGES - 1):
        if out.converged or not out.cost < best - tol_of(best):
            break
        out = local_search(cost, spec, out.end, optimizer, stage, tol_of)
        n += out.n_evals
    return StartOutcome(np.asarray(start, dtype=float), out.end, out.cost, out.converged, n, out.message)


#: Relative cost difference below which two ends of the best optimum are one point to rounding: the
#: cost itself is computed to about 1e-13 of its value (the two ends of an ML fit's early agreement
#: differ by 3e-13 at most on the virtual building's nights), so which of them is lower is noise.
#: The polish keeps an end (and the Hessian computed there) unless it gains more than this.
COST_TIE = 1e-10


def _polish(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    outcomes: list[StartOutcome],
    optima: tuple[Optimum, ...],
    max_evals: int | None,
    method: str,
    scale: float,
    tol: float,
) -> tuple[tuple[Optimum, ...], float]:
    """The best end searched on with the strict tolerance (:data:`~rczone.estimation.optimize.FINAL_FTOL`).

    The exploring searches stop on a looser relative decrease; on a flat likelihood that can leave
    the best end short of its minimum. The search that reached it goes on from there; its outcome
    keeps its start and counts the extra evaluations (no start is added).
    """
    i = optima[0].starts[0]
    out = outcomes[i]
    # where the search computed the Hessian at this end, its diagonal is the curvature that scales the
    # search on (exact, where d + 1 gradients would estimate it)
    curvature = None if out.hessian is None else np.diag(out.hessian)
    more = minimize_from(cost, spec, out.end, "lbfgs", max_evals, ftol=FINAL_FTOL, curvature=curvature)
    if not more.cost < out.cost - COST_TIE * max(abs(out.cost), 1.0):
        outcomes[i] = replace(out, n_evals=out.n_evals + more.n_evals)
        return optima, tol
    outcomes[i] = replace(
        out,
        end=more.end,
        cost=more.cost,
        n_evals=out.n_evals + more.n_evals,
        converged=more.converged,
        hessian=None,
    )
    return merge_optima(outcomes, method, scale)


def ends_agree(outcomes: list[StartOutcome], best: Optimum) -> bool:
    """Whether two searches that converged by their own test ended at the best optimum within :data:`COST_TIE`.

    Then the best end is at its minimum to rounding and the polish (:func:`_polish`) is not needed:
    a search stopped short on a flat likelihood ends where its start and path put it, so two
    searches from different starts (the first one and the restart displaced from its end) do not
    end within a relative 1e-10 of each other short of the minimum; the polish found nothing on
    the batch's nights where they did (its end is kept unless it gains more than ``COST_TIE``).

    Parameters
    ----------
    outcomes : list of StartOutcome
        Every local search.
    best : Optimum
        The best optimum (its ``starts`` index ``outcomes``).

    Returns
    -------
    bool
    """
    ends = [outcomes[i].cost for i in best.starts if outcomes[i].converged]
    if len(ends) < 2:
        return False
    return max(ends) - min(ends) <= COST_TIE * max(abs(min(ends)), 1.0)


def merge_optima(
    outcomes: list[StartOutcome], method: str, scale: float = 0.0
) -> tuple[tuple[Optimum, ...], float]:
    """Group end points by cost (best first); returns the optima and the tolerance used."""
    finite = [i for i, o in enumerate(outcomes) if math.isfinite(o.cost)]
    if not finite:
        return (), math.nan
    order = sorted(finite, key=lambda i: outcomes[i].cost)
    tol = cost_tolerance(method, outcomes[order[0]].cost, scale)
    groups: list[list[int]] = []
    for i in order:
        if groups and outcomes[i].cost - outcomes[groups[-1][0]].cost <= tol:
            groups[-1].append(i)
        else:
            groups.append([i])
    optima = tuple(Optimum(outcomes[g[0]].cost, outcomes[g[0]].end, tuple(sorted(g))) for g in groups)
    return optima, tol


def global_search(
    cost: Callable[[np.ndarray], float],
    spec: ParameterSpec,
    method: str,
    rng: np.random.Generator,
    optimizer: str = "nelder-mead",
    n_starts: int | None = None,
    max_evals: int | None = None,
    n_sample: int | None = None,
    scale: float = 0.0,
    progress=None,
) -> tuple[list[StartOutcome], SearchSummary]:
    """Minimize ``cost(eta)`` globally (see the module notes).

    Parameters
    ----------
    cost : callable
        Cost of ``eta`` (an :class:`~rczone.estimation.costs.Objective`).
    spec : ParameterSpec
    method : {"ls", "ml", "map"}
        Sets the tolerance of :func:`merge_optima`.
    rng : numpy.random.Generator
    optimizer : {"nelder-mead", "powell", "lbfgs"}
        The local method.
    n_starts : int, optional
        ``1``: one local search from ``spec.start`` (no global phase). ``k > 1``: exactly ``k``
        local searches. Default: adaptive, 2 to ``4 + n_free // 2`` (stops once the best optimum
        was reached twice).
    max_evals : int, optional
        Evaluation budget per local search.
    n_sample : int, optional
        Points of the global phase; default ``16 n_free`` clipped to [32, 256].
    scale : float
        The cost's natural scale (for least squares, the data's variation around their mean), for
        :func:`cost_tolerance`.
    progress : object, optional
        Told ``progress.advance(done, most)`` after each local search (``most``: the starts chosen,
        an upper bound of the adaptive search); None: nothing is told.

    Returns
    -------
    outcomes : list of StartOutcome
        Every local search, in the order run.
    summary : SearchSummary
    """
    if n_starts is not None and (not isinstance(n_starts, int) or n_starts < 1):
        raise ParameterError(f"n_starts must be a positive integer (or None for automatic), got {n_starts!r}")
    d = spec.n_free
    if optimizer == "lbfgs":  # a stage or search resumed at an end point asks for it again
        cost = remembered(cost)
    outcomes: list[StartOutcome] = []
    n_sampled = 0
    if n_starts == 1:
        starts = [spec.start]
        start_costs = [math.nan]
        adaptive, max_local = False, 1
    else:
        n_sample = n_sample or int(min(256, max(32, 16 * d)))
        pts = sample_points(spec, n_sample, rng)
        vals = _sampled_costs(cost, spec, pts)
        n_sampled = n_sample
        adaptive = n_starts is None
        max_local = n_starts if n_starts is not None else min(MAX_AUTO_STARTS, 4 + d // 2)
        starts = [spec.start]
        start_costs = [math.nan]
        chosen = [_unit(spec, spec.start)]
        for i in np.argsort(np.where(np.isfinite(vals), vals, np.inf)):
            if len(starts) >= max_local or not math.isfinite(vals[i]):
                break
            u = _unit(spec, pts[i])
            if all(np.max(np.abs(u - c)) > LINK_RADIUS for c in chosen):
                starts.append(pts[i])
                start_costs.append(float(vals[i]))
                chosen.append(u)

    def tol_of(c: float) -> float:
        return cost_tolerance(method, c, scale)

    lower_left = False
    restarted = False
    guide = None  # the Hessian at the first search's end: it scales the restart that confirms it
    for k, s in enumerate(starts):
        try:
            if k == 1 and restarted:
                # the restart near the first search's end runs in full: from near a stalled search's
                # end point it may need many steps to reach the minimum beyond, and in stages it was
                # given up while still above that point
                curvature = np.diag(guide) if guide is not None else None
                outcomes.append(
                    restart_search(cost, spec, s, max_evals, tol_of, outcomes[0].cost, curvature=curvature)
                )
            elif outcomes and k > 0:
                outcomes.append(budgeted_search(cost, spec, s, optimizer, max_evals, tol_of, outcomes))
            else:
                outcomes.append(local_search(cost, spec, s, optimizer, max_evals, tol_of))
        except ParameterError:
            # the model's own start may be invalid for these data (cost not finite): skip it
            if k == 0 and len(starts) > 1:
                continue
            raise
        if progress is not None:
            progress.advance(k + 1, len(starts))
        if k == 0 and adaptive and optimizer == "lbfgs" and outcomes[-1].converged:
            restart_second(starts, start_costs, spec, outcomes[-1].end, rng)
            restarted = True
            if getattr(cost, "adjoint_gradient", False):
                from rczone.estimation.uncertainty import hessian_from_gradient

                # needed for the standard errors if this end wins; its diagonal is the exact
                # curvature the restart would otherwise estimate at its start (d + 1 gradients)
                guide = hessian_from_gradient(cost.value_and_gradient, spec.to_eta(outcomes[-1].end))
                outcomes[-1] = replace(outcomes[-1], hessian=guide)
        if adaptive and len(outcomes) >= 2:
            optima, _ = merge_optima(outcomes, method, scale)
            # stop once the best optimum was reached twice, unless a sampled point not yet used as a
            # start lies below it: that point is in a better basin than any found so far
            pending = start_costs[k + 1 :]
            lower_left = bool(optima and any(c < optima[0].cost for c in pending))
            if settled(spec, len(outcomes), optima, lower_left, len(optima)):
                break
    optima, tol = merge_optima(outcomes, method, scale)
    if not optima:
        raise ParameterError("every local search ended at a point where the cost is not finite")
    confirmed_by = None
    n_runs = len(outcomes)
    if optima[0].count >= 2:
        converged = True
        reason = f"the best optimum was reached from {optima[0].count} of {n_runs} starts"
    else:
        # polish: a second method from the best point (a gradient search: itself from a displaced
        # point, a second start); where it finds lower, the first method again
        second = SECOND_METHOD.get(optimizer, "powell")
        converged = False
        for _ in range(POLISH_ROUNDS):
            best = optima[0]
            if second == optimizer:
                # a restart near it, in full: from near a stalled search's end point it goes on to the
                # minimum beyond (in stages it was given up while still above that point, which then
                # counted as confirmed)
                check = restart_search(
                    cost, spec, displaced(spec, best.theta, rng), max_evals, tol_of, best.cost
                )
            else:
                check = minimize_from(cost, spec, best.theta, second, max_evals)
            outcomes.append(check)
            if progress is not None:
                progress.advance(len(outcomes), len(outcomes) + 1)
            came_back = abs(check.cost - best.cost) <= tol_of(best.cost)
            if check.cost >= best.cost - tol_of(best.cost) and (check.converged or came_back):
                converged, confirmed_by = True, second
                break
            outcomes.append(local_search(cost, spec, check.end, optimizer, max_evals, tol_of))
            optima, tol = merge_optima(outcomes, method, scale)
        optima, tol = merge_optima(outcomes, method, scale)
        check_by = (
            f"a restart of {second} near it"
            if second == optimizer
            else f"a second method ({second}) started there"
        )
        if converged:
            reason = (
                f"the best optimum was reached from 1 of {n_runs} starts and {check_by} found nothing better"
            )
        else:
            reason = (
                f"the best optimum was reached from only 1 of {n_runs} starts and {check_by}"
                f" kept finding lower costs ({POLISH_ROUNDS} rounds): the search has not settled"
            )
    if optimizer == "lbfgs" and not ends_agree(outcomes, optima[0]):
        optima, tol = _polish(cost, spec, outcomes, optima, max_evals, method, scale, tol)
    best = optima[0]
    winner = outcomes[best.starts[0]]
    # the optimum is a minimum when at least one search that reached it ended by its own test (a
    # line search that fails at a perfect fit, cost 1e-23, is not evidence against it)
    if converged and not any(outcomes[i].converged for i in best.starts):
        converged = False
        reason += f", but every search that reached it stopped early ({winner.message})"
    if lower_left and converged:
        converged = False
        reason += ", but a sampled point not used as a start has a lower cost (raise the number of starts)"
    ends = np.array([outcomes[i].end for i in best.starts])
    spread = {n: (float(ends[:, j].min()), float(ends[:, j].max())) for j, n in enumerate(spec.names)}
    summary = SearchSummary(
        "global" if n_starts != 1 else "local",
        n_sampled,
        len(outcomes),
        optima,
        spread,
        confirmed_by,
        bool(converged),
        reason,
        tol,
    )
    return outcomes, summary
