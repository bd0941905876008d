"""Which parameters are estimated, their bounds, and the theta <-> eta transforms.

The *parameter space* of an estimation problem is the set of base (untied) parameters
of an :class:`~rczone.network.RCNetwork` plus the parameters of the stochastic model
used by the Kalman-filter likelihood:

============================  =========  ==================================================
name                          unit       meaning
============================  =========  ==================================================
``sigma_v``                   K          measurement-noise standard deviation (one output)
``sigma_v_<output>``          K          the same for each output of a multi-output network
``sigma_w_<state>``           K/sqrt(s)  process-noise intensity on state ``<state>``
``x0_<state>``                K / degC   initial state (default: see :func:`auto_initial_state`)
``sigma_x0_<state>``          K          standard deviation of the initial state
============================  =========  ==================================================

Those names are built and read by :mod:`rczone.network.stochastic` only.

Any subset is *free* (estimated); the others are fixed at the values given by the
user or at their defaults (network declarations, :data:`rczone.network.stochastic.KINDS`). Tied network
parameters (``R1 = Rw/2``) are handled by the network and are never free.

``theta`` is the physical value; ``eta`` the optimizer's value: ``eta = log(theta)``
for resistances, capacitances and noise standard deviations, ``eta = theta`` otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from rczone.errors import ParameterError, did_you_mean
from rczone.network import RCNetwork
from rczone.network.stochastic import (
    FIXED_PROCESS_NOISE,
    INITIAL_STATE,
    PROCESS_NOISE,
    default_value,
    kind_of,
    stochastic_parameter_names,
)

#: Default bound factor for log-transformed parameters: ``[theta0 / f, theta0 * f]``.
LOG_BOUND_FACTOR = 1000.0

#: Default half-width (K) of the bounds of an initial state.
X0_HALF_WIDTH = 20.0

_LOG_KINDS = ("resistance", "capacitance", "magnitude", "time", "noise")


def noise_parameter_names(network: RCNetwork) -> tuple[str, ...]:
    """Names of the stochastic-model parameters of ``network`` (see the module table)."""
    return stochastic_parameter_names(network.outputs, network.state_names)


def parameter_kind(network: RCNetwork, name: str) -> str:
    """Kind of a parameter: a network kind, ``"noise"`` (std devs) or ``"state"`` (x0)."""
    if name in network.parameters:
        return network.parameters[name].kind
    return "state" if kind_of(name) == INITIAL_STATE else "noise"


def _default_value(network: RCNetwork, name: str, x0_auto: Mapping[str, float] | None) -> float | None:
    if name in network.parameters:
        return network.parameters[name].value
    if kind_of(name) == INITIAL_STATE:
        return None if x0_auto is None else x0_auto.get(name)
    return default_value(name)


def check_name(network: RCNetwork, name: str, what: str = "parameter") -> None:
    """Raise :class:`ParameterError` unless ``name`` is a base or noise parameter."""
    if name in network.parameters and network.parameters[name].is_tied:
        raise ParameterError(
            f"{what} {name!r} is tied ({name} = {network.parameters[name].expr}); it follows the"
            " parameters it depends on: free those instead"
        )
    known = (*network.free_parameter_names, *noise_parameter_names(network))
    if name not in known:
        raise ParameterError(f"unknown {what} {name!r}; " + did_you_mean(name, known))


@dataclass(frozen=True, eq=False)
class ParameterSpec:
    """Free parameters with bounds and transforms, and the fixed values of the others.

    Build it with :func:`make_spec`. All arrays are in the order of :attr:`names`.

    Attributes
    ----------
    names : tuple of str
        Free parameter names.
    kinds : tuple of str
        ``"resistance"``, ``"capacitance"``, ``"noise"``, ``"state"``, ``"gain"`` or ``"other"``.
    log : ndarray of bool
        Whether ``eta = log(theta)`` (else ``eta = theta``).
    start, lower, upper : ndarray
        Start value and bounds in theta (physical units).
    construction : ndarray
        Reference (construction / declared default) values, NaN where none exists.
    fixed : dict of str to float
        Values of every non-free parameter that has one (``x0_*`` may be absent: then
        the data-driven default of :func:`auto_initial_state` is used).
    """

    names: tuple[str, ...]
    kinds: tuple[str, ...]
    log: np.ndarray
    start: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    construction: np.ndarray
    fixed: Mapping[str, float]

    @property
    def n_free(self) -> int:
        return len(self.names)

    # ------------------------------------------------------------ transforms
    def to_eta(self, theta: np.ndarray) -> np.ndarray:
        """Optimizer values from physical values (``log`` where :attr:`log`)."""
        theta = np.asarray(theta, dtype=float)
        if np.any(theta[self.log] <= 0):
            bad = self.names[int(np.flatnonzero(self.log & (theta <= 0))[0])]
            raise ParameterError(f"parameter {bad!r} must be > 0 to take its logarithm")
        return np.where(self.log, np.log(np.where(self.log, theta, 1.0)), theta)

    def to_theta(self, eta: np.ndarray) -> np.ndarray:
        """Physical values from optimizer values (inverse of :meth:`to_eta`)."""
        eta = np.asarray(eta, dtype=float)
        return np.where(self.log, np.exp(np.where(self.log, eta, 0.0)), eta)

    def jacobian(self, eta: np.ndarray) -> np.ndarray:
        """Diagonal of ``d theta / d eta`` (``theta`` for log parameters, 1 otherwise)."""
        return np.where(self.log, self.to_theta(eta), 1.0)

    @property
    def eta_lower(self) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return np.where(self.log, np.log(np.where(self.log, self.lower, 1.0)), self.lower)

    @property
    def eta_upper(self) -> np.ndarray:
        return np.where(self.log, np.log(np.where(self.log, self.upper, 1.0)), self.upper)

    # -------------------------------------------------- bounded unconstrained
    def to_z(self, eta: np.ndarray) -> np.ndarray:
        """Unbounded variable for direct search: ``z = logit((eta - lo) / (hi - lo))``.

        Bounds are enforced by this transform, so a direct-search method never
        evaluates outside them and nothing is clipped.
        """
        lo, hi = self.eta_lower, self.eta_upper
        f = (np.asarray(eta, dtype=float) - lo) / (hi - lo)
        with np.errstate(divide="ignore"):
            return np.log(f) - np.log1p(-f)

    def from_z(self, z: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_z`."""
        lo, hi = self.eta_lower, self.eta_upper
        return lo + (hi - lo) * (0.5 * (1.0 + np.tanh(0.5 * np.asarray(z, dtype=float))))

    # --------------------------------------------------------------- values
    def values(self, theta: np.ndarray) -> dict[str, float]:
        """Every parameter value: the fixed ones updated with the free ``theta``."""
        out = dict(self.fixed)
        out.update(zip(self.names, (float(v) for v in theta)))
        return out

    def near_bound(self, theta: np.ndarray, tol: float = 1e-3) -> np.ndarray:
        """Which estimates lie within ``tol`` (relative width in eta) of a bound."""
        eta = self.to_eta(theta)
        width = self.eta_upper - self.eta_lower
        return ((eta - self.eta_lower) <= tol * width) | ((self.eta_upper - eta) <= tol * width)


