"""Kalman-filter likelihood of a continuous-discrete stochastic RC model.

The model (Madsen & Holst 1995) is the bilinear RC network driven by white noise and
observed at discrete, possibly irregular, times:

.. math::

    dx = \\big(A(m)\\,x + B(m)\\,u\\big)\\,dt + \\sigma\\,dW, \\qquad
    y_k = C x_k + D u_k + v_k, \\quad v_k \\sim N(0, R), \\ R = \\mathrm{diag}(r)

The flows ``m`` are known and held constant over each interval, so each interval is
LTI and is discretized exactly (:func:`rczone.simulation.discretize.interval_discretization`),
once per distinct ``(dt, m)``. The measurement noise is independent between outputs
(one ``sigma_v`` per output), so the outputs of a sample are processed one at a time: a
missing output is skipped on its own, and the likelihood is exact [2]_.

There is one filter, :func:`rczone.kernels.kalman.kalman_filter` (compiled, with the
forward sensitivities of the likelihood); :func:`kalman_filter_arrays`, :func:`kalman_nll`
and :func:`kalman_innovations_fast` call it (for a 2-state, 1-output problem its unrolled twin
:func:`rczone.kernels.rc2.filter_rc2`). Its plain NumPy twin lives in the tests
(``tests/oracles.py``), which compare the two, and both with a brute-force joint Gaussian
density. :func:`kalman_nll_rc2` runs the fused 2-state kernel of :mod:`rczone.kernels.rc2`.

References
----------
.. [1] H. Madsen, J. Holst, "Estimation of continuous-time models for the heat dynamics
   of a building", Energy and Buildings 22 (1995) 67-79.
.. [2] J. Durbin, S. J. Koopman, *Time Series Analysis by State Space Methods*, 2nd ed.,
   Oxford University Press, 2012, section 6.4 (univariate treatment of multivariate series).
.. [3] A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman
   Filter*, Cambridge University Press, 1989, section 3.4 (prediction-error
   decomposition of the likelihood).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rczone.errors import InputShapeError
from rczone.kernels.arrays import (
    Dynamics,
    FilterOptions,
    FilterStart,
    FilterTrace,
    Observation,
    Series,
    writable,
)
from rczone.kernels.kalman import STEADY_RTOL, kalman_filter, no_sensitivities, outputs
from rczone.kernels.rc2 import filter_rc2, nll_rc2
from rczone.network.statespace import BilinearStateSpace
from rczone.simulation.discretize import SYMMETRY_RTOL, interval_discretization, symmetrizing_scale
from rczone.simulation.intervals import interval_keys, unique_rows
from rczone.simulation.simulate import HOLDS

_LOG_2PI = float(np.log(2.0 * np.pi))
_NO_GROUPS = np.empty(0, dtype=np.int64)


class SampledDynamics(NamedTuple):
    """The discrete matrices of each distinct interval of a time grid, and which one each step uses."""

    Phi: np.ndarray  #: (K, n, n)
    G0: np.ndarray  #: (K, n, p)
    G1: np.ndarray  #: (K, n, p)
    Qd: np.ndarray  #: (K, n, n)
    which: np.ndarray  #: (N - 1,) int


class FilterProblem(NamedTuple):
    """Everything a Kalman filter over a sampled linear Gaussian model takes, by name.

    ``FilterProblem(*stochastic_matrices(...), u, y, x0, P0, C, D, R)`` builds one.
    """

    Phi: np.ndarray  #: (K, n, n)
    G0: np.ndarray  #: (K, n, p)
    G1: np.ndarray  #: (K, n, p)
    Qd: np.ndarray  #: (K, n, n)
    which: np.ndarray  #: (N - 1,) int, interval ``k`` uses the matrices ``which[k]``
    u: np.ndarray  #: (N, p)
    y: np.ndarray  #: (N, ny), NaN where missing
    x0: np.ndarray  #: (n,) prior mean at the first sample
    P0: np.ndarray  #: (n, n) prior covariance
    C: np.ndarray  #: (ny, n)
    D: np.ndarray  #: (ny, p)
    R: np.ndarray  #: (ny, ny) measurement-noise covariance, K^2; diagonal


def stochastic_matrices(
    ss: BilinearStateSpace, t: np.ndarray, m: np.ndarray, Qc: np.ndarray, hold: str = "zoh"
) -> SampledDynamics:
    """Exact per-interval discretization of the stochastic model (:func:`~rczone.simulation.discretize.interval_discretization`).

    Parameters
    ----------
    ss : BilinearStateSpace
    t : ndarray, shape (N,)
        Sample times, s.
    m : ndarray, shape (N, n_flows)
        Flows held constant from ``t[k]`` to ``t[k+1]``.
    Qc : ndarray, shape (n, n)
        Continuous process-noise intensity, K^2/s.
    hold : {"zoh", "foh"}

    Returns
    -------
    SampledDynamics
    """
    if hold not in HOLDS:
        raise InputShapeError(f"hold must be one of {HOLDS}, got {hold!r}")
    uniq, _, which = unique_rows(interval_keys(t, m))
    Phi, G0, G1, Qd = interval_discretization(ss.A, ss.N, ss.B, ss.M, ss.capacities, uniq, hold, Qc)
    return SampledDynamics(Phi, G0, G1, Qd, which.reshape(-1))


def input_drive(G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Deterministic input contribution ``G0[w] u[k] + G1[w] u[k+1]`` per interval, shape (N-1, n)."""
    out = np.empty((u.shape[0] - 1, G0.shape[1]), np.result_type(G0, G1, u))
    for w in np.unique(which):
        sel = which == w
        out[sel] = u[:-1][sel] @ G0[w].T + u[1:][sel] @ G1[w].T
    return out


