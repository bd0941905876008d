"""The named arrays that cross the boundaries of the compiled kernels.

Every kernel of :mod:`rczone.kernels` takes and returns its arrays grouped and named by these
tuples, never as long positional tuples. numba compiles a ``NamedTuple`` as the plain tuple it is
[1]_, so the names cost nothing at run time; on the Python side ``_replace`` edits one field
without counting slots.

Shapes use ``N`` samples, ``K`` distinct sampling intervals, ``n`` states, ``p`` inputs, ``ny``
outputs and ``q`` parameter directions (``q = 0``: no derivatives).

References
----------
.. [1] numba documentation, "Supported Python features: tuple, namedtuple" (named tuples are
   compiled as heterogeneous or homogeneous tuples with attribute access).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rczone.kernels.cache import tolerate_stale_indexes

# an index written by an older rczone may name a class renamed since: a miss, not an error
tolerate_stale_indexes()


class Dynamics(NamedTuple):
    """Exact discrete matrices of each distinct sampling interval.

    ``x[k+1] = Phi x[k] + G0 u[k] + G1 (u[k+1] - u[k]) + w``, ``cov(w) = Qd`` (``G1 = 0`` for a
    zero-order hold).
    """

    Phi: np.ndarray  #: (K, n, n)
    G0: np.ndarray  #: (K, n, p)
    G1: np.ndarray  #: (K, n, p)
    Qd: np.ndarray  #: (K, n, n)


class DynamicsDerivatives(NamedTuple):
    """Derivatives of :class:`Dynamics` along ``q`` parameter directions."""

    dPhi: np.ndarray  #: (K, q, n, n)
    dG0: np.ndarray  #: (K, q, n, p)
    dG1: np.ndarray  #: (K, q, n, p)
    dQd: np.ndarray  #: (K, q, n, n)


class ModalDynamics(NamedTuple):
    """:class:`Dynamics` of an RC model in the modal coordinates of each interval.

    ``Phi = T diag(e) T^-1`` with ``T = diag(scale)^-1 V``; ``G0 = T H0``, ``G1 = T H1``,
    ``Qd = T Qm T'``.
    """

    V: np.ndarray  #: (K, n, n) orthogonal eigenvectors of the symmetrized state matrix
    e: np.ndarray  #: (K, n) ``exp(lambda h)``
    H0: np.ndarray  #: (K, n, p)
    H1: np.ndarray  #: (K, n, p)
    Qm: np.ndarray  #: (K, n, n)


class ModalBasis(NamedTuple):
    """The coordinates of each interval in which an RC model's transition matrix is diagonal.

    On interval ``w`` a filter given this basis carries ``xi = V[w]' diag(scale) x`` (so
    ``x = diag(scale)^-1 V[w] xi``, ``V[w]`` orthogonal) and :class:`Dynamics` in these
    coordinates: ``Phi[w] = diag(e^{lambda h})``, ``G0 = H0``, ``G1 = H1``, ``Qd = Qm`` of
    :class:`ModalDynamics`.
    """

    V: np.ndarray  #: (K, n, n) orthogonal eigenvectors of each interval's symmetrized state matrix
    scale: np.ndarray  #: (n,) ``sqrt(capacities)``


class Observation(NamedTuple):
    """``y = C x + D u + v``, ``cov(v) = diag(r)``, and the derivatives along ``q`` directions."""

    C: np.ndarray  #: (ny, n)
    D: np.ndarray  #: (ny, p)
    r: np.ndarray  #: (ny,) measurement variances, K^2
    dC: np.ndarray  #: (ny, q, n)
    dD: np.ndarray  #: (ny, q, p)
    dr: np.ndarray  #: (ny, q)


class StateMoments(NamedTuple):
    """Mean ``x`` and covariance ``P`` of the state: of one sample, or per sample (time first).

    The observer's estimate (:mod:`rczone.control.observer`) and the smoother's passes
    (:mod:`rczone.kernels.smoother`) both carry one.
    """

    x: np.ndarray  #: (n,) or (N, n)
    P: np.ndarray  #: (n, n) or (N, n, n)


class Moments2(NamedTuple):
    """Mean and covariance of a 2-state filter as scalars: what the unrolled 2-state kernels carry
    from one step to the next (:func:`rczone.kernels.rc2.predict_rc2`, :func:`~rczone.kernels.rc2.correct_rc2`)."""

    x0: float
    x1: float
    p00: float
    p01: float  #: the covariance's off-diagonal (kept symmetric)
    p11: float


class FilterStart(NamedTuple):
    """The state's mean and covariance at the first sample, and their derivatives."""

    x0: np.ndarray  #: (n,)
    P0: np.ndarray  #: (n, n)
    dx0: np.ndarray  #: (q, n)
    dP0: np.ndarray  #: (q, n, n)


