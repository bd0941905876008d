"""The compiled Kalman filter of rczone, with forward sensitivities of its likelihood.

One filter for every model: ``n`` states, ``ny`` outputs, the discrete matrices of each
distinct sampling interval (``Phi, G0, G1, Qd`` from :mod:`rczone.kernels.discretize`),
diagonal measurement noise ``R = diag(r)``. The likelihood is the prediction-error
decomposition [1]_ with the outputs of a sample processed one at a time (sequential
processing, exact for diagonal ``R`` [2]_): each observed output is a scalar update, a missing
output (NaN) is skipped on its own, and no matrix is inverted.

The filter is written as short step functions, compiled with ``inline="always"`` (numba inlines
them into the sample loop at its own intermediate representation, so no call remains):
:func:`innovation`, :func:`correct` (the state's correction by one output), :func:`drive` and
:func:`advance` (the mean's prediction), :func:`predict_covariance`, :func:`stationary`,
:func:`keep_prediction`, :func:`change_basis`, and the derivatives' steps
(:func:`innovation_derivatives`, :func:`gain_derivatives`, :func:`score`,
:func:`predict_mean_derivatives`), which take the filter's named groups (:class:`Moments`,
:class:`Gains`, :class:`Work`, :class:`Moved`). The reverse pass (:mod:`rczone.kernels.reverse`)
runs the same value steps. Four pieces stay written in place in the loop, marked by comments,
because as calls they measurably cost (interleaved runs with fresh compilation caches, 2026-11-26):
the scalar update of gain and covariance (``s = c'Pc + r``, ``k = Pc/s``, ``P -= k (Pc)'``; as a call
``nll_4zone`` took 1.2x), the value steps of modal coordinates (taking the :class:`Dynamics` group,
1.15-1.3x), the ``O(n)`` test of the covariance's diagonal and the covariance copies of the steady
state. Passing a named group into a step of the ``O(n)`` value path costs reference counts of every
array in it at each call; the derivative steps, ``O(q n^2)`` and more, do not notice them.

Modal coordinates: for an RC model (``diag(c) A`` symmetric) whose flows change the matrices
only now and then, the same filter runs in the eigen-coordinates of each interval's state
matrix (``basis``), where ``Phi`` is diagonal and the time update costs ``O(n^2)``
(:func:`modal_pays` decides; one filter, one set of steps, no second implementation).
The plain-NumPy twin (``tests/oracles.py``, ``kalman_filter_reference``) is written from the same
steps; the tests compare the two filters, and both with a brute-force multivariate-normal density.

Forward sensitivities [3]_: for ``q`` parameter directions the derivatives of everything the
filter carries (``dx``, ``dP``) are propagated alongside by the product rule, given the
derivatives of the discrete matrices (``dPhi, dG0, dG1, dQd`` per interval), of the output
matrices (``dC, dD``), of ``r`` and of the prior (``dx0, dP0``). The gradient of ``-log L``
costs about ``2.5 n^3`` per direction and sample (``1.5 n^3`` when the direction leaves the
dynamics unchanged), i.e. one evaluation per optimizer step instead of ``2q + 1``.

Steady state: while the interval and the set of observed outputs repeat, the covariance
recursion does not depend on the data and converges to the stationary solution of the
Riccati equation. Once the predicted covariance's diagonal repeats (an ``O(n)`` test, necessary
since a covariance's largest entry is on its diagonal), the full matrices are kept, and once
the predicted covariance (and each of its derivatives) repeats to ``steady_rtol`` relative, the gains are kept and the ``O(n^3)`` covariance work is skipped
until the interval or the observed set changes (statsmodels' filter does the same [4]_). The
frozen covariance differs from the recursion's by at most ``steady_rtol`` relative, and so
does every later term of the likelihood; ``steady_rtol = 0`` disables it.

Open loop (least squares): with ``open_loop`` the covariance is not propagated; the state
evolves without correction and ``e_out``/``de_out`` receive the output errors and their
derivatives (the simulation sensitivities of the output-error cost).

References
----------
.. [1] A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman Filter*,
   Cambridge University Press, 1989, section 3.4.
.. [2] J. Durbin, S. J. Koopman, *Time Series Analysis by State Space Methods*, 2nd ed.,
   Oxford University Press, 2012, section 6.4 (univariate treatment of multivariate series).
.. [3] R. K. Mehra, "Optimal input signals for parameter estimation in dynamic systems --
   survey and new results", IEEE Trans. Automatic Control 19(6), 1974 (the sensitivity
   recursions of the Kalman filter for the likelihood gradient).
.. [4] C. Fulton, "Estimating time series models by state space methods in Python:
   Statsmodels", 2015, section 3.2 (convergence of the filter to its steady state).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from rczone.kernels.arrays import (
    Dynamics,
    DynamicsDerivatives,
    FilterOptions,
    FilterStart,
    FilterTrace,
    FilterValue,
    ModalBasis,
    Observation,
    Series,
)

#: Default relative tolerance at which the predicted covariance counts as stationary.
STEADY_RTOL = 1e-14

#: Modal coordinates are used when the matrices change, at most at this fraction of the steps.
MODAL_CHANGES = 0.25

#: Floating-point freedoms of the filter: sums may be reassociated (vectorized) and products
#: fused with additions; NaN and infinities keep their IEEE meaning (missing data).
FAST = {"reassoc", "contract"}


@njit(cache=True, error_model="numpy")
def no_sensitivities(K: int, n: int, p: int) -> DynamicsDerivatives:
    """The ``ddyn`` argument of :func:`kalman_filter` for the likelihood alone (``q = 0``)."""
    return DynamicsDerivatives(
        np.empty((K, 0, n, n)), np.empty((K, 0, n, p)), np.empty((K, 0, n, p)), np.empty((K, 0, n, n))
    )


@njit(cache=True, error_model="numpy")
def outputs(N: int, n: int, ny: int, q: int, errors: bool, states: bool) -> FilterTrace:
    """The ``trace`` argument of :func:`kalman_filter`, empty where not wanted.

    ``errors``: the innovations or output errors (NaN where missing) and their derivatives;
    ``states``: the innovations, predicted and filtered states, predicted and filtered
    covariances, ``S``, and the filtered states' derivatives along the ``q`` directions.
    """
    ne = N if errors or states else 0
    nd = N if errors else 0
    ns = N if states else 0
    return FilterTrace(
        np.full((ne, ny), np.nan),
        np.zeros((nd, ny, q)),
        np.empty((ns, n)),
        np.empty((ns, n)),
        np.empty((ns, n, n)),
        np.empty((ns, ny, ny)),
        np.empty((ns, n, n)),
        np.empty((ns, q, n)),
    )


class Moved(NamedTuple):
    """The derivatives of the discrete matrices, and which parameter directions move what (the terms of the others are skipped)."""

    ddyn: DynamicsDerivatives
    dynamics: np.ndarray  #: (q,) bool: the direction moves ``Phi``, ``G0`` or ``G1``
    C: bool  #: a direction moves ``C``
    D: bool  #: a direction moves ``D``


class Moments(NamedTuple):
    """What the filter carries from step to step: the state's mean and covariance, and their derivatives."""

    x: np.ndarray  #: (n,)
    P: np.ndarray  #: (n, n)
    dx: np.ndarray  #: (q, n)
    dP: np.ndarray  #: (q, n, n)