def measurement_variances(R: np.ndarray) -> np.ndarray:
    """The diagonal of a measurement-noise covariance, which must be diagonal (one variance per output)."""
    R = np.asarray(R)
    if R.ndim != 2 or R.shape[0] != R.shape[1]:
        raise InputShapeError(f"R must be a square (ny, ny) matrix, got shape {R.shape}")
    d = np.diagonal(R)
    if np.count_nonzero(R) != np.count_nonzero(d):
        raise InputShapeError(
            "R must be diagonal: the measurement noise of each output is independent (one sigma_v per"
            " output); correlated measurement noise is not supported"
        )
    return np.array(d)


@dataclass(frozen=True, eq=False)
class FilterOutput:
    """Everything the filter computes, time-first.

    Attributes
    ----------
    nll : float
        ``-log L`` including ``0.5 n log(2 pi)`` (n = number of observed scalars).
    innovations : ndarray, shape (N, ny)
        ``y_k - C x_k|k-1 - D u_k``; NaN where ``y`` is missing.
    S : ndarray, shape (N, ny, ny)
        Innovation covariances ``C P_k|k-1 C' + R`` (also where ``y`` is missing).
    x_pred, x_filt : ndarray, shape (N, n)
        One-step predicted and filtered states.
    P_pred : ndarray, shape (N, n, n)
    n_obs : int
        Number of observed scalars.
    P_filt : ndarray, shape (N, n, n)
        Filtered covariances (what :mod:`rczone.estimation.smoother` needs).
    """

    nll: float
    innovations: np.ndarray
    S: np.ndarray
    x_pred: np.ndarray
    x_filt: np.ndarray
    P_pred: np.ndarray
    n_obs: int
    P_filt: np.ndarray


# --------------------------------------------------------------------------- the compiled filter


def _two_state(problem: FilterProblem) -> bool:
    """Whether ``problem`` has two states and one output: :func:`rczone.kernels.rc2.filter_rc2` runs it."""
    return problem.Phi.shape[1] == 2 and problem.y.shape[1] == 1


def _compiled_rc2(problem: FilterProblem) -> tuple[float, int, FilterTrace]:
    """Run :func:`rczone.kernels.rc2.filter_rc2` on a 2-state, 1-output ``problem``; as :func:`_compiled`."""
    f = writable  # one specialization whatever the arrays' origin
    N, p = problem.y.shape[0], problem.u.shape[1]
    trace = FilterTrace(
        np.full((N, 1), np.nan),
        np.zeros((0, 1, 0)),
        np.empty((N, 2)),
        np.empty((N, 2)),
        np.empty((N, 2, 2)),
        np.empty((N, 1, 1)),
        np.empty((N, 2, 2)),
        np.empty((0, 0, 2)),
    )
    nll, n_obs = filter_rc2(
        Dynamics(*(f(a) for a in (problem.Phi, problem.G0, problem.G1, problem.Qd))),
        Observation(
            f(problem.C),
            f(problem.D),
            f(measurement_variances(problem.R)),
            np.empty((1, 0, 2)),
            np.empty((1, 0, p)),
            np.empty((1, 0)),
        ),
        FilterStart(f(problem.x0), f(problem.P0), np.empty((0, 2)), np.empty((0, 2, 2))),
        Series(f(problem.u), f(problem.y), f(problem.which, np.int64)),
        bool(np.any(problem.G1)),
        trace,
    )
    if n_obs < 0:
        raise np.linalg.LinAlgError("an innovation variance is not positive: the noise model is invalid")
    return float(nll + 0.5 * n_obs * _LOG_2PI), n_obs, trace


