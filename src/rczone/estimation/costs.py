"""Identification costs: output-error least squares, Kalman likelihood, and MAP.

* ``J_LS`` (SPEC eq. 8): the integral over time of the squared open-loop output error,
  ``int (y - y_hat)^2 dt``, evaluated by the trapezoid rule over the sample times, so
  irregular sampling is weighted correctly. An interval enters only when both of its
  end samples are measured: a gap (NaN in ``y``) removes the intervals touching it, i.e.
  the integral is split at the gap. Units K^2 s.
* ``J_ML`` (SPEC eq. 9): ``-log L`` of the continuous-discrete stochastic model, by the
  Kalman filter (:mod:`rczone.estimation.kalman`).
* ``J_MAP = J_ML + sum_i 0.5 ((log theta_i - log theta_i,construction) / s)^2`` over the
  free resistances and capacitances: a log-normal prior centred on the construction
  value with spread ``s`` (default ``log 2``: a factor 2 is one standard deviation).

Initial state
-------------
``x0_<state>`` values given (fixed or free) are used. The others default to
:func:`auto_initial_state`: measured states start at their first measurement and the
unmeasured ones at the steady state given it and the first inputs (e.g. the wall at
steady state with the measured room temperature). Without a first measurement, the
full steady state is used.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rczone.errors import InputShapeError, ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.kalman import (
    FilterOutput,
    kalman_filter_arrays,
    kalman_nll_fast,
    stochastic_matrices,
)
from rczone.estimation.parameters import ParameterSpec
from rczone.kernels.kalman import kalman_nll_rc2, kalman_nll_rc2_values, rc2_applicable
from rczone.kernels.propagate import propagate
from rczone.network import BilinearStateSpace, RCNetwork
from rczone.simulation.simulate import transition_matrices

#: Default spread of the MAP log-normal prior: a factor 2 is one standard deviation.
PRIOR_SPREAD = math.log(2.0)
#: Correlation time of the output error assumed by MAP, s: the likelihood of N samples
#: ``dt`` apart counts as that of ``N dt / MAP_CORRELATION_TIME`` independent ones, as in
#: :func:`rczone.diagnostics.diagnose`.
MAP_CORRELATION_TIME = 1800.0

METHODS = ("ls", "ml", "map")


def measured_states(ss: BilinearStateSpace) -> dict[int, int]:
    """Map state index -> output index for outputs that read one state directly (C row = e_i, D row = 0)."""
    C = ss.C
    direct = ((C != 0).sum(axis=1) == 1) & (C == 1.0).any(axis=1) & ~ss.D.any(axis=1)
    out: dict[int, int] = {}
    for j in np.flatnonzero(direct).tolist():
        out.setdefault(int(C[j].argmax()), j)
    return out


def auto_initial_state(ss: BilinearStateSpace, u0: np.ndarray, m0: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """Measured states at their first measurement, the others at the conditional steady state.

    Parameters
    ----------
    ss : BilinearStateSpace
    u0 : ndarray, shape (p,)
    m0 : ndarray, shape (n_flows,)
    y0 : ndarray, shape (ny,)
        First measurement (NaN entries are treated as unmeasured).

    Returns
    -------
    ndarray, shape (n,)
    """
    A, B = ss.matrices(m0) if ss.n_flows else (ss.A, ss.B)
    meas = {i: j for i, j in measured_states(ss).items() if math.isfinite(y0[j])}
    x = np.zeros(ss.n_states)
    fixed = np.array(sorted(meas), dtype=int)
    free = np.array([i for i in range(ss.n_states) if i not in meas], dtype=int)
    x[fixed] = [y0[meas[i]] for i in fixed]
    if free.size == 1:  # the common 2-state case, without the LAPACK call
        f = free[0]
        x[f] = -(B[f] @ u0 + A[f, fixed] @ x[fixed]) / A[f, f]
    elif free.size:
        rhs = -(B[free] @ u0) - A[np.ix_(free, fixed)] @ x[fixed]
        x[free] = np.linalg.solve(A[np.ix_(free, free)], rhs)
    return x


def initial_state(ss: BilinearStateSpace, values: Mapping[str, float], data: Dataset) -> np.ndarray:
    """Initial state from ``x0_<state>`` values where given, else :func:`auto_initial_state`."""
    names = [f"x0_{s}" for s in ss.state_names]
    if all(n in values for n in names):
        return np.array([values[n] for n in names])
    x = auto_initial_state(ss, data.u[0], data.m[0], data.y[0])
    for i, n in enumerate(names):
        if n in values:
            x[i] = values[n]
    return x


def network_theta(network: RCNetwork, values: Mapping[str, float]) -> dict[str, float]:
    """The network's base parameter values out of a full value mapping."""
    return {n: values[n] for n in network.free_parameter_names if n in values}


