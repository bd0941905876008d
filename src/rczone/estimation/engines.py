"""How an identification cost is computed: the engines, and what they share.

Every cost (:mod:`rczone.estimation.costs`) is computed by one of three engines, chosen by
declared rules (:func:`choose_engine`), never by trying one and catching its failure:

``"rc2-fused"``
    Two states, one output, and the problem packs into arrays
    (:func:`rczone.estimation.compiled.compiled_problem`): the value comes from the fused
    2-state kernel (:mod:`rczone.kernels.rc2`, discretization inside the filter loop), the
    gradient from the ``"compiled"`` engine.
``"compiled"``
    The problem packs into arrays: parameter values to cost and gradient in one compiled call
    (:func:`rczone.kernels.problem.value_general`,
    :func:`rczone.kernels.problem.value_and_gradient`).
``"general"``
    Anything else (massless nodes, ties that are not proportional, ...): the state space and
    its exact parameter derivatives are built in Python (:meth:`RCNetwork.state_space`,
    :meth:`RCNetwork.state_space_derivatives`), then the compiled discretization and filter run
    on them (:func:`general_cost`).
Within the ``"compiled"`` and ``"general"`` engines the likelihood's filter is chosen by a declared
rule too (:func:`rczone.kernels.kalman.modal_pays`, from the number of states and how often the
intervals change their matrices): the one filter in modal coordinates for values where it pays,
in the original coordinates otherwise and for every gradient. The engine is recorded as :attr:`Objective.engine
<rczone.estimation.costs.Objective.engine>` and in every fit result (``FitResult.engine``, the
``engine`` of its ``to_dict()``); the filter follows from the engine and the data.
The tests compare every engine with a plain NumPy computation of the same cost
(``tests/oracles.py``: the NumPy spectral discretization, the NumPy twin of the filter, a Python loop for
the simulation).

All engines use the same model: the initial state of :func:`initial_state`, the noise of
:func:`noise_values`, the trapezoid rule of :func:`trapezoid_sse`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.kalman import (
    FilterOutput,
    FilterProblem,
    kalman_filter_arrays,
    stochastic_matrices,
)
from rczone.kernels.arrays import (
    Assembled,
    AssembledDerivatives,
    Discretization,
    FilterOptions,
    FilterStart,
    Observation,
    Series,
    Start,
    dynamics_derivatives,
    dynamics_model,
    writable,
)
from rczone.kernels.discretize import (
    derivatives_kernel,
    matrices_kernel,
    modal_matrices,
)
from rczone.kernels.kalman import (
    STEADY_RTOL,
    kalman_filter,
    modal_pays,
    no_sensitivities,
    outputs,
)
from rczone.kernels.problem import trapezoid
from rczone.network import BilinearStateSpace, RCNetwork
from rczone.network.stochastic import (
    MEASUREMENT_NOISE,
    initial_spread_name,
    initial_spread_names,
    initial_state_names,
    measurement_noise_names,
    parameter_name,
    process_noise_name,
    process_noise_names,
)
from rczone.simulation.discretize import symmetrizing_scale
from rczone.simulation.simulate import propagate, transition_matrices

ENGINES = ("rc2-fused", "compiled", "general")

_LOG_2PI = math.log(2.0 * math.pi)


def choose_engine(n_states: int, n_outputs: int, packs: bool) -> str:
    """The engine of a problem by the declared rules (see the module notes).

    Parameters
    ----------
    n_states, n_outputs : int
    packs : bool
        Whether :func:`rczone.estimation.compiled.compiled_problem` packs the problem.
    """
    if not packs:
        return "general"
    return "rc2-fused" if n_states == 2 and n_outputs == 1 else "compiled"


def gradient_engine(engine: str) -> str:
    """The engine that computes gradients for a problem whose values come from ``engine``."""
    return "compiled" if engine == "rc2-fused" else engine


# ----------------------------------------------------------------------------- shared model


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

    Computed by :func:`rczone.kernels.problem.initial_state`, the compiled engine's own start.

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

    Raises
    ------
    numpy.linalg.LinAlgError
        The steady state of the unmeasured states is singular.
    """
    n = ss.n_states
    given = np.zeros(n, dtype=bool)
    return _start(ss, StartData(u0, m0, y0), given, np.zeros(n), _no_directions(ss, 0))[0]