def _compiled(problem: FilterProblem, *, keep: bool, general: bool = False) -> tuple[float, int, FilterTrace]:
    """Run :func:`rczone.kernels.kalman.kalman_filter` on ``problem``.

    With ``keep`` the intermediate results are returned too (the trace of the kernel). A 2-state,
    1-output problem runs :func:`rczone.kernels.rc2.filter_rc2` instead (the same filter unrolled,
    no steady state: equal within the general filter's steady-state tolerance), unless ``general``.
    """
    if not general and _two_state(problem):
        return _compiled_rc2(problem)
    Phi, Gamma0, Gamma1, Qd, which = problem.Phi, problem.G0, problem.G1, problem.Qd, problem.which
    u, y, x0, P0, C, D, R = problem.u, problem.y, problem.x0, problem.P0, problem.C, problem.D, problem.R
    f = writable  # read-only arrays (a Dataset's, np.diag's views) would compile a second specialization
    r = f(measurement_variances(R))
    N, ny = y.shape
    n, p = x0.shape[0], u.shape[1]
    outs = outputs(N, n, ny, 0, False, keep)
    nll, n_obs, _, _ = kalman_filter(
        Dynamics(*(f(a) for a in (Phi, Gamma0, Gamma1, Qd))),
        no_sensitivities(Phi.shape[0], n, p),
        Observation(
            f(C),
            f(D),
            r,
            np.empty((ny, 0, n)),
            np.empty((ny, 0, p)),
            np.empty((ny, 0)),
        ),
        FilterStart(f(x0), f(P0), np.empty((0, n)), np.empty((0, n, n))),
        Series(f(u), f(y), f(which, np.int64)),
        FilterOptions(bool(np.any(Gamma1)), False, STEADY_RTOL),
        outs,
    )
    if n_obs < 0:
        raise np.linalg.LinAlgError("an innovation variance is not positive: the noise model is invalid")
    return float(nll + 0.5 * n_obs * _LOG_2PI), n_obs, outs


def kalman_filter_arrays(problem: FilterProblem, *, general: bool = False) -> FilterOutput:
    """The compiled filter over ``problem``, with every intermediate result.

    ``x0, P0`` are the prior of the state at the first sample (the first measurement is used
    in the likelihood). The observed outputs of each sample are processed one at a time;
    missing ones (NaN in ``y``) are skipped. A 2-state, 1-output problem runs the unrolled
    2-state filter (:func:`rczone.kernels.rc2.filter_rc2`; a small kernel, so a first run that
    needs a 2-state model's bands does not compile the general one), unless ``general``.
    """
    nll, n_obs, trace = _compiled(problem, keep=True, general=general)
    return FilterOutput(
        nll=nll,
        innovations=trace.e,
        S=trace.S,
        x_pred=trace.xp,
        x_filt=trace.xf,
        P_pred=trace.Pp,
        n_obs=n_obs,
        P_filt=trace.Pf,
    )


def kalman_nll(problem: FilterProblem) -> float:
    """``-log L`` (including ``0.5 n log 2 pi``) by the compiled filter (:func:`kalman_filter_arrays`)."""
    return _compiled(problem, keep=False)[0]


def kalman_innovations_fast(problem: FilterProblem) -> np.ndarray:
    """One-step-ahead prediction errors, shape (N, ny), NaN where missing (compiled filter)."""
    return kalman_filter_arrays(problem).innovations


# --------------------------------------------------------------------------- the fused 2-state kernel


def rc2_applicable(ss: BilinearStateSpace, n_outputs: int) -> bool:
    """Whether :func:`kalman_nll_rc2` handles this model: 2 states, one output, RC-symmetrizable."""
    if ss.n_states != 2 or n_outputs != 1:
        return False
    c = ss.capacities
    if c.shape == (2,) and c[0] > 0 and c[1] > 0:
        # quick scalar form of symmetrizing_scale for 2 states: c0 A01 == c1 A10, likewise for N
        mats = [ss.A, *ss.N]
        if all(
            abs(c[0] * a[0, 1] - c[1] * a[1, 0])
            <= SYMMETRY_RTOL * max(abs(c[0] * a[0, 1]), abs(c[1] * a[1, 0]))
            for a in mats
        ) and all(math.isfinite(x) for a in mats for x in a.flat):
            return True
    return symmetrizing_scale(ss.A, ss.N, ss.capacities) is not None