def make_spec(
    network: RCNetwork,
    free: Sequence[str],
    bounds: Mapping[str, tuple[float, float]] | None = None,
    start: Mapping[str, float] | None = None,
    fixed: Mapping[str, float] | None = None,
    x0_auto: Mapping[str, float] | None = None,
) -> ParameterSpec:
    """Declare the free parameters of an estimation problem.

    Parameters
    ----------
    network : RCNetwork
    free : sequence of str
        Names of the parameters to estimate: base network parameters and/or noise
        parameters (:func:`noise_parameter_names`).
    bounds : mapping of name to (lower, upper), optional
        Bounds in physical units. Default: the bounds declared on the network parameter,
        else ``[theta0/1000, theta0*1000]`` for
        resistances, capacitances and noise standard deviations, ``theta0 +- 20 K`` for
        initial states and ``theta0 +- max(10 |theta0|, 1)`` otherwise.
    start : mapping of name to float, optional
        Start values of free parameters; default the construction value.
    fixed : mapping of name to float, optional
        Values for non-free parameters (override the declared defaults).
    x0_auto : mapping of ``x0_<state>`` to float, optional
        Data-driven default initial state (start of a free ``x0_*``).

    Returns
    -------
    ParameterSpec

    Raises
    ------
    ParameterError
        For an unknown or tied name, a name both free and fixed, a bound with
        ``lower >= upper``, a non-positive bound of a log parameter, a start outside the
        bounds, or a free parameter without a start value. Nothing is clipped or swapped.
    """
    free = tuple(free)
    bounds = dict(bounds or {})
    start = dict(start or {})
    fixed = dict(fixed or {})
    if not free:
        raise ParameterError("no free parameter given; name at least one (e.g. free=['Cr', 'Rw'])")
    if len(set(free)) != len(free):
        dup = next(n for n in free if free.count(n) > 1)
        raise ParameterError(f"free parameter {dup!r} is listed twice")
    for name in free:
        check_name(network, name, "free parameter")
    for name, what in [*((n, "bound") for n in bounds), *((n, "start value") for n in start)]:
        check_name(network, name, what)
        if name not in free:
            raise ParameterError(f"{what} given for {name!r}, which is not free; add it to free or drop it")
    for name in fixed:
        check_name(network, name, "fixed parameter")
        if name in free:
            raise ParameterError(f"parameter {name!r} is both free and fixed; choose one")
    kinds = tuple(parameter_kind(network, n) for n in free)
    log = np.array([k in _LOG_KINDS for k in kinds])
    st, lo, hi, con = (np.empty(len(free)) for _ in range(4))
    for i, name in enumerate(free):
        c = _default_value(network, name, x0_auto)
        con[i] = np.nan if c is None or kinds[i] in ("noise", "state") else c
        s = start.get(name, c)
        if s is None:
            raise ParameterError(
                f"free parameter {name!r} has no start value: declare a value or pass start={{{name!r}: ...}}"
            )
        s = float(s)
        if not math.isfinite(s) or (log[i] and s <= 0):
            raise ParameterError(
                f"start of {name!r} = {s!r}: expected a finite value" + (" > 0" if log[i] else "")
            )
        st[i] = s
        if name in bounds:
            try:
                lo[i], hi[i] = (float(b) for b in bounds[name])
            except (TypeError, ValueError):
                raise ParameterError(
                    f"bounds of {name!r} must be a (lower, upper) pair, got {bounds[name]!r}"
                ) from None
        elif name in network.parameters and network.parameters[name].bounds is not None:
            lo[i], hi[i] = network.parameters[name].bounds
        elif log[i]:
            ref = c if c is not None and c > 0 else s
            lo[i], hi[i] = ref / LOG_BOUND_FACTOR, ref * LOG_BOUND_FACTOR
        elif kinds[i] == "state":
            lo[i], hi[i] = s - X0_HALF_WIDTH, s + X0_HALF_WIDTH
        else:
            w = max(10.0 * abs(s), 1.0)
            lo[i], hi[i] = s - w, s + w
        if not lo[i] < hi[i]:
            raise ParameterError(
                f"bounds of {name!r}: lower {lo[i]:g} must be < upper {hi[i]:g} (they are never swapped)"
            )
        if log[i] and lo[i] <= 0:
            raise ParameterError(
                f"lower bound of {name!r} = {lo[i]:g}: a {kinds[i]} is estimated in log space and needs a"
                " lower bound > 0"
            )
        if not lo[i] < s < hi[i]:
            raise ParameterError(
                f"start of {name!r} = {s:g} is outside its bounds ({lo[i]:g}, {hi[i]:g}); move the start or"
                " widen the bounds (values are never clipped)"
            )
    values: dict[str, float] = {}
    for name in (*network.free_parameter_names, *noise_parameter_names(network)):
        if name in free:
            continue
        # x0_* without a user value stays absent: the cost derives it from the data and the
        # current parameters (auto_initial_state), not from the construction values
        v = fixed.get(name)
        if v is None:
            v = FIXED_PROCESS_NOISE if kind_of(name) == PROCESS_NOISE else _default_value(network, name, None)
        if v is not None:
            values[name] = float(v)
    return ParameterSpec(free, kinds, log, st, lo, hi, con, MappingProxyType(values))
