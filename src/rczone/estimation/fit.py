"""``fit``: estimate free parameters of an RC network from a data set.

The top-level function ties the pieces together: parameter spec, cost, (multistart)
optimizer, uncertainty, and the frozen :class:`~rczone.estimation.result.FitResult`.
The network is never modified.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import (
    MAP_CORRELATION_TIME,
    METHODS,
    PRIOR_SPREAD,
    Objective,
    auto_initial_state,
    filter_arrays,
    simulate_output,
)
from rczone.estimation.data import Dataset
from rczone.estimation.kalman import kalman_innovations_fast
from rczone.estimation.optimize import OPTIMIZERS, latin_hypercube_starts, minimize_from
from rczone.estimation.parameters import make_spec
from rczone.estimation.result import FitResult
from rczone.estimation.uncertainty import covariance, hessian
from rczone.network import RCNetwork
from rczone.simulation.simulate import HOLDS


def rmse_of(network: RCNetwork, values: Mapping[str, float], data: Dataset, method: str, hold: str) -> float:
    """Open-loop RMSE (``"ls"``) or one-step-ahead RMSE (``"ml"``, ``"map"``), K."""
    if method == "ls":
        e = data.y - simulate_output(network, values, data, hold)[1]
    else:
        e = kalman_innovations_fast(*filter_arrays(network, values, data, hold))
    return float(np.sqrt(np.nanmean(e**2)))


def fit(
    network: RCNetwork,
    data: Dataset,
    free: Sequence[str],
    method: str = "ls",
    optimizer: str = "nelder-mead",
    n_starts: int = 1,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    rng: np.random.Generator | None = None,
    start: Mapping[str, float] | None = None,
    fixed: Mapping[str, float] | None = None,
    hold: str = "zoh",
    prior_spread: float = PRIOR_SPREAD,
    correlation_time_s: float = MAP_CORRELATION_TIME,
    spread: float = 10.0,
    uncertainty: bool = True,
    max_evals: int | None = None,
) -> FitResult:
    """Estimate the ``free`` parameters of ``network`` from ``data``.

    Parameters
    ----------
    network : RCNetwork
        Model structure; declared parameter values are the construction values and
        the values of non-free parameters.
    data : Dataset
        Columns must match ``network.input_names``, ``flow_names`` and ``outputs``.
    free : sequence of str
        Parameters to estimate (base network parameters, ``sigma_v``,
        ``sigma_w_<state>``, ``x0_<state>``, ``sigma_x0_<state>``).
    method : {"ls", "ml", "map"}
        Output-error least squares (SPEC eq. 8), Kalman-filter maximum likelihood
        (eq. 9), or ML with a log-normal prior on the free R and C.
    optimizer : {"nelder-mead", "powell", "lbfgs"}
    n_starts : int
        Number of starts; the first is ``start`` (default: construction values), the
        others a Latin hypercube (needs ``rng``).
    bounds : mapping of name to (lower, upper), optional
    rng : numpy.random.Generator, optional
        Required when ``n_starts > 1``.
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
    spread : float
        Multistart box: factor around the construction values.
    uncertainty : bool
        Compute the Hessian, standard errors and correlations.
    max_evals : int, optional
        Evaluation budget per start.

    Returns
    -------
    FitResult
    """
    if method not in METHODS:
        raise ParameterError(f"method must be one of {METHODS}, got {method!r}")
    if optimizer not in OPTIMIZERS:
        raise ParameterError(f"optimizer must be one of {OPTIMIZERS}, got {optimizer!r}")
    if hold not in HOLDS:
        raise ParameterError(f"hold must be one of {HOLDS}, got {hold!r}")
    if not isinstance(data, Dataset):
        raise ParameterError(
            f"data must be an rczone Dataset, got {type(data).__name__}; see Dataset.from_frame"
        )
    data.check_against(network)
    if n_starts > 1 and rng is None:
        raise ParameterError("n_starts > 1 needs rng (a numpy.random.Generator) to draw the starts")
    if method == "ls":
        noisy = [n for n in free if n.startswith("sigma_")]
        if noisy:
            raise ParameterError(
                f"noise parameter(s) {noisy} cannot be estimated by least squares; use method='ml' or 'map'"
            )
    ss0 = network.state_space()
    x0a = auto_initial_state(ss0, data.u[0], data.m[0], data.y[0])
    x0_auto = {f"x0_{s}": float(v) for s, v in zip(ss0.state_names, x0a)}
    spec = make_spec(network, free, bounds=bounds, start=start, fixed=fixed, x0_auto=x0_auto)
    if not correlation_time_s > 0:
        raise ParameterError(f"correlation_time_s must be > 0, got {correlation_time_s!r}")
    weight = min(1.0, float(np.median(np.diff(data.t))) / correlation_time_s) if method == "map" else 1.0
    objective = Objective(network, data, spec, method, hold, prior_spread, weight)
    starts = latin_hypercube_starts(spec, n_starts, rng, spread) if n_starts > 1 else spec.start[None]
    outcomes = tuple(minimize_from(objective, spec, s, optimizer, max_evals) for s in starts)
    costs = np.array([o.cost for o in outcomes])
    best = int(np.nanargmin(np.where(np.isfinite(costs), costs, np.nan)))
    win = outcomes[best]
    theta = win.end
    names = spec.names
    d = spec.n_free
    flags: list[str] = []
    if uncertainty:
        H = hessian(objective, spec.to_eta(theta))
        scale = 1.0
        if method == "ls":
            dt = np.diff(data.t)
            tau = float(np.sum(dt[np.isfinite(data.y[:-1, 0]) & np.isfinite(data.y[1:, 0])]))
            scale = 2.0 * win.cost / tau * float(np.mean(dt)) if tau > 0 else math.nan
        unc = covariance(spec, theta, H, scale)
        se, corr = unc.std_error, unc.correlation
        if not unc.positive_definite:
            flags.append("Hessian not positive definite: the parameters are not identifiable from these data")
    else:
        se, corr = np.full(d, np.nan), np.full((d, d), np.nan)
    near = spec.near_bound(theta)
    for n, b in zip(names, near):
        if b:
            flags.append(f"{n} is at a bound")
    if not win.converged:
        flags.append(f"the winning start did not converge: {win.message}")
    values = spec.values(theta)
    return FitResult(
        names=names,
        estimates=dict(zip(names, map(float, theta))),
        std_errors=dict(zip(names, map(float, se))),
        correlation=corr,
        cost=win.cost,
        method=method,
        optimizer=optimizer,
        hold=hold,
        converged=win.converged,
        n_evals=sum(o.n_evals for o in outcomes),
        starts=outcomes,
        best_start=best,
        lower=dict(zip(names, map(float, spec.lower))),
        upper=dict(zip(names, map(float, spec.upper))),
        construction=dict(zip(names, map(float, spec.construction))),
        at_bound=dict(zip(names, map(bool, near))),
        rmse_K=rmse_of(network, values, data, method, hold),
        rmse_kind="open-loop" if method == "ls" else "one-step",
        fixed={k: v for k, v in values.items() if k not in names},
        flags=tuple(flags),
    )