class Gains(NamedTuple):
    """Each output's gain and the derivatives of gain and innovation variance (kept for the steady state)."""

    kg: np.ndarray  #: (ny, n)
    dkg: np.ndarray  #: (ny, q, n)
    dsg: np.ndarray  #: (ny, q)


class Work(NamedTuple):
    """Work space of the steps."""

    pc: np.ndarray  #: (n,) ``P c``
    dpc: np.ndarray  #: (q, n) its derivatives
    de: np.ndarray  #: (q,) the innovation's derivatives
    xn: np.ndarray  #: (n,)
    T: np.ndarray  #: (n, n)
    X: np.ndarray  #: (n, n)
    Y: np.ndarray  #: (n, n)


@njit(cache=True, error_model="numpy")
def _moved(ddyn: DynamicsDerivatives, dC: np.ndarray, dD: np.ndarray) -> Moved:
    """The :class:`Moved` of a run from the derivatives of the dynamics and of the output matrices."""
    dPhi, dG0, dG1 = ddyn.dPhi, ddyn.dG0, ddyn.dG1
    K, q, n, p = dG0.shape
    dyn = np.zeros(q, dtype=np.bool_)
    for d in range(q):
        for w in range(K):
            for i in range(n):
                for j in range(n):
                    dyn[d] = dyn[d] or dPhi[w, d, i, j] != 0.0
                for j in range(p):
                    dyn[d] = dyn[d] or dG0[w, d, i, j] != 0.0 or dG1[w, d, i, j] != 0.0
    has_dc = False
    has_dd = False
    for j in range(dC.shape[0]):
        for d in range(q):
            for i in range(n):
                has_dc = has_dc or dC[j, d, i] != 0.0
            for i in range(p):
                has_dd = has_dd or dD[j, d, i] != 0.0
    return Moved(ddyn, dyn, has_dc, has_dd)