def kalman_nll_rc2(
    ss: BilinearStateSpace,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    Qc: np.ndarray,
    R: np.ndarray,
    hold: str = "zoh",
    innovations: np.ndarray | None = None,
    groups: np.ndarray | None = None,
) -> float:
    """``-log L`` (including ``0.5 n log 2 pi``) of a 2-state RC model with one output, fused.

    Equal to ``kalman_nll(FilterProblem(*stochastic_matrices(ss, t, m, Qc, hold), u, y, x0, P0, ss.C, ss.D, R))``,
    computed in one compiled pass (:func:`rczone.kernels.rc2.nll_rc2`).

    Parameters
    ----------
    ss : BilinearStateSpace
        Two states, symmetrizable (see :func:`rc2_applicable`).
    t : ndarray, shape (N,)
        Sample times, s, strictly increasing.
    m : ndarray, shape (N, n_flows)
    u : ndarray, shape (N, p)
    y : ndarray, shape (N, 1)
        Measurements; NaN where missing.
    x0 : ndarray, shape (2,)
    P0 : ndarray, shape (2, 2)
    Qc : ndarray, shape (2, 2)
        Process-noise intensity, K^2/s; diagonal.
    R : ndarray, shape (1, 1)
        Measurement-noise variance, K^2.
    hold : {"zoh", "foh"}
    innovations : ndarray, shape (N,), optional
        Filled with the one-step prediction errors (missing samples untouched).
    groups : ndarray, optional
        :func:`rczone.simulation.intervals.interval_groups` of ``(t, m)``: discretize each
        distinct interval once.

    Returns
    -------
    float
    """
    if hold not in HOLDS:
        raise InputShapeError(f"hold must be one of {HOLDS}, got {hold!r}")
    if ss.n_states != 2:
        raise InputShapeError(
            f"kalman_nll_rc2 needs a 2-state RC model, got {ss.n_states} states;"
            " use rczone.estimation.kalman.kalman_nll instead"
        )
    y = np.asarray(y, dtype=np.float64)
    if y.ndim != 2 or y.shape[1] != 1 or ss.C.shape[0] != 1:
        raise InputShapeError(f"kalman_nll_rc2 needs one output, y of shape (N, 1); got {y.shape}")
    if innovations is not None and (
        innovations.shape != (y.shape[0],)
        or innovations.dtype != np.float64
        or not innovations.flags.c_contiguous
    ):
        raise InputShapeError(f"innovations must be a contiguous float64 array of shape ({y.shape[0]},)")
    Qc = np.asarray(Qc, dtype=np.float64)
    if Qc.shape != (2, 2) or Qc[0, 1] != 0.0 or Qc[1, 0] != 0.0:
        raise InputShapeError(f"Qc must be a diagonal (2, 2) matrix (process noise per state), got {Qc!r}")
    f = np.ascontiguousarray
    # the state space's own arrays are contiguous float64 already; the data are made so (one
    # compiled specialization serves every caller)
    nll, n_obs = nll_rc2(
        ss.A,
        ss.N,
        ss.B,
        ss.M,
        ss.capacities,
        f(t, dtype=np.float64),
        f(m, dtype=np.float64),
        f(u, dtype=np.float64),
        f(y[:, 0]),
        f(x0, dtype=np.float64),
        f(P0, dtype=np.float64),
        ss.C[0],
        ss.D[0],
        float(R[0, 0]),
        np.array([Qc[0, 0], Qc[1, 1]]),
        hold == "foh",
        SYMMETRY_RTOL,
        STEADY_RTOL,
        np.empty(0) if innovations is None else innovations,
        _NO_GROUPS if groups is None else groups,
    )
    if n_obs == -2:
        raise np.linalg.LinAlgError("an innovation variance is not positive: the noise model is invalid")
    if n_obs < 0:
        raise InputShapeError(
            "kalman_nll_rc2 needs an RC model (diag(capacities) A and diag(capacities) N symmetric);"
            " use rczone.estimation.kalman.kalman_nll for other state spaces"
        )
    return float(nll + 0.5 * n_obs * _LOG_2PI)