class Series(NamedTuple):
    """The data a filter runs over: inputs, outputs (NaN where missing), and the interval of each step."""

    u: np.ndarray  #: (N, p)
    y: np.ndarray  #: (N, ny)
    which: np.ndarray  #: (N - 1,) int64, interval ``k`` uses the matrices ``which[k]``


class FilterOptions(NamedTuple):
    """How the filter runs."""

    foh: bool  #: first-order hold of the inputs between samples (else zero-order)
    open_loop: bool  #: no measurement updates: output errors of a simulation (least squares)
    steady_rtol: float  #: relative tolerance at which the covariance counts as stationary (0: never)


class FilterTrace(NamedTuple):
    """What a filter run may keep per sample; an array whose first axis is not ``N`` is not filled."""

    e: np.ndarray  #: (N, ny) innovations (output errors in open loop)
    de: np.ndarray  #: (N, ny, q) their derivatives (open loop only)
    xp: np.ndarray  #: (N, n) predicted states
    xf: np.ndarray  #: (N, n) filtered states
    Pp: np.ndarray  #: (N, n, n) predicted covariances
    S: np.ndarray  #: (N, ny, ny) innovation covariances ``C P C' + R``
    Pf: np.ndarray  #: (N, n, n) filtered covariances (what the smoother's backward pass needs)
    dxf: (
        np.ndarray
    )  #: (N, q, n) derivatives of the filtered states (not in open loop; the k-step criterion's)


class FilterValue(NamedTuple):
    """What a filter run returns."""

    nll: float  #: ``sum 0.5 (log s + e^2/s)`` over the observed outputs; NaN for an invalid model
    n_obs: int  #: observed scalars; -1 for an invalid model
    grad: np.ndarray  #: (q,) derivatives of ``nll``
    fim: np.ndarray  #: (q,) diagonal of the Fisher information


class Discretization(NamedTuple):
    """How the intervals of a bilinear model are discretized (:func:`rczone.kernels.discretize.interval_matrices`)."""

    keys: np.ndarray  #: (K, 1 + nf) ``(dt, m_1, ..., m_nf)`` of each distinct interval
    scale: (
        np.ndarray
    )  #: (n,) ``sqrt(capacities)`` of an RC network (spectral formulas), or (0,) (matrix exponentials)
    foh: bool  #: first-order hold of the inputs (else zero-order)
    noise: bool  #: compute ``Qd`` and its derivatives (zero otherwise)


class Eigen2(NamedTuple):
    """The eigenvalues ``lam0 <= lam1`` of a symmetric 2-by-2 matrix and its orthogonal eigenvectors ``V``, by rows."""

    lam0: float
    lam1: float
    v00: float
    v01: float
    v10: float
    v11: float


class Interval(NamedTuple):
    """The continuous model over one interval: ``dx = (A x + B u) dt + dw``, ``cov(dw) = diag(qc) dt``."""

    A: np.ndarray  #: (n, n)
    B: np.ndarray  #: (n, p)
    qc: np.ndarray  #: (n,) process-noise intensities
    h: float  #: length of the interval, s


class IntervalDirections(NamedTuple):
    """Derivatives of an :class:`Interval`'s matrices along ``q`` parameter directions."""

    dA: np.ndarray  #: (q, n, n)
    dB: np.ndarray  #: (q, n, p)
    dqc: np.ndarray  #: (q, n)