def trapezoid_sse(t: np.ndarray, e: np.ndarray) -> float:
    """``int e(t)^2 dt`` by the trapezoid rule, skipping intervals with a missing end.

    Parameters
    ----------
    t : ndarray, shape (N,)
    e : ndarray, shape (N, ny)
        Errors; NaN where the measurement is missing. Outputs are summed.
    """
    sq = e * e
    seg = 0.5 * (sq[:-1] + sq[1:]) * np.diff(t)[:, None]
    return float(np.sum(seg[np.isfinite(seg)]))


def simulate_output(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop states and outputs, shapes (N, n) and (N, ny)."""
    ss = network.state_space(network_theta(network, values))
    x0 = initial_state(ss, values, data)
    Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, hold)
    x = propagate(Phi, G0, G1, which, data.u, x0)
    return x, x @ ss.C.T + data.u @ ss.D.T


def ls_cost(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> float:
    """``J_LS = int (y - y_hat)^2 dt`` (K^2 s) of the open-loop simulation; see the module notes.

    A 2-state model with one output runs the fused compiled kernel of the ML cost with no
    process noise and no initial uncertainty: its gain is then zero, the state evolves open
    loop, and its innovations are exactly the open-loop output errors.
    """
    zero = np.zeros((2, 2))
    if fused_path_applies(network, values, data):
        e = np.full(data.t.shape[0], np.nan)
        res, cap = network.conductance_values(network_theta(network, values))
        kalman_nll_rc2_values(
            network, res, cap, data.t, data.m, data.u, data.y, zero, zero, 1.0, hold, e, data.interval_groups
        )
        return trapezoid_sse(data.t, e[:, None])
    ss = network.state_space(network_theta(network, values))
    e = np.full(data.t.shape[0], np.nan)
    if _nll_rc2_or_none(ss, values, data, hold, zero, zero, 1.0, e) is not None:
        return trapezoid_sse(data.t, e[:, None])
    _, yhat = simulate_output(network, values, data, hold)
    return trapezoid_sse(data.t, data.y - yhat)


def _nll_rc2_or_none(
    ss: BilinearStateSpace,
    values: Mapping[str, float],
    data: Dataset,
    hold: str,
    P0: np.ndarray,
    Qc: np.ndarray,
    r: float,
    innovations: np.ndarray | None = None,
) -> float | None:
    """The fused 2-state kernel on a state space, or None where it does not apply.

    An RC network's 2-state state space is symmetrizable by construction; the kernel checks
    it and refuses otherwise (None: the caller takes the general path).
    """
    if ss.n_states != 2 or data.y.shape[1] != 1:
        return None
    x0 = initial_state(ss, values, data)
    try:
        return kalman_nll_rc2(
            ss,
            data.t,
            data.m,
            data.u,
            data.y,
            x0,
            P0,
            Qc,
            np.array([[r]]),
            hold,
            innovations,
            data.interval_groups,
        )
    except InputShapeError:
        if rc2_applicable(ss, 1):
            raise
    return None


def fused_path_applies(network: RCNetwork, values: Mapping[str, float], data: Dataset) -> bool:
    """Whether the 2-state likelihood can run straight from parameter values."""
    return (
        len(network.state_names) == 2
        and data.y.shape[1] == 1
        and len(network.outputs) == 1
        and network.conductance_form is not None
        and math.isfinite(data.y[0, 0])
        and not any(f"x0_{n}" in values for n in network.state_names)
    )


def noise_values(ss: BilinearStateSpace, values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray, float]:
    """``(sigma_w, sigma_x0, sigma_v)`` from ``values``, validated."""
    return _noise(ss.state_names, values)


def _noise(s: tuple[str, ...], values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray, float]:
    try:
        sw = np.array([values[f"sigma_w_{n}"] for n in s])
        sx = np.array([values[f"sigma_x0_{n}"] for n in s])
        sv = values["sigma_v"]
    except KeyError as exc:
        raise ParameterError(f"noise parameter {exc.args[0]!r} has no value; fix it or free it") from None
    for nm, v in (("sigma_v", (sv,)), ("sigma_w_*", sw), ("sigma_x0_*", sx)):
        if not all(0.0 <= x < math.inf for x in v):  # also rejects NaN
            raise ParameterError(f"{nm} must be finite and >= 0, got {v}")
    return sw, sx, sv


def filter_arrays(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> tuple:
    """The argument tuple of :func:`~rczone.estimation.kalman.kalman_filter_arrays` for ``values``."""
    ss = network.state_space(network_theta(network, values))
    sw, sx, sv = noise_values(ss, values)
    x0 = initial_state(ss, values, data)
    Phi, G0, G1, Qd, which = stochastic_matrices(ss, data.t, data.m, np.diag(sw**2), hold)
    ny = ss.C.shape[0]
    return (Phi, G0, G1, Qd, which, data.u, data.y, x0, np.diag(sx**2), ss.C, ss.D, sv**2 * np.eye(ny))


def run_filter(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> FilterOutput:
    """Kalman filter (reference implementation) of the stochastic model with the noise in ``values``."""
    return kalman_filter_arrays(*filter_arrays(network, values, data, hold))


def ml_cost(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> float:
    """``J_ML = -log L`` including ``0.5 n log(2 pi)``.

    A 2-state RC model with one output runs the fused compiled kernel (exact closed-form
    discretization + filter, :func:`rczone.kernels.kalman.kalman_nll_rc2`); other models the
    compiled filter loop on :func:`stochastic_matrices`.
    """
    if fused_path_applies(network, values, data):
        # parameter values to likelihood in one compiled call (assembly, initial state, filter)
        res, cap = network.conductance_values(network_theta(network, values))
        sw, sx, sv = _noise(network.state_names, values)
        return kalman_nll_rc2_values(
            network,
            res,
            cap,
            data.t,
            data.m,
            data.u,
            data.y,
            np.diag(sx**2),
            np.diag(sw**2),
            sv**2,
            hold,
            groups=data.interval_groups,
        )
    ss = network.state_space(network_theta(network, values))
    if ss.n_states == 2:
        sw, sx, sv = noise_values(ss, values)
        nll = _nll_rc2_or_none(ss, values, data, hold, np.diag(sx**2), np.diag(sw**2), sv**2)
        if nll is not None:
            return nll
    return kalman_nll_fast(*filter_arrays(network, values, data, hold))


def log_prior_penalty(spec: ParameterSpec, theta: np.ndarray, spread: float = PRIOR_SPREAD) -> float:
    """``sum 0.5 ((log theta - log theta_c) / s)^2`` over free resistances and capacitances."""
    sel = np.array([k in ("resistance", "capacitance") for k in spec.kinds]) & np.isfinite(spec.construction)
    if not sel.any():
        return 0.0
    d = (np.log(theta[sel]) - np.log(spec.construction[sel])) / spread
    return float(0.5 * d @ d)


@dataclass(frozen=True, eq=False)
class Objective:
    """The cost of one estimation problem as a function of the free parameters.

    Calling it never mutates the network, the data or the spec. Invalid parameter
    values (e.g. a non-positive resistance from a non-log parameter) return ``inf``
    instead of raising, so direct search can step back.

    Problems that qualify (:func:`rczone.estimation.compiled.compiled_problem`: 2-state
    networks whose element values are proportional to the free parameters, such as the
    paper's) are evaluated by one compiled call (:func:`rczone.kernels.rc2fit.cost_theta`),
    about 3x faster than going through parameter dictionaries; :meth:`reference_cost` is
    the Python path it is tested against, and the one every other problem takes.

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

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ParameterError(f"method must be one of {METHODS}, got {self.method!r}")
        if not self.prior_spread > 0:
            raise ParameterError(f"prior_spread must be > 0, got {self.prior_spread!r}")
        if not 0 < self.likelihood_weight <= 1:
            raise ParameterError(f"likelihood_weight must be in (0, 1], got {self.likelihood_weight!r}")

    @cached_property
    def compiled(self) -> tuple | None:
        """The compiled form of this problem, or None (see the class notes)."""
        from rczone.estimation.compiled import compiled_problem

        return compiled_problem(self)

    def theta_cost(self, theta: np.ndarray) -> float:
        """Cost at physical values ``theta`` (order of ``spec.names``)."""
        if self.compiled is not None:
            from rczone.kernels.rc2fit import cost_theta

            return float(cost_theta(np.asarray(theta, dtype=np.float64), self.compiled))
        return self.reference_cost(theta)

    def reference_cost(self, theta: np.ndarray) -> float:
        """Cost at physical values ``theta`` through parameter values and the Python path."""
        values = self.spec.values(theta)
        try:
            if self.method == "ls":
                return ls_cost(self.network, values, self.data, self.hold)
            j = ml_cost(self.network, values, self.data, self.hold)
        except (ParameterError, np.linalg.LinAlgError):
            return math.inf
        if self.method == "map":
            j = self.likelihood_weight * j + log_prior_penalty(
                self.spec, np.asarray(theta, dtype=float), self.prior_spread
            )
        return j

    def __call__(self, eta: np.ndarray) -> float:
        """Cost at optimizer values ``eta``."""
        c = self.theta_cost(self.spec.to_theta(eta))
        return c if math.isfinite(c) else math.inf
