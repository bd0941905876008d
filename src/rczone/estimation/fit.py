"""``fit``: estimate free parameters of an RC network from a data set.

The top-level function builds the problem once (default free set, bounds, start values, the
parameter spec) and hands it to the method (:mod:`rczone.estimation.methods`), which returns the
frozen :class:`~rczone.estimation.result.FitResult`. The network is never modified.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import auto_initial_state
from rczone.estimation.data import Dataset
from rczone.estimation.methods import FitProblem, method_of
from rczone.estimation.parameters import make_spec
from rczone.estimation.resolution import noise_floor
from rczone.estimation.result import FitResult
from rczone.estimation.settings import FitSettings
from rczone.kernels.blas import single_threaded
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


@single_threaded
def fit(
    network: RCNetwork,
    data: Dataset,
    free: Sequence[str] | None = None,
    *,
    settings: FitSettings | None = None,
    rng: np.random.Generator | None = None,
    start: Mapping[str, float] | None = None,
    fixed: Mapping[str, float] | None = None,
    uncertainty: bool = True,
    max_evals: int | None = None,
    initial_state: str = "estimate",
    **overrides: Any,
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
    settings : FitSettings, optional
        How to fit (:class:`~rczone.estimation.settings.FitSettings`): the method and its options,
        the search, the hold, the bounds; default ``FitSettings()`` (maximum likelihood, the global
        search), as ``rczone fit``. Its ``fixed`` values apply where ``fixed`` gives none, its free
        set (:meth:`~rczone.estimation.settings.FitSettings.free_for`) where ``free`` is not given.
    rng : numpy.random.Generator, optional
        Draws the global phase (or the sampler's starts); default one seeded by ``settings.seed``.
    start, fixed : mapping of name to float, optional
        Start values of free parameters; values of non-free ones.
    uncertainty : bool
        Compute the Hessian, standard errors and correlations.
    max_evals : int, optional
        Evaluation budget per local search.
    initial_state : {"estimate", "steady"}
        Only when ``free`` is not given: ``"estimate"`` (default) frees the initial temperature of
        every unmeasured state in an LS fit; ``"steady"`` starts them in equilibrium with the first
        inputs and measurement, which biases the fit when the data do not start at rest. ML and
        MAP fits carry an initial-state uncertainty in the filter either way.
    **overrides
        Fields of :class:`~rczone.estimation.settings.FitSettings` replacing those of ``settings``
        (``method="ls"``, ``n_starts=1``, ``options={"draws": 500}``, ...), as
        ``lmfit.minimize(..., method=...)`` takes them; any other name is refused.

    Returns
    -------
    FitResult
    """
    settings = FitSettings.of(settings, exclude=("free", "fixed"), **overrides)
    meth = method_of(settings.method)
    if initial_state not in ("estimate", "steady"):
        raise ParameterError(f"initial_state must be 'estimate' or 'steady', got {initial_state!r}")
    if not isinstance(data, Dataset):
        raise ParameterError(
            f"data must be an rczone Dataset, got {type(data).__name__}; see Dataset.from_frame"
        )
    data.check_against(network)
    if free:
        free = tuple(free)
    elif settings.free is None and initial_state == "steady":
        free = default_free(network, meth.name, initial_state, settings.noise)
    else:
        free = settings.free_for(network)
    bounds = settings.bounds
    if fixed is None:
        fixed = {k: v for k, v in settings.fixed.items() if v is not None}
    if not meth.stochastic:
        noisy = [n for n in free if is_noise_name(n)]
        if noisy:
            raise ParameterError(
                f"noise parameter(s) {noisy} cannot be estimated by"
                f" {'least squares' if meth.kernel == 'ls' else meth.title} (no noise model); use method='ml' or 'map'"
            )
    rng = np.random.default_rng(settings.seed) if rng is None else rng
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
    problem = FitProblem(
        network,
        data,
        spec,
        meth.name,
        settings.hold,
        settings.optimizer,
        settings.n_starts,
        max_evals,
        uncertainty,
    )
    result = meth.run(problem, settings.options, rng)
    if not isinstance(result, FitResult):
        raise ParameterError(f"method {meth.name!r} returned a {type(result).__name__}, not a FitResult")
    return dataclasses.replace(result, method=meth.name, options=settings.options.to_dict())