class Rc2Model(NamedTuple):
    """A 2-state RC model as scalars: ``A = [[a, a01], [a10, d]]`` and ``s = sqrt(capacities)``, ``is = 1/s``."""

    a: float
    a01: float
    a10: float
    d: float
    s0: float
    s1: float
    is0: float
    is1: float


class Rc2Matrices(NamedTuple):
    """The exact discrete matrices of a 2-state RC model over one interval, as named scalars.

    ``G0 = H0 B``, ``G1 = H1 B``; ``Qd`` is symmetric (``qd10 = qd01``).
    """

    phi00: float
    phi01: float
    phi10: float
    phi11: float
    h0_00: float
    h0_01: float
    h0_10: float
    h0_11: float
    h1_00: float
    h1_01: float
    h1_10: float
    h1_11: float
    qd00: float
    qd01: float
    qd11: float


# ----------------------------------------------------------------- a packed estimation problem


class ConductanceArrays(NamedTuple):
    """An RC network in conductance form (:attr:`rczone.network.RCNetwork.conductance_form`)."""

    L: np.ndarray  #: (nr, n) incidence of the resistors on the states
    P: np.ndarray  #: (nr, nb) incidence of the resistors on the boundary inputs
    E: np.ndarray  #: (nb, p) selection of the boundary inputs among the inputs
    Gb0: np.ndarray  #: (n, p) heat inputs, W per unit input
    Nf: np.ndarray  #: (nf, n, n) supply-air terms of each flow
    Mf: np.ndarray  #: (nf, n, p)
    output_state: np.ndarray  #: (ny,) int64, output j reads state output_state[j]


class ProblemData(NamedTuple):
    """The data of a packed problem, with its distinct sampling intervals."""

    t: np.ndarray  #: (N,) s
    m: np.ndarray  #: (N, nf) kg/s
    u: np.ndarray  #: (N, p)
    y: np.ndarray  #: (N, ny)
    keys: np.ndarray  #: (K, 1 + nf) ``(dt, m_1, ...)`` of each distinct interval
    which: np.ndarray  #: (N - 1,) int64
    groups: np.ndarray  #: interval groups of the fused kernel, or empty


class Slots(NamedTuple):
    """Where each element, noise level, initial state and heat-input gain takes its value.

    A slot ``(idx, k)`` has the value ``k * theta[idx]``, or ``k`` when ``idx < 0``. The heat-input
    gains that are parameters are affine in ``theta``, ``Gb = Gb0 + sum_t k_t theta[idx_t] e_i e_j'``
    (a circuit's last share ``1 - s_1 - s_2`` is three terms: its constant is in ``Gb0``): term ``t``
    adds ``gain_k[t] * theta[gain_idx[t]]`` to ``Gb[gain_state[t], gain_input[t]]``.
    """

    res_idx: np.ndarray
    res_k: np.ndarray
    cap_idx: np.ndarray
    cap_k: np.ndarray
    sv_idx: np.ndarray  #: measurement noise, per output
    sv_k: np.ndarray
    sw_idx: np.ndarray  #: process noise, per state
    sw_k: np.ndarray
    sx_idx: np.ndarray  #: initial-state spread, per state
    sx_k: np.ndarray
    x0_idx: np.ndarray  #: initial state, per state
    x0_k: np.ndarray
    x0_given: np.ndarray  #: bool, given (else derived from the data)
    gain_state: np.ndarray  #: (ng,) int64, the state (row of ``Gb``) of each gain term
    gain_input: np.ndarray  #: (ng,) int64, the input (column of ``Gb``)
    gain_idx: np.ndarray  #: (ng,) int64, the parameter of each term
    gain_k: np.ndarray  #: (ng,) its coefficient, W per unit input and unit parameter


class SearchBox(NamedTuple):
    """The direct search's transform of the optimizer variables (``eta`` within its bounds)."""

    eta_lower: np.ndarray
    eta_upper: np.ndarray
    log: np.ndarray  #: bool, the parameter is searched in log space