@njit(error_model="numpy", fastmath=FAST, inline="always")
def innovation(
    k: int, o: int, y: np.ndarray, u: np.ndarray, D: np.ndarray, C: np.ndarray, x: np.ndarray
) -> float:
    """``e = y[k, o] - D[o] u[k] - C[o] x``: the innovation of output ``o`` (its error in open loop)."""
    e = y[k, o]
    for i in range(u.shape[1]):
        e -= D[o, i] * u[k, i]
    for i in range(x.shape[0]):
        e -= C[o, i] * x[i]
    return e


@njit(error_model="numpy", fastmath=FAST, inline="always")
def correct(o: int, e: float, kg: np.ndarray, x: np.ndarray) -> None:
    """``x += kg[o] e``: the state's correction by output ``o``."""
    for i in range(x.shape[0]):
        x[i] += kg[o, i] * e


@njit(error_model="numpy", fastmath=FAST, inline="always")
def drive(w: int, k: int, G0: np.ndarray, G1: np.ndarray, u: np.ndarray, foh: bool, out: np.ndarray) -> None:
    """``out = G0[w] u[k] (+ G1[w] u[k + 1] with a first-order hold)``: the inputs' part of the mean's prediction."""
    p = u.shape[1]
    for i in range(out.shape[0]):
        acc = 0.0
        for j in range(p):
            acc += G0[w, i, j] * u[k, j]
        if foh:
            for j in range(p):
                acc += G1[w, i, j] * u[k + 1, j]
        out[i] = acc


@njit(error_model="numpy", fastmath=FAST, inline="always")
def advance(w: int, Phi: np.ndarray, x: np.ndarray, drv: np.ndarray) -> None:
    """``x = Phi[w] x + drv``: the mean's prediction; ``drv`` (of :func:`drive`) is overwritten."""
    n = x.shape[0]
    for i in range(n):
        acc = drv[i]
        for j in range(n):
            acc += Phi[w, i, j] * x[j]
        drv[i] = acc
    for i in range(n):
        x[i] = drv[i]


@njit(error_model="numpy", fastmath=FAST, inline="always")
def innovation_derivatives(
    k: int, o: int, u: np.ndarray, m: Moments, obs: Observation, moved: Moved, de: np.ndarray
) -> None:
    """``de[d] = -dD[o, d] u[k] - dC[o, d] x - C[o] dx[d]`` along each direction (before the update)."""
    C, dC, dD = obs.C, obs.dC, obs.dD
    x, dx = m.x, m.dx
    n = x.shape[0]
    p = u.shape[1]
    for d in range(de.shape[0]):
        ed = 0.0
        if moved.D:
            for i in range(p):
                ed -= dD[o, d, i] * u[k, i]
        for i in range(n):
            ed -= C[o, i] * dx[d, i]
        if moved.C:
            for i in range(n):
                ed -= dC[o, d, i] * x[i]
        de[d] = ed


@njit(error_model="numpy", fastmath=FAST, inline="always")
def gain_derivatives(
    o: int, s: float, m: Moments, obs: Observation, moved: Moved, gains: Gains, work: Work
) -> None:
    """The derivatives of the gain and of the covariance's downdate along each direction (``P`` before it).

    ``dpc = dP c + P dc``, ``ds = c'dpc + dc'pc + dr``, ``dk = (dpc - k ds) / s``,
    ``dP -= dk pc' + k dpc'`` (exactly symmetric); ``pc = P c`` and ``k`` of the update in ``work.pc``
    and ``gains.kg[o]``.
    """
    C, dC, dr = obs.C, obs.dC, obs.dr
    P, dP = m.P, m.dP
    kg, dkg, dsg = gains
    pc, dpc = work.pc, work.dpc
    n = P.shape[0]
    inv = 1.0 / s
    for d in range(dP.shape[0]):
        sd = dr[o, d]
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += dP[d, i, j] * C[o, j]
            if moved.C:
                for j in range(n):
                    acc += P[i, j] * dC[o, d, j]
                sd += dC[o, d, i] * pc[i]
            dpc[d, i] = acc
            sd += C[o, i] * acc
        dsg[o, d] = sd
        for i in range(n):
            dkg[o, d, i] = (dpc[d, i] - kg[o, i] * sd) * inv
        for i in range(n):
            dki = dkg[o, d, i]  # locals: the stores into dP could alias them
            ki = kg[o, i]
            for j in range(i, n):
                v = dP[d, i, j] - dki * pc[j] - ki * dpc[d, j]
                dP[d, i, j] = v
                dP[d, j, i] = v


