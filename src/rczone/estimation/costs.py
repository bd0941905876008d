"""Identification costs: output-error least squares, Kalman likelihood, and MAP.

* ``J_LS`` (Lin et al. 2012, eq. (8)): the integral over time of the squared open-loop output error,
  ``int (y - y_hat)^2 dt``, evaluated by the trapezoid rule over the sample times, so
  irregular sampling is weighted correctly. An interval enters only when both of its
  end samples are measured: a gap (NaN in ``y``) removes the intervals touching it, i.e.
  the integral is split at the gap. Units K^2 s.
* ``J_ML`` (Lin et al. 2012, eq. (9)): ``-log L`` of the continuous-discrete stochastic model, by the
  Kalman filter (:mod:`rczone.estimation.kalman`); one measurement-noise level per output.
* ``J_MAP = w J_ML - log p(eta)``: the declared prior of every free parameter that has one
  (:mod:`rczone.network.prior`, carried to the optimizer's scale by :mod:`rczone.estimation.priors`),
  and for the other free resistances and capacitances ``0.5 ((log theta_i - log theta_i,construction) / s)^2``,
  a log-normal prior centred on the construction value with spread ``s`` (default ``log 2``: a
  factor 2 is one standard deviation).

Initial state
-------------
``x0_<state>`` values given (fixed or free) are used. The others default to
:func:`auto_initial_state`: measured states start at their first measurement and the
unmeasured ones at the steady state given it and the first inputs (e.g. the wall at
steady state with the measured room temperature). Without a first measurement, the
full steady state is used.

Engines
-------
How a cost is computed (fused 2-state kernel, one compiled call, Python assembly with the
compiled filter, or plain NumPy) is decided by the declared rules of
:mod:`rczone.estimation.engines`; :attr:`Objective.engine` names the one used. Gradients
(:meth:`Objective.value_and_gradient`) are exact: a backward (adjoint) pass of the filter
for the compiled likelihoods, forward sensitivities through the discretization and the filter
(or the simulation, for ``J_LS``) otherwise.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.compiled import compiled_problem
from rczone.estimation.data import Dataset
from rczone.estimation.engines import (
    ENGINES,
    auto_initial_state,
    choose_engine,
    filter_arrays,
    general_cost,
    gradient_engine,
    initial_state,
    measured_states,
    network_theta,
    noise_values,
    run_filter,
    simulate_output,
    trapezoid_sse,
)
from rczone.estimation.methods import map as _map
from rczone.estimation.methods import method_of
from rczone.estimation.parameters import ParameterSpec, make_spec
from rczone.estimation.priors import LogPrior, log_prior
from rczone.kernels.adjoint import gradient_kernel
from rczone.kernels.arrays import Problem
from rczone.kernels.problem import LS, cost_and_gradient, value_kernel
from rczone.network import RCNetwork
from rczone.network.stochastic import (
    initial_spread_names,
    initial_state_names,
    measurement_noise_names,
    process_noise_names,
)

__all__ = [
    "MAP_CORRELATION_TIME",
    "PRIOR_SPREAD",
    "Objective",
    "auto_initial_state",
    "filter_arrays",
    "initial_state",
    "log_prior_penalty",
    "ls_cost",
    "measured_states",
    "ml_cost",
    "network_theta",
    "noise_values",
    "run_filter",
    "simulate_output",
    "trapezoid_sse",
]

#: Default spread of the MAP log-normal prior (a factor 2 is one standard deviation), and the
#: correlation time of the output error MAP assumes by default, s: the likelihood of N samples
#: ``dt`` apart counts as that of ``N dt / MAP_CORRELATION_TIME`` independent ones, as in
#: :func:`rczone.diagnostics.diagnose` (the options of :mod:`rczone.estimation.methods.map`).
PRIOR_SPREAD = _map.PRIOR_SPREAD
MAP_CORRELATION_TIME = _map.CORRELATION_TIME_S


def ls_cost(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> float:
    """``J_LS = int (y - y_hat)^2 dt`` (K^2 s) of the open-loop simulation; see the module notes.

    Computed as an :class:`Objective` would (see :func:`public_cost`).
    """
    return public_cost(network, values, data, hold, "ls")


def ml_cost(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> float:
    """``J_ML = -log L`` including ``0.5 n log(2 pi)``.

    Computed as an :class:`Objective` would (see :func:`public_cost`).
    """
    return public_cost(network, values, data, hold, "ml")


#: Objectives kept per data set for :func:`public_cost` (one per network, hold, method and value names).
PUBLIC_KEPT = 8


def public_cost(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str, method: str
) -> float:
    """``J_LS`` or ``J_ML`` at parameter ``values`` by the compiled engines, their structure built once.

    :func:`ml_cost` and :func:`ls_cost` are called in loops (an MPC, an emulator, a user's own
    optimizer) with new values on the same network and data. The first call packs the problem
    into an :class:`Objective` whose free parameters are the names in ``values``
    (:func:`_public_objective`); it is kept on the (immutable) data set, keyed by the network,
    hold, method and the names of ``values``, so later calls only pass the values to the
    compiled kernel. Problems that do not pack, and values where the compiled cost is not finite
    (an invalid value, which the general engine then reports), take the general engine
    (:func:`rczone.estimation.engines.general_cost`): the results are the same to rounding.

    Parameters
    ----------
    network : RCNetwork
    values : mapping of name to float
        Base parameters (the network's values for those missing), noise levels (ML), ``x0_*``.
    data : Dataset
    hold : {"zoh", "foh"}
    method : {"ls", "ml"}
    """
    if isinstance(data, Dataset) and hold in ("zoh", "foh"):
        kept = data.__dict__.setdefault("_public_objectives", {})
        key = (id(network), hold, method, tuple(values))
        entry = kept.get(key)
        if entry is None or entry[0] is not network:  # the entry holds its network: ids are not reused
            if len(kept) >= PUBLIC_KEPT:
                kept.pop(next(iter(kept)))
            entry = kept[key] = (network, *_public_objective(network, values, data, hold, method))
        objective, names = entry[1], entry[2]
        if objective is not None:
            try:
                theta = np.array([values[n] for n in names], dtype=np.float64)
            except (TypeError, ValueError):
                theta = None
            if theta is not None:
                j = objective.theta_cost(theta)
                if math.isfinite(j):
                    return float(j)
    return general_cost(network, values, data, hold, method)[0]


def _public_objective(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str, method: str
) -> tuple[Objective | None, tuple[str, ...]]:
    """The compiled :class:`Objective` of :func:`public_cost` and its parameter names, or ``(None, ())``.

    Its free parameters are the network's base parameters given in ``values``, the noise
    levels (ML) and the given ``x0_*``; the other base parameters are fixed at the network's
    values, as the general engine takes them. Start and bounds play no part (the cost is taken
    at ``theta``): every start is 1 inside the widest bounds.
    """
    states = network.state_names
    names = [n for n in network.free_parameter_names if n in values]
    if method == "ml":
        noise = (
            *measurement_noise_names(network.outputs),
            *process_noise_names(states),
            *initial_spread_names(states),
        )
        if any(n not in values for n in noise):
            return None, ()
        names += noise
    names += [n for n in initial_state_names(states) if n in values]
    declared = network.values()
    fixed = {
        n: declared[n]
        for n in network.free_parameter_names
        if n not in values and declared.get(n) is not None
    }
    try:
        spec = make_spec(
            network,
            names,
            bounds={n: (1e-300, 1e300) for n in names},
            start=dict.fromkeys(names, 1.0),
            fixed=fixed,
        )
        objective = Objective(network, data, spec, method, hold)
    except ParameterError:
        return None, ()
    return (objective, tuple(names)) if objective.compiled is not None else (None, ())


def log_prior_penalty(spec: ParameterSpec, theta: np.ndarray, spread: float = PRIOR_SPREAD) -> float:
    """``sum 0.5 ((log theta - log theta_c) / s)^2`` over free resistances and capacitances (no declared prior)."""
    return log_prior(spec, {}, default="construction", spread=spread).terms(theta)[0]


@dataclass(frozen=True, eq=False)
class Objective:
    """The cost of one estimation problem as a function of the free parameters.

    Calling it never mutates the network, the data or the spec. Invalid parameter
    values (e.g. a non-positive resistance from a non-log parameter) return ``inf``
    instead of raising, so direct search can step back.

    The engine is chosen by the declared rules of :mod:`rczone.estimation.engines` (or
    forced with ``engine``) and named by :attr:`engine` after construction; problems that
    pack into arrays (:func:`rczone.estimation.compiled.compiled_problem`: networks in
    conductance form whose element values are proportional to the free parameters, such as
    the paper's) are evaluated by one compiled call, several times faster than the general
    engine.

    Attributes
    ----------
    network : RCNetwork
    data : Dataset
    spec : ParameterSpec
    method : {"ls", "ml", "map"}
    hold : {"zoh", "foh"}
    prior_spread : float
        ``s`` of the MAP prior (log units).
    likelihood_weight : float
        MAP only: ``J_MAP = w J_ML + prior``. Residuals of a low-order building model are
        correlated over tens of minutes, so ``-log L`` of a white-noise model overstates the
        information in the data by the ratio of that correlation time to the sample time;
        ``w = dt / t_corr`` counts it once per correlation time (a tempered, or power,
        likelihood [1]_). The ML optimum of the noise parameters is unchanged by ``w``.
    engine : str
        Requested as ``"auto"`` (default) or one of
        :data:`rczone.estimation.engines.ENGINES`; after construction, the engine of the
        values (:meth:`__call__`). :attr:`gradient_engine` is that of the gradients.

    References
    ----------
    .. [1] P. G. Bissiri, C. C. Holmes, S. G. Walker, "A general framework for updating
       belief distributions", J. R. Stat. Soc. B 78(5), 2016.
    """

    network: RCNetwork
    data: Dataset
    spec: ParameterSpec
    method: str = "ls"
    hold: str = "zoh"
    prior_spread: float = PRIOR_SPREAD
    likelihood_weight: float = 1.0
    engine: str = "auto"

    def __post_init__(self) -> None:
        meth = method_of(self.method)
        if not self.prior_spread > 0:
            raise ParameterError(f"prior_spread must be > 0, got {self.prior_spread!r}")
        prior = (
            log_prior(self.spec, self.network.priors, default="construction", spread=self.prior_spread)
            if meth.prior
            else None
        )
        object.__setattr__(self, "_prior", prior)
        if not 0 < self.likelihood_weight <= 1:
            raise ParameterError(f"likelihood_weight must be in (0, 1], got {self.likelihood_weight!r}")
        if self.engine not in ("auto", *ENGINES):
            raise ParameterError(f"engine must be 'auto' or one of {ENGINES}, got {self.engine!r}")
        packed = compiled_problem(self)
        rule = choose_engine(len(self.network.state_names), len(self.network.outputs), packed is not None)
        engine = rule if self.engine == "auto" else self.engine
        if engine in ("rc2-fused", "compiled") and (
            packed is None or (engine == "rc2-fused" and rule != engine)
        ):
            raise ParameterError(
                f"engine {engine!r} does not apply to this problem (the rules choose {rule!r});"
                " see rczone.estimation.engines"
            )
        if packed is not None and engine != "rc2-fused":
            packed = packed._replace(
                consts=packed.consts._replace(fused=False)
            )  # values from the general kernel
        object.__setattr__(self, "engine", engine)
        object.__setattr__(self, "_packed", packed if engine in ("rc2-fused", "compiled") else None)
        # the compiled value kernel of the engine, chosen once (rczone.kernels.problem.value_kernel)
        object.__setattr__(self, "_value", None if self._packed is None else value_kernel(self._packed))
        # the adjoint gradient of the 2-state likelihood (rczone.kernels.adjoint); least squares keeps the forward one
        object.__setattr__(self, "_adjoint", engine == "rc2-fused" and method_of(self.method).kernel != "ls")
        # the reverse pass of the general filter for the other compiled likelihoods (rczone.kernels.reverse)
        object.__setattr__(self, "_reverse", engine == "compiled" and method_of(self.method).kernel != "ls")
        # either bound once to the packed problem (rczone.kernels.adjoint.gradient_kernel)
        gradient = self._adjoint or self._reverse
        object.__setattr__(
            self, "_gradient", gradient_kernel(self._packed, fused=self._adjoint) if gradient else None
        )

    @property
    def compiled(self) -> Problem | None:
        """The packed problem of a search that never leaves compiled code, or None.

        A MAP problem's packed prior (:attr:`rczone.kernels.arrays.Problem.penalty`) holds every
        prior of :attr:`map_prior`, declared or the construction default, and the compiled costs
        evaluate it (:func:`rczone.kernels.problem.prior_terms`, the function
        :meth:`rczone.estimation.priors.LogPrior.terms` calls too).
        """
        return self._packed

    @property
    def declared_prior(self) -> bool:
        """Whether a MAP problem has a declared prior on a free parameter (:mod:`rczone.network.prior`)."""
        return self._prior is not None and bool(self._prior.declared)

    @property
    def map_prior(self) -> LogPrior | None:
        """The prior a MAP cost adds (:func:`rczone.estimation.priors.log_prior`); None for LS and ML."""
        return self._prior

    @property
    def adjoint_gradient(self) -> bool:
        """Whether the fused 2-state adjoint kernel serves a likelihood fit (:func:`rczone.kernels.adjoint.gradient_fused`).

        Its values, gradients and innovations then come from that one kernel, and a fit's curvature
        from differences of its gradients. The ``"compiled"`` engine's likelihoods also take their
        gradients from a backward pass (:func:`rczone.kernels.adjoint.gradient_general`) but keep
        the forward sensitivities for the Fisher curvature, one evaluation instead of ``d + 1``.
        """
        return self._adjoint

    @property
    def backward_gradient(self) -> bool:
        """Whether :meth:`value_and_gradient` is a backward pass (the fused 2-state adjoint or the general
        filter's reverse pass): a gradient then costs a few likelihoods whatever the number of
        parameters, so a Hessian from ``2 d`` gradients costs less than one from ``2 d^2`` values."""
        return self._adjoint or self._reverse

    @property
    def gradient_engine(self) -> str:
        """The engine of :meth:`value_and_gradient`."""
        return gradient_engine(self.engine)

    def theta_cost(self, theta: np.ndarray) -> float:
        """Cost at physical values ``theta`` (order of ``spec.names``)."""
        if self._packed is not None:
            return self._value(np.asarray(theta, dtype=np.float64), self._packed)
        return self._general(np.asarray(theta, dtype=float), False)[0]

    def theta_value_and_gradient(self, theta: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Cost at physical values ``theta``, its exact gradient and a diagonal curvature estimate, in theta.

        The curvature is the diagonal of the Fisher information (ML, MAP) or of the
        Gauss-Newton Hessian (LS). ``(inf, 0, 0)`` where the model is invalid.
        """
        theta = np.asarray(theta, dtype=np.float64)
        if self.gradient_engine == "compiled":
            j, g, c = cost_and_gradient(theta, self._packed)
            return (
                (float(j), g, c)
                if math.isfinite(j)
                else (math.inf, np.zeros(theta.size), np.zeros(theta.size))
            )
        return self._general(theta, True)

    def _general(self, theta: np.ndarray, want_grad: bool) -> tuple[float, np.ndarray, np.ndarray]:
        """The general engine at ``theta`` (``inf`` where the parameters are invalid)."""
        values = self.spec.values(theta)
        wrt = self.spec.names if want_grad else ()
        zero = np.zeros(theta.size)
        try:
            j, g, c = general_cost(
                self.network, values, self.data, self.hold, method_of(self.method).kernel, wrt
            )
        except (ParameterError, np.linalg.LinAlgError):
            return math.inf, zero, zero
        if not want_grad:
            g = c = zero
        if self._prior is not None:
            pen, dpen, cpen = self._prior.terms(theta)
            j = self.likelihood_weight * j + pen
            if want_grad:
                g = self.likelihood_weight * g + dpen
                c = self.likelihood_weight * c + cpen
        if not math.isfinite(j):
            return math.inf, zero, zero
        return j, np.asarray(g, dtype=float), np.asarray(c, dtype=float)

    def __call__(self, eta: np.ndarray) -> float:
        """Cost at optimizer values ``eta``."""
        c = self.theta_cost(self.spec.to_theta(eta))
        return c if math.isfinite(c) else math.inf

    def value_and_gradient(self, eta: np.ndarray) -> tuple[float, np.ndarray]:
        """Cost at optimizer values ``eta`` and its exact gradient with respect to ``eta``.

        A likelihood (ML, MAP) of the ``"rc2-fused"`` and ``"compiled"`` engines takes its gradient
        from one backward pass (:mod:`rczone.kernels.adjoint`: the unrolled 2-state pass, or the
        reverse pass of the general filter, :mod:`rczone.kernels.reverse`), about three
        likelihoods whatever the number of parameters; least squares and the ``"general"``
        engine from forward sensitivities (see :mod:`rczone.kernels.kalman`), one evaluation
        either way, not ``2 d + 1``. ``(inf, zeros)`` where the model is invalid.
        """
        eta = np.asarray(eta, dtype=float)
        theta = self.spec.to_theta(eta)
        if self._adjoint or self._reverse:
            theta = np.asarray(theta, dtype=np.float64)
            j, g = self._gradient(theta, self._packed)
        else:
            j, g, _ = self.theta_value_and_gradient(theta)
        if not math.isfinite(j):
            return math.inf, np.zeros(eta.size)
        return j, g * np.where(self.spec.log, theta, 1.0)  # spec.jacobian(eta), theta known

    def innovations(self, eta: np.ndarray) -> np.ndarray:
        """One-step-ahead prediction errors at ``eta`` (NaN where missing), from the adjoint kernel's filter.

        Only where :attr:`adjoint_gradient` holds: a fit then computes its RMSE without compiling a
        second filter (:func:`rczone.estimation.fit.rmse_of` is the general way).
        """
        if not self._adjoint:
            raise ParameterError("innovations come from the adjoint kernel of a 2-state likelihood only")
        self._gradient(np.asarray(self.spec.to_theta(eta), dtype=np.float64), self._packed)
        return self._packed.scratch.copy()

    def output_errors(self, eta: np.ndarray) -> np.ndarray | None:
        """Open-loop output errors ``y - y_hat`` at ``eta`` (NaN where missing) from the fused value kernel, or None.

        Only for least squares on the ``"rc2-fused"`` engine, whose value kernel leaves them in its
        scratch buffer: a fit then computes its open-loop RMSE without a second simulation
        (:func:`rczone.estimation.fit.rmse_of` is the general way).
        """
        if self._packed is None or not self._packed.consts.fused or self._packed.kind != LS:
            return None
        self.theta_cost(self.spec.to_theta(eta))
        return self._packed.scratch.copy()

    def curvature(self, eta: np.ndarray) -> np.ndarray:
        """Diagonal curvature estimate of the cost in ``eta`` (Fisher information or Gauss-Newton).

        Positive semidefinite, cheap (one gradient evaluation) and close to the diagonal of the
        Hessian near the optimum: optimizers scale their variables with its square root
        (:func:`rczone.estimation.optimize.minimize_from`). Zeros where the model is invalid.
        """
        eta = np.asarray(eta, dtype=float)
        _, _, c = self.theta_value_and_gradient(self.spec.to_theta(eta))
        return c * self.spec.jacobian(eta) ** 2