class Penalty(NamedTuple):
    """The prior of a MAP problem, packed (:func:`rczone.estimation.priors.LogPrior.packed`).

    Prior ``k`` is on ``theta[prior_idx[k]]``, of family ``family[k]`` (``LOGNORMAL``, ``NORMAL``,
    ``UNIFORM`` of :mod:`rczone.kernels.problem`) with parameters ``(a[k], b[k])``: (median,
    sigma), (mean, sigma), (lower, upper); evaluated by :func:`rczone.kernels.problem.prior_terms`.
    """

    prior_idx: np.ndarray  #: (np_,) int64, parameters with a prior
    family: np.ndarray  #: (np_,) int64
    a: np.ndarray  #: (np_,) first parameter of each prior (SI)
    b: np.ndarray  #: (np_,) second parameter
    log: np.ndarray  #: (np_,) bool, the parameter is searched in log space (the density is on eta)
    likelihood_weight: float


class ProblemConstants(NamedTuple):
    """Settings of a packed problem."""

    foh: bool
    symmetry_rtol: float
    steady_rtol: float
    fused: bool  #: the fused 2-state kernel serves values (:func:`rczone.kernels.problem.value_kernel`)


class ElementValues(NamedTuple):
    """Element values, noise levels and initial states of a packed problem at one parameter point (SI)."""

    res: np.ndarray  #: (nr,) resistances, K/W
    cap: np.ndarray  #: (n,) capacities, J/K
    sv: np.ndarray  #: (ny,) measurement noise, K
    sw: np.ndarray  #: (n,) process noise intensity
    sx: np.ndarray  #: (n,) initial state spread, K
    x0: np.ndarray  #: (n,) given initial states, K


class Assembled(NamedTuple):
    """The continuous-time model of a packed problem at one parameter point, with its filter's start."""

    A0: np.ndarray  #: (n, n)
    N: np.ndarray  #: (nf, n, n)
    B0: np.ndarray  #: (n, p)
    M: np.ndarray  #: (nf, n, p)
    cap: np.ndarray  #: (n,) capacities, J/K
    x0: np.ndarray  #: (n,) initial state
    P0: np.ndarray  #: (n, n) its covariance
    qc: np.ndarray  #: (n,) process noise intensities
    r: np.ndarray  #: (ny,) measurement variances
    C: np.ndarray  #: (ny, n)


class AssembledDerivatives(NamedTuple):
    """Derivatives of :class:`Assembled` along ``q`` parameter directions (``q = 0``: none)."""

    dA0: np.ndarray  #: (q, n, n)
    dN: np.ndarray  #: (q, nf, n, n)
    dB0: np.ndarray  #: (q, n, p)
    dM: np.ndarray  #: (q, nf, n, p)
    dx0: np.ndarray  #: (q, n)
    dP0: np.ndarray  #: (q, n, n)
    dqc: np.ndarray  #: (q, n)
    dr: np.ndarray  #: (ny, q)


class SpectralWeights(NamedTuple):
    """An interval's spectral quantities (:mod:`rczone.kernels.discretize_adjoint`): ``x = lam h``, ``e^x``,
    the hold's weights ``h phi1(x)`` and the divided differences of ``Phi`` (``F0``) and ``G0`` (``Fg``)."""

    x: np.ndarray  #: (n,)
    e: np.ndarray  #: (n,)
    wg: np.ndarray  #: (n,)
    F0: np.ndarray  #: (n, n)
    Fg: np.ndarray  #: (n, n)


class ModelAdjoints(NamedTuple):
    """Adjoints of a continuous model: of ``A`` and ``B`` and of the process noise ``qc``.

    Of one interval's ``A``, ``B`` (shapes (n, n), (n, p)); summed over the intervals, of ``A0``
    and each flow's ``N_f`` (shape (1 + nf, n, n)) and of ``B0`` and each ``M_f`` ((1 + nf, n, p)).
    """

    A: np.ndarray
    B: np.ndarray
    qc: np.ndarray  #: (n,)