@njit(error_model="numpy", fastmath=FAST, inline="always")
def score(
    o: int, e: float, s: float, gains: Gains, work: Work, m: Moments, grad: np.ndarray, fim: np.ndarray
) -> None:
    """The gradient and Fisher terms of output ``o``'s ``0.5 (log s + e^2/s)``, and ``dx += dk e + k de``."""
    kg, dkg, dsg = gains
    de = work.de
    dx = m.dx
    inv = 1.0 / s
    n = dx.shape[1]
    for d in range(de.shape[0]):
        sd = dsg[o, d]
        ed = de[d]
        grad[d] += 0.5 * sd * inv + e * ed * inv - 0.5 * e * e * sd * inv * inv
        fim[d] += ed * ed * inv + 0.5 * sd * sd * inv * inv
        for i in range(n):
            dx[d, i] += dkg[o, d, i] * e + kg[o, i] * ed


@njit(error_model="numpy", fastmath=FAST, inline="always")
def predict_mean_derivatives(
    w: int, k: int, m: Moments, dyn: Dynamics, moved: Moved, u: np.ndarray, foh: bool, xn: np.ndarray
) -> None:
    """``dx[d] = Phi dx[d] + dPhi[d] x + dG0[d] u[k] (+ dG1[d] u[k + 1])`` (``x`` before :func:`predict_mean`).

    The ``dPhi``, ``dG0``, ``dG1`` terms are skipped for directions that leave the dynamics unchanged.
    """
    Phi = dyn.Phi
    dPhi, dG0, dG1 = moved.ddyn.dPhi, moved.ddyn.dG0, moved.ddyn.dG1
    x, dx = m.x, m.dx
    n = x.shape[0]
    p = u.shape[1]
    for d in range(dx.shape[0]):
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += Phi[w, i, j] * dx[d, j]
            if moved.dynamics[d]:
                for j in range(n):
                    acc += dPhi[w, d, i, j] * x[j]
                for j in range(p):
                    acc += dG0[w, d, i, j] * u[k, j]
                if foh:
                    for j in range(p):
                        acc += dG1[w, d, i, j] * u[k + 1, j]
            xn[i] = acc
        for i in range(n):
            dx[d, i] = xn[i]


@njit(error_model="numpy", fastmath=FAST, inline="always")
def keep_prediction(
    k: int, x: np.ndarray, P: np.ndarray, obs: Observation, trace: FilterTrace, pc: np.ndarray
) -> None:
    """Store the predicted state, its covariance and ``S = C P C' + R`` in the trace arrays that have row ``k``."""
    n = x.shape[0]
    C, r = obs.C, obs.r
    if trace.xp.shape[0] > k:
        for i in range(n):
            trace.xp[k, i] = x[i]
    if trace.Pp.shape[0] > k:
        for i in range(n):
            for j in range(n):
                trace.Pp[k, i, j] = P[i, j]
    if trace.S.shape[0] > k:
        ny = C.shape[0]
        for a in range(ny):
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += P[i, j] * C[a, j]
                pc[i] = acc
            for b in range(ny):
                acc = r[a] if a == b else 0.0
                for i in range(n):
                    acc += C[b, i] * pc[i]
                trace.S[k, a, b] = acc


@njit(error_model="numpy", fastmath=FAST, inline="always")
def predict_covariance(w: int, m: Moments, dyn: Dynamics, moved: Moved, work: Work) -> None:
    """``P = Phi P Phi' + Qd``; ``dP = dPhi P Phi' + Phi P dPhi' + Phi dP Phi' + dQd`` (exactly symmetric)."""
    P, dP = m.P, m.dP
    Phi, Qd = dyn.Phi, dyn.Qd
    dPhi, dQd = moved.ddyn.dPhi, moved.ddyn.dQd
    T, X, Y = work.T, work.X, work.Y
    n = P.shape[0]
    phi_times(w, Phi, P, T)
    for d in range(dP.shape[0]):
        if moved.dynamics[d]:
            for i in range(n):
                for j in range(n):
                    acc = 0.0
                    for a in range(n):
                        acc += T[i, a] * dPhi[w, d, j, a]
                    X[i, j] = acc
        for i in range(n):
            for j in range(n):
                Y[i, j] = 0.0
            for a in range(n):
                f = Phi[w, i, a]
                for j in range(n):
                    Y[i, j] += f * dP[d, a, j]
        for i in range(n):
            for j in range(i, n):
                acc = dQd[w, d, i, j]
                for a in range(n):
                    acc += Y[i, a] * Phi[w, j, a]
                if moved.dynamics[d]:
                    acc += X[i, j] + X[j, i]
                dP[d, i, j] = acc
                dP[d, j, i] = acc
    times_phi_plus(w, T, Phi, Qd, P)


