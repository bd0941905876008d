"""``fit``: estimate free parameters of an RC network from a data set.

The top-level function ties the pieces together: default free set, parameter spec, cost, global
search, uncertainty, the flags that say when a result should not be trusted, and the frozen
:class:`~rczone.estimation.result.FitResult`. The network is never modified.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation import leastsq
from rczone.estimation.costs import (
    MAP_CORRELATION_TIME,
    PRIOR_SPREAD,
    Objective,
    auto_initial_state,
    filter_arrays,
    simulate_output,
    trapezoid_sse,
)
from rczone.estimation.data import Dataset
from rczone.estimation.engines import general_cost
from rczone.estimation.kalman import kalman_innovations_fast
from rczone.estimation.methods import Method, method_of
from rczone.estimation.optimize import OPTIMIZERS, StartOutcome
from rczone.estimation.parameters import make_spec
from rczone.estimation.resolution import noise_floor
from rczone.estimation.result import FitResult
from rczone.estimation.search import COST_TIE, global_search
from rczone.estimation.uncertainty import covariance, hessian, hessian_from_gradient
from rczone.network import RCNetwork
from rczone.network.stochastic import (
    KINDS,
    MEASUREMENT_NOISE,
    initial_state_name,
    initial_state_names,
    is_noise_name,
    kind_of,
    measurement_noise_names,
    process_noise_names,
)
from rczone.network.stochastic import unit_of as stochastic_unit
from rczone.results import Estimate
from rczone.simulation.simulate import HOLDS

if TYPE_CHECKING:
    from rczone.estimation.sampling import SamplerSettings


def rmse_of(network: RCNetwork, values: Mapping[str, float], data: Dataset, method: str, hold: str) -> float:
    """Open-loop RMSE (``"ls"``) or one-step-ahead RMSE (``"ml"``, ``"map"``), K."""
    if method_of(method).kernel == "ls":
        e = data.y - simulate_output(network, values, data, hold)[1]
    else:
        e = kalman_innovations_fast(filter_arrays(network, values, data, hold))
    return float(np.sqrt(np.nanmean(e**2)))


def measured_states(network: RCNetwork) -> tuple[str, ...]:
    """States that an output measures directly."""
    return tuple(o for o in network.outputs if o in network.state_names)


def default_free(
    network: RCNetwork, method: str, initial_state: str = "estimate", noise: str = "measured"
) -> tuple[str, ...]:
    """Parameters a fit estimates when the user names none.

    The network's :attr:`~rczone.network.RCNetwork.default_free` (every resistance, capacitance and
    gain not declared fixed); for ML and MAP also the measurement noise of every output and the
    process noise of every measured state (``noise="measured"``) or of every state (``"all"``); for
    LS with ``initial_state="estimate"`` the initial temperature of every state that is not measured
    (the data rarely start at rest, and assuming they do biases the fit: see :func:`fit`).

    Why ``"measured"`` by default: process noise on an unmeasured node (a wall, a slab) lets the
    filter correct that node from the room's innovations, which always raises the likelihood of a
    low-order model of a real room (by about 270 log-units on the virtual building's forced nights)
    but lets the deterministic part drift: on six forced nights the room capacity fell from
    2.6-3.6e5 J/K to 8e4 J/K (about 5.7e5 in the building), and the open-loop prediction of the
    following night worsened from 0.36-0.52 K to 0.47-0.72 K RMSE. A model for control is judged by
    its open-loop prediction, so noise on every state is an option (``rczone select`` uses it, because
    likelihood-ratio tests and information criteria need a well specified noise model; Bacher &
    Madsen 2011).
    """
    if noise not in ("measured", "all"):
        raise ParameterError(f"noise must be 'measured' or 'all', got {noise!r}")
    free = list(network.default_free)
    measured = measured_states(network)
    if method_of(method).stochastic:
        free += measurement_noise_names(network.outputs)
        # a disturbance's latent states have the diffusion of their GP, not a sigma_w_ of their own
        free += process_noise_names(measured if noise == "measured" else network.node_state_names)
    elif initial_state == "estimate":
        free += initial_state_names(s for s in network.state_names if s not in measured)
    return tuple(free)


def noise_bounds(network: RCNetwork, data: Dataset, free: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Bounds of free measurement-noise levels derived from the data (see :mod:`~rczone.estimation.resolution`).

    Lower: the output's :func:`~rczone.estimation.resolution.noise_floor`; upper: ten times the
    output's spread (a noise larger than the signal explains nothing), at least 100 floors.
    """
    out = {}
    for j, name in enumerate(measurement_noise_names(network.outputs)):
        if name not in free:
            continue
        y = data.y[:, j]
        floor = noise_floor(y)
        spread = float(np.nanstd(y)) if np.isfinite(y).sum() > 1 else 1.0
        out[name] = (floor, max(10.0 * spread, 100.0 * floor, 1.0))
    return out


def fit(
    network: RCNetwork,
    data: Dataset,
    free: Sequence[str] | None = None,
    *,
    method: str = "ls",
    optimizer: str = "auto",
    n_starts: int | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    rng: np.random.Generator | None = None,
    start: Mapping[str, float] | None = None,
    fixed: Mapping[str, float] | None = None,
    hold: str = "zoh",
    prior_spread: float = PRIOR_SPREAD,
    correlation_time_s: float = MAP_CORRELATION_TIME,
    uncertainty: bool = True,
    max_evals: int | None = None,
    initial_state: str = "estimate",
    sampler: SamplerSettings | None = None,
) -> FitResult:
    """Estimate the ``free`` parameters of ``network`` from ``data``.

    By default the search is global (:func:`~rczone.estimation.search.global_search`): the cost is
    sampled over the whole box of bounds, local searches start from the model's values and from
    the best samples, identical optima are merged, and the result is *converged* only when the best
    optimum was reached from two starts or confirmed by a second method.

    Parameters
    ----------
    network : RCNetwork
        Model structure; declared parameter values are the construction values and
        the values of non-free parameters.
    data : Dataset
        Columns must match ``network.input_names``, ``flow_names`` and ``outputs``.
    free : sequence of str, optional
        Parameters to estimate (base network parameters, ``sigma_v`` (``sigma_v_<output>`` with
        several outputs), ``sigma_w_<state>``, ``x0_<state>``, ``sigma_x0_<state>``). Default
        :func:`default_free`.
    method : {"ls", "ml", "map", "mcmc"}
        Output-error least squares (Lin et al. 2012, eq. (8)), Kalman-filter maximum likelihood
        (eq. 9), ML with a prior on the free R and C (declared, else log-normal around the
        construction value), or posterior sampling (:mod:`rczone.estimation.sampling`; the
        estimates are posterior means, the standard errors posterior standard deviations).
    optimizer : {"auto", "nelder-mead", "powell", "lbfgs"}
        The local method. ``"auto"``: L-BFGS with the exact gradient (one evaluation per step, a
        gradient costing a few likelihoods: :meth:`~rczone.estimation.costs.Objective.value_and_gradient`);
        the direct searches need tens of times more evaluations. For least squares on a problem
        that packs into arrays, ``"auto"`` is Gauss-Newton on the residual Jacobian
        (:mod:`rczone.estimation.leastsq`, recorded as ``"gauss-newton"``).
    n_starts : int, optional
        Local searches: default automatic (2 or more, see the search); ``1`` is one local search
        from the start values (no global phase); ``k`` runs exactly ``k``.
    bounds : mapping of name to (lower, upper), optional
        Default: declared on the parameter, else a factor 1000 around its value; measurement
        noise from the data (:func:`noise_bounds`).
    rng : numpy.random.Generator, optional
        Draws the global phase; default ``numpy.random.default_rng(0)`` (reproducible).
    start, fixed : mapping of name to float, optional
        Start values of free parameters; values of non-free ones.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the inputs.
    prior_spread : float
        Spread (log units) of the MAP prior.
    correlation_time_s : float
        MAP only: correlation time of the output error; the likelihood is weighted by
        ``min(1, dt / correlation_time_s)`` (see :class:`~rczone.estimation.costs.Objective`),
        so that a night of closed-loop data cannot overrule the construction values with
        thousands of samples that carry the information of a few dozen.
    uncertainty : bool
        Compute the Hessian, standard errors and correlations.
    max_evals : int, optional
        Evaluation budget per local search.
    initial_state : {"estimate", "steady"}
        Only when ``free`` is not given: ``"estimate"`` (default) frees the initial temperature of
        every unmeasured state in an LS fit; ``"steady"`` starts them in equilibrium with the first
        inputs and measurement, which biases the fit when the data do not start at rest. ML and
        MAP fits carry an initial-state uncertainty in the filter either way.
    sampler : SamplerSettings, optional
        Draws, warm-up and chains of a sampling method (``"mcmc"``,
        :mod:`rczone.estimation.sampling`); default :class:`~rczone.estimation.sampling.SamplerSettings`.

    Returns
    -------
    FitResult
    """
    meth = method_of(method)
    if optimizer != "auto" and optimizer not in OPTIMIZERS:
        raise ParameterError(f"optimizer must be 'auto' or one of {OPTIMIZERS}, got {optimizer!r}")
    if hold not in HOLDS:
        raise ParameterError(f"hold must be one of {HOLDS}, got {hold!r}")
    if initial_state not in ("estimate", "steady"):
        raise ParameterError(f"initial_state must be 'estimate' or 'steady', got {initial_state!r}")
    if not isinstance(data, Dataset):
        raise ParameterError(
            f"data must be an rczone Dataset, got {type(data).__name__}; see Dataset.from_frame"
        )
    data.check_against(network)
    free = tuple(free) if free else default_free(network, method, initial_state)
    if not meth.stochastic:
        noisy = [n for n in free if is_noise_name(n)]
        if noisy:
            raise ParameterError(
                f"noise parameter(s) {noisy} cannot be estimated by least squares; use method='ml' or 'map'"
            )
    rng = np.random.default_rng(0) if rng is None else rng
    ss0 = network.state_space()
    x0a = auto_initial_state(ss0, data.u[0], data.m[0], data.y[0])
    x0_auto = {initial_state_name(s): float(v) for s, v in zip(ss0.state_names, x0a)}
    all_bounds = {**noise_bounds(network, data, free), **dict(bounds or {})}
    start = dict(start or {})
    for name, (lo, hi) in all_bounds.items():
        if kind_of(name) == MEASUREMENT_NOISE and name not in start and name not in (bounds or {}):
            v = KINDS[MEASUREMENT_NOISE].default
            if not lo < v < hi:  # a coarse logger: start above its resolution
                start[name] = math.sqrt(lo * hi) if hi < 100 * lo else 10.0 * lo
    spec = make_spec(network, free, bounds=all_bounds, start=start, fixed=fixed, x0_auto=x0_auto)
    if not correlation_time_s > 0:
        raise ParameterError(f"correlation_time_s must be > 0, got {correlation_time_s!r}")
    weight = min(1.0, float(np.median(np.diff(data.t))) / correlation_time_s) if meth.prior else 1.0
    objective = Objective(network, data, spec, method, hold, prior_spread, weight)
    if meth.search == "sample":
        from rczone.estimation.sampling import SamplerSettings, sample_fit

        return sample_fit(objective, settings=sampler or SamplerSettings(), rng=rng)
    scale = trapezoid_sse(data.t, data.y - np.nanmean(data.y, axis=0)) if meth.kernel == "ls" else 0.0
    if optimizer == "auto" and leastsq.applies(objective):  # Gauss-Newton on the residual Jacobian
        optimizer = leastsq.NAME
        outcomes, search = leastsq.leastsq_search(objective, rng, n_starts, max_evals, scale)
    else:
        optimizer = "lbfgs" if optimizer == "auto" else optimizer  # every Objective has its exact gradient
        outcomes, search = global_search(
            objective, spec, method, rng, optimizer, n_starts, max_evals, scale=scale
        )
    best = winning_end(outcomes, search.optima[0].starts)
    win = outcomes[best]
    theta = win.end
    names = spec.names
    d = spec.n_free
    flags: list[str] = []
    notes: list[str] = []
    issues: list[str] = []
    positive_definite = True
    near = spec.near_bound(theta)
    if uncertainty:
        if win.hessian is not None:  # the search computed it at this end (search.global_search)
            H = win.hessian
        elif objective.adjoint_gradient:
            H = hessian_from_gradient(objective.value_and_gradient, spec.to_eta(theta))
        else:
            H = hessian(objective, spec.to_eta(theta))
        scale = 1.0
        if meth.kernel == "ls":
            dt = np.diff(data.t)
            obs = np.isfinite(data.y).all(axis=1)
            tau = float(np.sum(dt[obs[:-1] & obs[1:]]))
            scale = 2.0 * win.cost / tau * float(np.mean(dt)) if tau > 0 else math.nan
        unc = covariance(spec, theta, H, scale, held=near)
        se, corr = unc.std_error, unc.correlation
        positive_definite = unc.positive_definite
        if not positive_definite:
            issues.append("hessian")
            flags.append("Hessian not positive definite: the parameters are not identifiable from these data")
        missing = [n for n, v, b in zip(names, se, near) if not math.isfinite(v) and not b]
        if missing and positive_definite:
            issues.append("std_error")
            flags.append(f"no standard error for {', '.join(missing)}")
    else:
        se, corr = np.full(d, np.nan), np.full((d, d), np.nan)
    lower_side = spec.to_eta(theta) - spec.eta_lower <= spec.eta_upper - spec.to_eta(theta)
    for n, b, low, kind in zip(names, near, lower_side, spec.kinds):
        if not b:
            continue
        if kind == "noise" and low:
            notes.append(
                f"{n} is at its lower bound {spec.lower[names.index(n)]:.3g}: that noise is negligible"
            )
        else:
            issues.append("at_bound")
            flags.append(f"{n} is at a bound")
    if not search.converged:
        issues.append("not_converged")
        flags.append(f"not converged: {search.reason}")
    for n, kind in zip(names, spec.kinds):
        lo_v, hi_v = search.spread[n]
        if kind in ("resistance", "capacitance", "gain") and search.n_best >= 2:
            rel = (hi_v / lo_v if lo_v > 0 else math.inf) if kind != "gain" else abs(hi_v - lo_v)
            wide = rel > 1.1 if kind != "gain" else rel > 0.1 * max(abs(hi_v), 1e-12)
            if wide:
                issues.append("starts_disagree")
                flags.append(
                    f"starts that reach the same cost disagree on {n} ({lo_v:.3g} to {hi_v:.3g}):"
                    " the data do not determine it"
                )
    values = spec.values(theta)
    units = [unit_of(network, n) for n in names]
    parameters = {
        n: Estimate(n, float(v), float(e), float(lo), float(hi), float(c), bool(b), u, k, bool(lg))
        for n, v, e, lo, hi, c, b, u, k, lg in zip(
            names, theta, se, spec.lower, spec.upper, spec.construction, near, units, spec.kinds, spec.log
        )
    }
    return FitResult(
        parameters=parameters,
        correlation=corr,
        objective_value=win.cost,
        method=method,
        engine=objective.engine,
        optimizer=optimizer,
        hold=hold,
        converged=search.converged,
        n_evals=search.n_sampled + sum(o.n_evals for o in outcomes),
        starts=tuple(outcomes),
        best_start=best,
        rmse_K=_rmse(objective, theta, values),
        rmse_kind=meth.rmse_kind,
        llf=log_likelihood(network, values, data, meth, hold, win.cost),
        nobs=int(np.isfinite(data.y).sum()),
        fixed={k: v for k, v in values.items() if k not in names},
        flags=tuple(flags),
        search=search,
        notes=tuple(notes),
        issues=tuple(dict.fromkeys(issues)),
    )


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
    """The log-likelihood at the estimate: ``-objective`` for ML, recomputed without prior or tempering for MAP.

    NaN for a method without a noise model (least squares has no likelihood of its own).
    """
    if not kind.stochastic:
        return math.nan
    if not kind.prior:
        return -float(objective)
    return -float(general_cost(network, values, data, hold, "ml", ())[0])


def unit_of(network: RCNetwork, name: str) -> str:
    """SI unit of a free parameter, for tables."""
    if name in network.parameters:
        return network.parameters[name].unit or ""
    return stochastic_unit(name) or ""