class Start(NamedTuple):
    """What the initial state is derived from (:func:`rczone.kernels.problem.initial_state`)."""

    m0: np.ndarray  #: (nf,) flows at the first sample, kg/s
    u0: np.ndarray  #: (p,) inputs at the first sample
    y0: np.ndarray  #: (ny,) first measurement, NaN where missing
    out_state: np.ndarray  #: (ny,) int64, output j reads state out_state[j]
    given: np.ndarray  #: (n,) bool, the state's initial value is given (kept as it is)


class Problem(NamedTuple):
    """A packed estimation problem (:func:`rczone.estimation.compiled.compiled_problem`)."""

    kind: int  #: LS, ML or MAP of :mod:`rczone.kernels.problem`
    form: ConductanceArrays
    data: ProblemData
    slots: Slots
    box: SearchBox
    penalty: Penalty
    consts: ProblemConstants
    scratch: np.ndarray  #: (N,) buffer for the fused open-loop errors


def dynamics_model(A0: np.ndarray, N: np.ndarray, B0: np.ndarray, M: np.ndarray, qc: np.ndarray) -> Assembled:
    """An :class:`Assembled` of a bilinear model's dynamics only, for callers that have no filter start.

    Parameters
    ----------
    A0, N, B0, M : ndarray, shapes (n, n), (nf, n, n), (n, p), (nf, n, p)
        ``A = A0 + sum_f m_f N_f``, ``B = B0 + sum_f m_f M_f``.
    qc : ndarray, shape (n,)
        Process-noise intensities.

    Returns
    -------
    Assembled
        With unit capacities, a zero initial state and covariance and no outputs (``C`` of shape
        (0, n)): what :mod:`rczone.kernels.discretize` and the initial state read are the
        dynamics. Every array is contiguous, writable float64, so one compiled specialization
        serves these and the packed problem's.
    """
    n = A0.shape[0]
    return Assembled(
        _writable(A0), _writable(N), _writable(B0), _writable(M), np.ones(n), np.zeros(n), np.zeros((n, n)),
        _writable(qc), np.zeros(0), np.zeros((0, n)),
    )  # fmt: skip


def dynamics_derivatives(
    dA0: np.ndarray, dN: np.ndarray, dB0: np.ndarray, dM: np.ndarray, dqc: np.ndarray
) -> AssembledDerivatives:
    """An :class:`AssembledDerivatives` of the dynamics only (no outputs, a fixed initial covariance).

    Parameters
    ----------
    dA0, dN, dB0, dM : ndarray, shapes (q, n, n), (q, nf, n, n), (q, n, p), (q, nf, n, p)
        Derivatives of the matrices of :func:`dynamics_model` along ``q`` directions.
    dqc : ndarray, shape (q, n)
        Derivatives of the process-noise intensities.

    Returns
    -------
    AssembledDerivatives
        With zero ``dx0`` and ``dP0`` and ``dr`` of shape (0, q).
    """
    q, n = dqc.shape
    return AssembledDerivatives(
        _writable(dA0), _writable(dN), _writable(dB0), _writable(dM), np.zeros((q, n)), np.zeros((q, n, n)),
        _writable(dqc), np.zeros((0, q)),
    )  # fmt: skip


def writable(a: np.ndarray, dtype: type = np.float64) -> np.ndarray:
    """``a`` as a C-contiguous, writable array of ``dtype``: a copy only where it is not one already.

    What every caller hands a kernel. numba compiles one specialization per argument type, and
    read-only is part of the type: a data set's frozen arrays, ``np.diag`` of a matrix (a
    read-only view when it is contiguous, a writable copy when not) or a model's arrays would
    otherwise compile a kernel again for the next model structure or data source. An array that
    already is one is returned as it is without ``np.require``'s checks (about 1 us against 0.2 us:
    a 2-state simulation makes four such calls, 5 % of its time).
    """
    if type(a) is np.ndarray and a.dtype == dtype:
        flags = a.flags
        if flags.c_contiguous and flags.writeable:
            return a
    return np.require(a, dtype, "CW")


_writable = writable