@njit(error_model="numpy", fastmath=FAST, inline="always")
def phi_times(w: int, Phi: np.ndarray, P: np.ndarray, T: np.ndarray) -> None:
    """``T = Phi[w] P``: the first half of the covariance prediction (also kept by the reverse pass)."""
    n = P.shape[0]
    for i in range(n):
        for j in range(n):
            T[i, j] = 0.0
        for a in range(n):
            f = Phi[w, i, a]
            for j in range(n):
                T[i, j] += f * P[a, j]


@njit(error_model="numpy", fastmath=FAST, inline="always")
def times_phi_plus(w: int, T: np.ndarray, Phi: np.ndarray, Qd: np.ndarray, P: np.ndarray) -> None:
    """``P = T Phi[w]' + Qd[w]`` from the upper triangle, mirrored: exactly symmetric."""
    n = P.shape[0]
    for i in range(n):
        for j in range(i, n):
            acc = Qd[w, i, j]
            for a in range(n):
                acc += T[i, a] * Phi[w, j, a]
            P[i, j] = acc
            P[j, i] = acc


@njit(error_model="numpy", fastmath=FAST, inline="always")
def stationary(P: np.ndarray, dP: np.ndarray, P_prev: np.ndarray, dP_prev: np.ndarray, rtol: float) -> bool:
    """Whether ``P`` and each ``dP[d]`` repeat their previous values to ``rtol`` (largest difference / largest entry)."""
    n = P.shape[0]
    big = 0.0
    diff = 0.0
    for i in range(n):
        for j in range(n):
            big = max(big, abs(P[i, j]))
            diff = max(diff, abs(P[i, j] - P_prev[i, j]))
    if not diff <= rtol * big:
        return False
    for d in range(dP.shape[0]):
        big = 0.0
        diff = 0.0
        for i in range(n):
            for j in range(n):
                big = max(big, abs(dP[d, i, j]))
                diff = max(diff, abs(dP[d, i, j] - dP_prev[d, i, j]))
        if not diff <= rtol * big:
            return False
    return True


@njit(error_model="numpy", fastmath=FAST, inline="always")
def change_basis(
    Vnew: np.ndarray, Vold: np.ndarray, x: np.ndarray, P: np.ndarray, Mx: np.ndarray, xn: np.ndarray
) -> None:
    """Carry ``x, P`` from the modal coordinates ``Vold`` to ``Vnew``: ``M = Vnew' Vold``, ``x = M x``, ``P = M P M'``."""
    n = x.shape[0]
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for a in range(n):
                acc += Vnew[a, i] * Vold[a, j]
            Mx[i, j] = acc
    transform(Mx, x, P, xn)


@njit(error_model="numpy", fastmath=FAST, inline="always")
def transform(M: np.ndarray, x: np.ndarray, P: np.ndarray, xn: np.ndarray) -> None:
    """``x = M x``, ``P = M P M'`` (exactly symmetric) in place; ``xn`` (n,) is work space.

    :func:`rczone.kernels.discretize.congruence` with the filter's floating-point freedoms
    (:data:`FAST`): called from there, strict, it cost the 13-state likelihood 25 %.
    """
    n = x.shape[0]
    T = np.empty((n, n))
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += M[i, j] * x[j]
        xn[i] = acc
        for j in range(n):
            T[i, j] = 0.0
        for a in range(n):
            f = M[i, a]
            for j in range(n):
                T[i, j] += f * P[a, j]
    for i in range(n):
        x[i] = xn[i]
        for j in range(i, n):
            acc = 0.0
            for a in range(n):
                acc += T[i, a] * M[j, a]
            P[i, j] = acc
            P[j, i] = acc