def initial_state(ss: BilinearStateSpace, values: Mapping[str, float], data: Dataset) -> np.ndarray:
    """Initial state from ``x0_<state>`` values where given, else :func:`auto_initial_state`."""
    names = initial_state_names(ss.state_names)
    given = np.array([nm in values for nm in names], dtype=bool)
    x0 = np.array([float(values[nm]) if g else 0.0 for nm, g in zip(names, given, strict=True)])
    return _start(ss, StartData(data.u[0], data.m[0], data.y[0]), given, x0, _no_directions(ss, 0))[0]


class StartData(NamedTuple):
    """The first sample of a data set: what the initial state is derived from."""

    u0: np.ndarray  #: (p,)
    m0: np.ndarray  #: (n_flows,)
    y0: np.ndarray  #: (ny,), NaN where not measured


def _no_directions(ss: BilinearStateSpace, q: int) -> AssembledDerivatives:
    n, p, nf = ss.n_states, ss.n_inputs, ss.n_flows
    return dynamics_derivatives(
        np.zeros((q, n, n)),
        np.zeros((q, nf, n, n)),
        np.zeros((q, n, p)),
        np.zeros((q, nf, n, p)),
        np.zeros((q, n)),
    )


def _start(
    ss: BilinearStateSpace,
    first: StartData,
    given: np.ndarray,
    x0: np.ndarray,
    directions: AssembledDerivatives,
    given_direction: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The initial state and its derivatives (q, n) by :func:`rczone.kernels.problem.initial_state`.

    ``given`` (bool, n) marks the states whose value ``x0`` is given; ``given_direction`` (int,
    n) the direction along which a given state moves with unit derivative (-1: none).
    """
    from rczone.kernels.problem import initial_state as start_kernel

    direct = measured_states(ss)
    states = np.array(sorted(direct), dtype=np.int64)
    first_y = np.asarray(first.y0, dtype=float)[[direct[i] for i in states.tolist()]]
    q = directions.dA0.shape[0]
    mod = dynamics_model(ss.A, ss.N, ss.B, ss.M, np.zeros(ss.n_states))
    given = writable(given, bool)
    mod.x0[given] = np.asarray(x0, dtype=float)[given]
    dx0 = np.zeros((q, ss.n_states))
    if given_direction is not None:
        for i, d in enumerate(np.asarray(given_direction).tolist()):
            if given[i] and 0 <= d < q:
                dx0[d, i] = 1.0
    der = directions._replace(dx0=dx0)
    # writable copies, as the compiled engine passes: one specialization
    start = Start(np.array(first.m0, dtype=float), np.array(first.u0, dtype=float), first_y, states, given)
    if not start_kernel(mod, der, start):
        raise np.linalg.LinAlgError("the steady state that starts the unmeasured states is singular")
    return mod.x0, der.dx0


def network_theta(network: RCNetwork, values: Mapping[str, float]) -> dict[str, float]:
    """The network's base parameter values out of a full value mapping."""
    return {n: values[n] for n in network.free_parameter_names if n in values}


def noise_values(
    ss: BilinearStateSpace, values: Mapping[str, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(sigma_w, sigma_x0, sigma_v)`` from ``values``: per state, per state, per output; validated."""
    try:
        sw = np.array([values[n] for n in process_noise_names(ss.state_names)], dtype=float)
        sx = np.array([values[n] for n in initial_spread_names(ss.state_names)], dtype=float)
        sv = np.array([values[n] for n in measurement_noise_names(ss.output_names)], dtype=float)
    except KeyError as exc:
        raise ParameterError(f"noise parameter {exc.args[0]!r} has no value; fix it or free it") from None
    labels = (parameter_name(MEASUREMENT_NOISE, None), process_noise_name("*"), initial_spread_name("*"))
    for nm, v in zip(labels, (sv, sw, sx), strict=True):
        if not all(0.0 <= x < math.inf for x in v):  # also rejects NaN
            raise ParameterError(f"{nm} must be finite and >= 0, got {v}")
    return sw, sx, sv


def trapezoid_sse(t: np.ndarray, e: np.ndarray) -> float:
    """``int e(t)^2 dt`` by the trapezoid rule, skipping intervals with a missing end.

    The compiled engine's own rule (:func:`rczone.kernels.problem.trapezoid`).

    Parameters
    ----------
    t : ndarray, shape (N,)
    e : ndarray, shape (N, ny)
        Errors; NaN where the measurement is missing. Outputs are summed.
    """
    N, ny = e.shape
    f = writable  # read-only arrays would compile the kernels a second time
    return float(trapezoid(f(t), f(e), np.empty((N, ny, 0)), np.zeros(0), np.zeros(0)))


def simulate_output(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop states and outputs, shapes (N, n) and (N, ny)."""
    ss = network.state_space(network_theta(network, values))
    x0 = initial_state(ss, values, data)
    Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, hold)
    x = propagate(Phi, G0, G1, which, data.u, x0)
    return x, x @ ss.C.T + data.u @ ss.D.T


def filter_arrays(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> FilterProblem:
    """The filter problem of ``values`` on ``data`` (:func:`rczone.estimation.kalman.stochastic_matrices`), for :mod:`rczone.estimation.kalman`."""
    ss = network.state_space(network_theta(network, values))
    sw, sx, sv = noise_values(ss, values)
    x0 = initial_state(ss, values, data)
    dynamics = stochastic_matrices(ss, data.t, data.m, np.diag(sw**2 + ss.diffusion), hold)
    return FilterProblem(*dynamics, data.u, data.y, x0, np.diag(sx**2), ss.C, ss.D, np.diag(sv**2))


def run_filter(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> FilterOutput:
    """Kalman filter of the stochastic model with the noise in ``values``, every intermediate result kept."""
    return kalman_filter_arrays(filter_arrays(network, values, data, hold))


# ----------------------------------------------------------------------------- the general engine


def _initial_state_derivatives(
    ss: BilinearStateSpace,
    values: Mapping[str, float],
    data: Dataset,
    wrt: Sequence[str],
    directions: AssembledDerivatives,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`initial_state` and its derivatives (len(wrt), n) along ``directions`` of the state space."""
    names = initial_state_names(ss.state_names)
    given = np.array([nm in values for nm in names], dtype=bool)
    x0 = np.array([float(values[nm]) if g else 0.0 for nm, g in zip(names, given, strict=True)])
    moves = np.array(
        [list(wrt).index(nm) if g and nm in wrt else -1 for nm, g in zip(names, given, strict=True)]
    )
    return _start(ss, StartData(data.u[0], data.m[0], data.y[0]), given, x0, directions, moves)


def general_cost(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    hold: str,
    method: str,
    wrt: Sequence[str] = (),
) -> tuple[float, np.ndarray, np.ndarray]:
    """``J_LS`` or ``-log L`` by the general engine, its gradient and curvature in the parameters ``wrt`` (theta units).

    Parameters
    ----------
    network, values, data, hold
        As :func:`rczone.estimation.costs.ml_cost`.
    method : {"ls", "ml"}
    wrt : sequence of str
        Base network parameters, ``sigma_v[_<output>]``, ``sigma_w_<state>``,
        ``sigma_x0_<state>`` or ``x0_<state>`` (given in ``values``).

    Returns
    -------
    cost : float
    gradient : ndarray, shape (len(wrt),)
    curvature : ndarray, shape (len(wrt),)
        Diagonal of the Fisher information (``-log L``) or of the Gauss-Newton Hessian (``J_LS``).

    Raises
    ------
    ParameterError
        For invalid parameter values.
    numpy.linalg.LinAlgError
        For a singular steady state or a non-positive innovation variance.
    """
    asm = assemble(network, values, data, hold, method, wrt)
    ss, mod, der, how = asm.ss, asm.mod, asm.der, asm.how
    n, p, ny = ss.n_states, ss.n_inputs, ss.C.shape[0]
    q, ls, foh, keys = len(tuple(wrt)), method == "ls", hold == "foh", how.keys
    which = writable(data.intervals[1], np.int64)
    scale = how.scale if how.scale.shape[0] else None
    if q:
        mats, dmats = derivatives_kernel(scale is not None)(mod, der, how)
    else:
        if scale is not None and not ls and modal_pays(which, n):
            mats, basis = modal_matrices(mod, how)
            nll, n_obs, _, _ = kalman_filter(
                mats,
                no_sensitivities(keys.shape[0], n, p),
                asm.observation,
                asm.prior,
                Series(np.require(data.u, np.float64, "CW"), np.require(data.y, np.float64, "CW"), which),
                FilterOptions(foh, False, STEADY_RTOL),
                outputs(data.n_samples, n, ny, 0, False, False),
                basis,
            )
            if n_obs < 0:
                raise np.linalg.LinAlgError(
                    "an innovation variance is not positive: the noise model is invalid"
                )
            return float(nll + 0.5 * n_obs * _LOG_2PI), np.zeros(0), np.zeros(0)
        mats = matrices_kernel(n, scale is not None)(mod, how)
        dmats = no_sensitivities(keys.shape[0], n, p)
    # writable as the packed problem's (a Dataset's arrays are read-only): one compiled specialization
    y = np.require(data.y, np.float64, "CW")
    outs = outputs(data.n_samples, n, ny, q, ls, False)
    nll, n_obs, g, fim = kalman_filter(
        mats,
        dmats,
        asm.observation,
        asm.prior,
        Series(np.require(data.u, np.float64, "CW"), y, which),
        FilterOptions(foh, ls, STEADY_RTOL),
        outs,
    )
    if n_obs < 0:
        raise np.linalg.LinAlgError("an innovation variance is not positive: the noise model is invalid")
    if not ls:
        return float(nll + 0.5 * n_obs * _LOG_2PI), g, fim
    grad, curv = np.zeros(q), np.zeros(q)
    sse = trapezoid(data.t, outs.e, outs.de, grad, curv)
    return float(sse), grad, curv


class Assembly(NamedTuple):
    """A filter problem's continuous matrices, their derivatives and how they are discretized (:func:`assemble`)."""

    ss: BilinearStateSpace
    mod: Assembled  #: the continuous matrices and process noise
    der: AssembledDerivatives
    how: Discretization
    observation: Observation
    prior: FilterStart


def assemble(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    hold: str,
    method: str,
    wrt: Sequence[str] = (),
) -> Assembly:
    """The arrays :func:`general_cost` hands the compiled filter, with their derivatives along ``wrt``.

    Parameters
    ----------
    network, values, data, hold
        As :func:`general_cost`.
    method : {"ls", "ml"}
        ``"ls"``: no noise (unit measurement variances, no process noise).
    wrt : sequence of str
        As :func:`general_cost`.
    """
    theta = network_theta(network, values)
    ss = network.state_space(theta)
    n, p, ny, nf = ss.n_states, ss.n_inputs, ss.C.shape[0], ss.n_flows
    wrt = tuple(wrt)
    q = len(wrt)
    net_wrt = [w for w in wrt if w in network.parameters]
    ders = dict(zip(net_wrt, network.state_space_derivatives(theta, net_wrt, log=False))) if net_wrt else {}
    derivs = [ders.get(w) for w in wrt]
    dA0, dN = np.zeros((q, n, n)), np.zeros((q, nf, n, n))
    dB0, dM = np.zeros((q, n, p)), np.zeros((q, nf, n, p))
    dC, dD = np.zeros((ny, q, n)), np.zeros((ny, q, p))
    for k, d in enumerate(derivs):
        if d is not None:
            dA0[k], dN[k], dB0[k], dM[k] = d.dA, d.dN, d.dB, d.dM
            dC[:, k], dD[:, k] = d.dC, d.dD
    ls = method == "ls"
    if ls:
        sw, sx, r = np.zeros(n), np.zeros(n), np.ones(ny)
    else:
        sw, sx, sv = noise_values(ss, values)
        r = sv**2
    dqc, dP0, dr = np.zeros((q, n)), np.zeros((q, n, n)), np.zeros((ny, q))
    if not ls:
        sv_names = measurement_noise_names(ss.output_names)
        for k, w in enumerate(wrt):
            for i, s in enumerate(ss.state_names):
                if w == process_noise_name(s):
                    dqc[k, i] = 2.0 * sw[i]
                elif w == initial_spread_name(s):
                    dP0[k, i, i] = 2.0 * sx[i]
            if w in sv_names:
                j = sv_names.index(w)
                dr[j, k] = 2.0 * sv[j]
        for k, d in enumerate(derivs):  # the disturbances' diffusion follows their hyper-parameters
            if d is not None and d.dQ is not None:
                dqc[k] += d.dQ
    qc = sw**2 + (0.0 if ls else ss.diffusion)
    mod = dynamics_model(ss.A, ss.N, ss.B, ss.M, qc)
    der = dynamics_derivatives(dA0, dN, dB0, dM, dqc)
    x0, dx0 = _initial_state_derivatives(ss, values, data, wrt, der)
    f = writable  # read-only arrays (a Dataset's) would compile the kernels a second time
    keys = f(data.intervals[0])
    foh = hold == "foh"
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    how = Discretization(keys, np.empty(0) if scale is None else scale, foh, not ls)
    return Assembly(
        ss,
        mod,
        der,
        how,
        Observation(f(ss.C), f(ss.D), f(r), dC, dD, dr),
        FilterStart(x0, np.diag(sx**2), dx0, dP0),
    )