@njit(cache=True, error_model="numpy")
def modal_start(basis: ModalBasis, w: int, x: np.ndarray, P: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Carry the prior ``x, P`` and the output rows ``C`` into the modal coordinates of interval ``w``, in place.

    ``x = V[w]' diag(scale) x``, ``P = V[w]' diag(scale) P diag(scale) V[w]``, ``C = C diag(scale)^-1 V[w]``;
    returns the output rows of every interval's coordinates, shape (K, ny, n).
    """
    V, scale = basis.V, basis.scale
    K, n, _ = V.shape
    ny = C.shape[0]
    Cm = np.empty((K, ny, n))
    for k in range(K):
        for o in range(ny):
            for i in range(n):
                acc = 0.0
                for a in range(n):
                    acc += C[o, a] / scale[a] * V[k, a, i]
                Cm[k, o, i] = acc
    for o in range(ny):
        for i in range(n):
            C[o, i] = Cm[w, o, i]
    M = np.empty((n, n))  # V[w]' diag(scale)
    for i in range(n):
        for a in range(n):
            M[i, a] = V[w, a, i] * scale[a]
    transform(M, x, P, np.empty(n))
    return Cm


@njit(cache=True, error_model="numpy", fastmath=FAST)
def kalman_filter(
    dyn: Dynamics,
    ddyn: DynamicsDerivatives,
    obs: Observation,
    prior: FilterStart,
    series: Series,
    opts: FilterOptions,
    trace: FilterTrace,
    basis: ModalBasis | None = None,
) -> FilterValue:
    """Run the filter over all samples; ``-log L`` without ``0.5 n log 2 pi``, and its gradient.

    Parameters
    ----------
    dyn : Dynamics
        Discrete matrices of each distinct interval.
    ddyn : DynamicsDerivatives
        Their derivatives along ``q`` directions; ``q = 0`` (:func:`no_sensitivities`) computes the
        likelihood only.
    obs : Observation
        Output matrices and measurement variances (``R = diag(r)``), with derivatives.
    prior : FilterStart
        Mean and covariance at the first sample, with derivatives.
    series : Series
        Inputs, outputs (NaN marks a missing output) and the interval of each step.
    opts : FilterOptions
        Hold, open loop, steady-state tolerance.
    trace : FilterTrace
        Each array is filled when its first axis has N entries (:func:`outputs` makes them):
        innovations ``y - C x_pred - D u`` (the output errors in open loop), their derivatives
        (open loop only), predicted and filtered states, predicted covariances, innovation
        covariances, innovation covariances, filtered covariances and the filtered states'
        derivatives (the last two not in open loop). Entries of missing outputs are left as they are.
    basis : ModalBasis, optional
        Run in the modal coordinates of an RC model (values only: ``q = 0``, only the
        innovations in ``trace``): ``dyn`` holds each interval's matrices in its own modal
        coordinates (:func:`rczone.kernels.discretize.modal_matrices`), where ``Phi`` is diagonal.
        The prior and ``C`` are carried into the coordinates of the first interval, the state
        and covariance into those of the next one where the interval changes (``O(n^3)`` once
        per change), and the time update costs ``O(n^2)`` instead of ``O(n^3)``. The likelihood
        is the same (coordinates change nothing but rounding); :func:`modal_pays` says when it
        is faster.

    Returns
    -------
    FilterValue
        ``nll = sum 0.5 (log s + e^2/s)`` over the observed outputs (0 in open loop), NaN for an
        invalid model (a non-positive innovation variance); ``n_obs`` observed scalars (-1 for an
        invalid model); ``grad`` the derivatives of ``nll``; ``fim`` the diagonal of the Fisher
        information, ``sum de^2/s + 0.5 (ds/s)^2`` over the observed outputs [3]_: the curvature
        optimizers scale their variables with.

    Notes
    -----
    The update by output ``o`` with ``c = C[o]``: :func:`innovation` ``e = y - d'u - c'x``; the scalar
    update in the loop ``s = c'Pc + r``, ``k = Pc / s``, ``P -= k (Pc)'`` (kept exactly symmetric);
    :func:`correct` ``x += k e``. Along each direction ``j`` (:func:`innovation_derivatives`,
    :func:`gain_derivatives`, :func:`score`): ``de = -dd_j'u - dc_j'x - c'dx_j``,
    ``ds = c'dP_j c + 2 dc_j'Pc + dr_j``, ``dk = (dPc - k ds)/s``, ``dx_j += dk e + k de``,
    ``dP_j -= dk (Pc)' + k (dPc)'``; the gradient gains the derivative of ``0.5 (log s + e^2/s)``.

    The prediction with the matrices of interval ``w`` (:func:`drive` and :func:`advance`,
    :func:`predict_mean_derivatives`, :func:`predict_covariance`; with a basis the value steps in the
    loop, ``Phi`` diagonal, after :func:`change_basis` where the interval changes): ``x = Phi x + drive``,
    ``P = Phi P Phi' + Qd``; ``dx_j = dPhi_j x + Phi dx_j + ddrive_j``,
    ``dP_j = dPhi_j P Phi' + Phi P dPhi_j' + Phi dP_j Phi' + dQd_j`` (the ``dPhi`` terms skipped
    for directions that leave the dynamics unchanged).
    """
    Phi, G0, G1, Qd = dyn
    D, r = obs.D, obs.r
    u, y, which = series
    foh, open_loop, steady_rtol = opts
    N, ny = y.shape
    n = prior.x0.shape[0]
    q = prior.dx0.shape[0]
    if basis is not None:
        q = 0  # a constant: the compiler drops every derivative loop of this specialization
    moved = _moved(ddyn, obs.dC, obs.dD)
    # one definition each (no reassignment): numba then keeps their reference counts out of the loop
    x = prior.x0.copy()
    P = prior.P0.copy()
    C = obs.C.copy()
    cur = 0  # the interval whose modal coordinates carry x, P and C (with a basis)
    Cm = np.empty((0, ny, n))
    if basis is not None:
        if (
            prior.dx0.shape[0] > 0
            or trace.xp.shape[0] + trace.xf.shape[0] + trace.Pp.shape[0] + trace.S.shape[0] > 0
        ):
            raise ValueError("the filter in modal coordinates computes values and innovations only")
        cur = which[0] if N > 1 else 0
        Cm = modal_start(basis, cur, x, P, C)
    dx = prior.dx0.copy()
    dP = prior.dP0.copy()
    d_prev = np.empty(n)  # the diagonal of the last prediction
    for i in range(n):
        d_prev[i] = P[i, i]
    grad = np.zeros(q)
    fim = np.zeros(q)
    # work arrays of the steps, local variables (held in a tuple they cost ~10 % on nll_4zone)
    pc = np.empty(n)
    dpc = np.empty((q, n))
    de = np.empty(q)
    xn = np.empty(n)
    diag = np.empty(n)  # Phi's diagonal in modal coordinates
    T = np.empty((n, n))
    X = np.empty((n, n))
    Y = np.empty((n, n))
    Mx = np.empty((n, n))
    # each output's gain, innovation variance and their derivatives, kept for the steady state
    kg = np.zeros((ny, n))
    dkg = np.zeros((ny, q, n))
    sg = np.ones(ny)
    lg = np.zeros(ny)
    dsg = np.zeros((ny, q))
    # the same arrays by name, for the steps of the derivatives and of the covariance (O(q n^2) and more)
    m = Moments(x, P, dx, dP)
    gains = Gains(kg, dkg, dsg)
    work = Work(pc, dpc, de, xn, T, X, Y)
    # the covariances the steady state compares with (the last prediction) and returns to (the last
    # filtered): copied in full only while armed, i.e. once the diagonal has repeated (the O(n) test in the loop)
    armed = False
    P_prev = np.empty((n, n))
    dP_prev = np.empty((q, n, n))
    P_filt = np.empty((n, n))
    dP_filt = np.empty((q, n, n))
    steady = False
    steady_key = -1
    steady_mask = -1
    prev_key = -1
    prev_mask = -1
    keep_xf = trace.xf.shape[0] == N
    keep_pred = trace.xp.shape[0] == N or trace.Pp.shape[0] == N or trace.S.shape[0] == N
    keep_e = trace.e.shape[0] == N
    keep_de = trace.de.shape[0] == N
    keep_Pf = trace.Pf.shape[0] == N and not open_loop
    keep_dxf = trace.dxf.shape[0] == N and not open_loop
    nll = 0.0
    n_obs = 0
    for k in range(N):
        mask = 0
        for j in range(ny):
            if y[k, j] == y[k, j]:
                mask |= 1 << j
        if keep_pred:
            keep_prediction(k, x, P, obs, trace, pc)
        if keep_e:
            for j in range(ny):
                if mask & (1 << j):
                    trace.e[k, j] = innovation(k, j, y, u, D, C, x)
        if open_loop:
            if keep_de:
                for j in range(ny):
                    if mask & (1 << j):
                        innovation_derivatives(k, j, u, m, obs, moved, trace.de[k, j])
        else:
            if steady and mask != steady_mask:
                steady = False
            if not steady and armed:
                for i in range(n):
                    for j in range(n):
                        P_prev[i, j] = P[i, j]
                        for d in range(q):
                            dP_prev[d, i, j] = dP[d, i, j]
            for o in range(ny):
                if not mask & (1 << o):
                    continue
                e = innovation(k, o, y, u, D, C, x)
                if q > 0:
                    innovation_derivatives(k, o, u, m, obs, moved, de)
                if not steady:
                    # gain() and downdate() written in place: as calls they made nll_4zone 1.2x slower
                    # (interleaved runs, fresh caches; the other steps are free as calls)
                    s = r[o]
                    for i in range(n):
                        acc = 0.0
                        for j in range(n):
                            acc += P[i, j] * C[o, j]
                        pc[i] = acc
                        s += C[o, i] * acc
                    if not s > 0.0:
                        return FilterValue(math.nan, -1, grad, fim)
                    inv = 1.0 / s
                    for i in range(n):
                        kg[o, i] = pc[i] * inv
                    if q > 0:
                        gain_derivatives(o, s, m, obs, moved, gains, work)
                    for i in range(n):
                        ki = kg[o, i]
                        for j in range(i, n):
                            v = P[i, j] - ki * pc[j]
                            P[i, j] = v
                            P[j, i] = v
                    sg[o] = s
                    lg[o] = math.log(s)
                # the state's correction, likelihood term and gradient (steady or not)
                s = sg[o]
                if q > 0:
                    score(o, e, s, gains, work, m, grad, fim)
                correct(o, e, kg, x)
                inv = 1.0 / s
                nll += 0.5 * (lg[o] + e * e * inv)
                n_obs += 1
            if not steady and (armed or keep_Pf):
                for i in range(n):
                    for j in range(n):
                        P_filt[i, j] = P[i, j]
                        for d in range(q):
                            dP_filt[d, i, j] = dP[d, i, j]
        if keep_xf:
            for i in range(n):
                trace.xf[k, i] = x[i]
        if keep_dxf:
            for d in range(q):
                for i in range(n):
                    trace.dxf[k, d, i] = dx[d, i]
        if keep_Pf:
            # the filtered covariance, also while the steady state holds P at its prediction
            for i in range(n):
                for j in range(n):
                    trace.Pf[k, i, j] = P_filt[i, j]
        if k == N - 1:
            break
        w = which[k]
        if not open_loop and steady and w != steady_key:
            # leave the steady state from its filtered covariance
            steady = False
            for i in range(n):
                for j in range(n):
                    P[i, j] = P_filt[i, j]
                    for d in range(q):
                        dP[d, i, j] = dP_filt[d, i, j]
        if basis is not None:
            if w != cur:
                change_basis(basis.V[w], basis.V[cur], x, P, Mx, xn)
                cur = w
                for o in range(ny):
                    for i in range(n):
                        C[o, i] = Cm[w, o, i]
            # ---- the mean's prediction in modal coordinates, Phi diagonal (in the loop, see above)
            drive(w, k, G0, G1, u, foh, xn)
            for i in range(n):
                diag[i] = Phi[w, i, i]  # contiguous, so the loops below vectorize
            for i in range(n):
                x[i] = diag[i] * x[i] + xn[i]
        else:
            if q > 0:
                predict_mean_derivatives(w, k, m, dyn, moved, u, foh, xn)
            drive(w, k, G0, G1, u, foh, xn)
            advance(w, Phi, x, xn)
        if open_loop:
            continue
        if steady:
            prev_key = w
            prev_mask = mask
            continue
        if basis is not None:
            # ---- the covariance's prediction in modal coordinates: P_ij e_i e_j + Qd_ij, O(n^2) (in the loop)
            for i in range(n):
                ei = diag[i]
                for j in range(i, n):
                    v = P[i, j] * ei * diag[j] + Qd[w, i, j]
                    P[i, j] = v
                    P[j, i] = v
        else:
            predict_covariance(w, m, dyn, moved, work)
        # the steady state: the same interval and observed outputs as before, and P repeats. First the
        # diagonal repeats the last prediction's (O(n), in the loop): necessary for the stationary test of a
        # covariance, whose largest entry lies on its diagonal; the full matrices are kept for it from then on
        repeats = False
        if steady_rtol > 0.0:
            big = 0.0
            diff = 0.0
            for i in range(n):
                v = P[i, i]
                big = max(big, abs(v))
                diff = max(diff, abs(v - d_prev[i]))
                d_prev[i] = v
            repeats = w == prev_key and mask == prev_mask and diff <= steady_rtol * big
        if repeats:
            if armed:
                steady = stationary(P, dP, P_prev, dP_prev, steady_rtol)
                if steady:
                    steady_key = w
                    steady_mask = mask
            armed = True
        else:
            armed = False
        prev_key = w
        prev_mask = mask
    return FilterValue(nll, n_obs, grad, fim)


@njit(cache=True, error_model="numpy")
def modal_pays(which: np.ndarray, n: int) -> bool:
    """Whether :func:`kalman_filter` in modal coordinates (``basis``) beats it in the original ones (``-log L`` only).

    A change of coordinates costs about three ``n^3`` products, a direct time update one and
    a half; modal coordinates win for three or more states when the intervals change their
    matrices at most at :data:`MODAL_CHANGES` of the steps, and also when they never change (one
    interval: LTI data, regular sampling), where the ``O(n^2)`` time updates before the steady
    state beat the ``O(n^3)`` ones (the steady state costs ``O(n)`` per output in either).
    Measured by ``bench/filters.py`` (load 7.4): the original coordinates take 2.44x the modal
    ones' time on ``nll_13state`` (13 states, 24 stretches of 30 samples, never stationary within
    one) and 1.29x on ``nll_4zone`` (8 states, 4 outputs, one interval).

    Parameters
    ----------
    which : ndarray of int64, shape (N - 1,)
        The interval of each step.
    n : int
        The number of states.

    Returns
    -------
    bool
    """
    changes = 0
    for k in range(1, which.shape[0]):
        if which[k] != which[k - 1]:
            changes += 1
    return n >= 3 and which.shape[0] > 0 and changes <= MODAL_CHANGES * which.shape[0]
