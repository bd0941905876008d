"""The k-step prediction-error criterion of the Kalman predictor, with its exact gradient.

A model predictive controller uses the model 1 to 24 h ahead; maximum likelihood fits it one
step ahead (the innovations). MPC-relevant identification [1]_ [2]_ instead fits the predictions
the controller will use: over a set of horizons ``H``,

``J(theta) = 1/2 sum_{k in H} sum_j sum_o (y_jo - y_hat_jo|j-k)^2``  (K^2),

where ``y_hat_j|j-k`` is the Kalman filter's filtered state at ``j - k`` propagated ``k`` steps with
the known inputs (:func:`rczone.estimation.forecast.k_step_bands` computes the same means). The
predictions depend on the noise levels only through the filter's gains, which are unchanged when
every noise level is multiplied by one factor: the criterion identifies the ratios of the noise
levels, not their scale. The scale is then set for the band by the closed-form maximum of the
likelihood over that one factor with the gains fixed, ``c^2 = mean(e_j^2 / S_j)`` of the one-step
innovations (:func:`noise_scale`).

The gradient is exact: the filter is run with its forward sensitivities (the derivatives of the
discrete matrices from :func:`rczone.kernels.discretize.interval_derivatives`, then those of the
gain, the filtered mean and covariance at every sample, the scalar updates of one output at a
time as the compiled filter does), and the k-step means and their derivatives are propagated from
every origin at once. The per-sample contributions ``g_j = -sum_k e_j|j-k dy_hat_j|j-k`` are kept
for the criterion's sandwich covariance (:func:`sandwich_covariance`): the criterion is not a
likelihood, so the inverse Hessian alone is not the estimates' covariance [3]_.

References
----------
.. [1] M. S. Shook, C. Mohtadi, S. L. Shah, "Identification for long-range predictive control",
   IEE Proceedings D 138 (1991) 75-84.
.. [2] R. B. Gopaluni, R. S. Patwardhan, S. L. Shah, "The nature of data pre-filters in MPC
   relevant identification - open- and closed-loop issues", Automatica 39 (2003) 1617-1626.
.. [3] H. White, "Maximum likelihood estimation of misspecified models", Econometrica 50 (1982)
   1-25; W. K. Newey, K. D. West, "A simple, positive semi-definite, heteroskedasticity and
   autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703-708.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.engines import assemble
from rczone.kernels.arrays import Dynamics, DynamicsDerivatives, FilterOptions, FilterTrace, Series, writable
from rczone.kernels.discretize import interval_derivatives
from rczone.kernels.kalman import kalman_filter
from rczone.network import RCNetwork


@dataclass(frozen=True, eq=False)
class KStepCost:
    """The k-step criterion at one parameter value.

    Attributes
    ----------
    value : float
        ``J``, K^2.
    gradient : ndarray, shape (q,)
        ``dJ / d theta`` along the names asked for (theta units).
    gauss_newton : ndarray, shape (q, q)
        ``sum dy_hat dy_hat'``: the Gauss-Newton Hessian of ``J``.
    contributions : ndarray, shape (N, q)
        The gradient's part from each target sample (summed over horizons and outputs).
    n_errors : int
        Number of (target, horizon, output) errors in ``J``.
    """

    value: float
    gradient: np.ndarray
    gauss_newton: np.ndarray
    contributions: np.ndarray
    n_errors: int


def check_horizons(horizons: Sequence[int]) -> tuple[int, ...]:
    """Sorted distinct positive step counts; anything else is a ParameterError.

    Parameters
    ----------
    horizons : sequence of int
    """
    try:
        hs = sorted({int(h) for h in horizons})
        ok = bool(hs) and all(h >= 1 for h in hs) and all(float(h) == int(h) for h in horizons)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ParameterError(f"horizons must be positive step counts (e.g. 1,12,72), got {horizons!r}")
    return tuple(hs)


def _filtered(asm, mats: Dynamics, dmats: DynamicsDerivatives, data: Dataset, foh: bool):
    """Filtered means and their derivatives at every sample, shapes (N, n) and (N, q, n).

    The compiled filter (:func:`rczone.kernels.kalman.kalman_filter`) with its forward
    sensitivities keeps them (``trace.xf``, ``trace.dxf``); its steady-state shortcut is off, so
    the gains are those of the exact recursion at every sample.
    """
    obs, prior = asm.observation, asm.prior
    N, n, ny, q = data.n_samples, prior.x0.shape[0], obs.C.shape[0], prior.dx0.shape[0]
    trace = FilterTrace(
        np.full((0, ny), np.nan),
        np.zeros((0, ny, q)),
        np.empty((0, n)),
        np.empty((N, n)),
        np.empty((0, n, n)),
        np.empty((0, ny, ny)),
        np.empty((0, n, n)),
        np.empty((N, q, n)),
    )
    f = writable  # one specialization whatever the arrays' origin
    series = Series(f(data.u), f(data.y), f(data.intervals[1], np.int64))
    _, n_obs, _, _ = kalman_filter(mats, dmats, obs, prior, series, FilterOptions(foh, False, 0.0), trace)
    if n_obs < 0:
        raise np.linalg.LinAlgError("an innovation variance is not positive: the noise model is invalid")
    return trace.xf, trace.dxf


def kstep_cost(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    horizons: Sequence[int],
    *,
    wrt: Sequence[str] = (),
    hold: str = "zoh",
) -> KStepCost:
    """The k-step criterion ``J`` and its exact gradient along ``wrt`` (see the module notes).

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Parameter values and noise levels (as for the likelihood).
    data : Dataset
    horizons : sequence of int
        Steps ahead the predictions are scored at.
    wrt : sequence of str
        Parameters the gradient is taken along (names as :func:`rczone.estimation.costs.ml_cost` takes).
    hold : {"zoh", "foh"}

    Returns
    -------
    KStepCost
    """
    hs = check_horizons(horizons)
    data.check_against(network)
    asm = assemble(network, values, data, hold, "ml", wrt)
    mats, dmats = interval_derivatives(asm.mod, asm.der, asm.how)
    xf, dxf = _filtered(asm, mats, dmats, data, hold == "foh")
    obs = asm.observation
    u, y, which = data.u, data.y, data.intervals[1]
    N, q = y.shape[0], len(tuple(wrt))
    drive = np.einsum("tab,tb->ta", mats.G0[which], u[:-1]) + np.einsum("tab,tb->ta", mats.G1[which], u[1:])
    ddrive = np.einsum("tqab,tb->tqa", dmats.dG0[which], u[:-1]) + np.einsum(
        "tqab,tb->tqa", dmats.dG1[which], u[1:]
    )
    value, grad, gn, contrib, count = 0.0, np.zeros(q), np.zeros((q, q)), np.zeros((N, q)), 0
    origin = np.arange(N - hs[0]) if hs[0] < N else np.arange(0)
    x, dx = xf[origin].copy(), dxf[origin].copy()
    for step in range(1, min(hs[-1], N - 1) + 1):
        live = origin + step < N
        origin, x, dx = origin[live], x[live], dx[live]
        t = origin + step - 1
        F, dF = mats.Phi[which[t]], dmats.dPhi[which[t]]
        dx = np.einsum("mab,mqb->mqa", F, dx) + np.einsum("mqab,mb->mqa", dF, x) + ddrive[t]
        x = np.einsum("mab,mb->ma", F, x) + drive[t]
        if step not in hs:
            continue
        target = origin + step
        y_hat = x @ obs.C.T + u[target] @ obs.D.T
        dy = np.einsum("oa,mqa->mqo", obs.C, dx) + np.einsum("oqa,ma->mqo", obs.dC, x)
        dy += np.einsum("oqb,mb->mqo", obs.dD, u[target])
        e = y[target] - y_hat
        ok = np.isfinite(e)
        e0 = np.where(ok, e, 0.0)
        dy0 = np.where(ok[:, None, :], dy, 0.0)
        value += 0.5 * float(np.sum(e0**2))
        part = -np.einsum("mo,mqo->mq", e0, dy0)
        np.add.at(contrib, target, part)
        grad += part.sum(axis=0)
        gn += np.einsum("mqo,mpo->qp", dy0, dy0)
        count += int(ok.sum())
    return KStepCost(value, grad, gn, contrib, count)


def noise_scale(network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh") -> float:
    """The factor ``c`` on every noise level that maximizes the likelihood with the filter's gains fixed.

    Scaling every noise level (process, measurement, initial spread) by ``c`` leaves the gains and
    the predictions unchanged and scales every innovation variance by ``c^2``; the likelihood's
    maximum over ``c`` is ``c^2 = mean(e_j^2 / S_j)`` over the observed innovations.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Parameter values and noise levels.
    data : Dataset
    hold : {"zoh", "foh"}
    """
    from rczone.estimation.engines import run_filter

    out = run_filter(network, values, data, hold)
    z2 = out.innovations**2 / np.einsum("kii->ki", out.S)
    return math.sqrt(float(np.nanmean(z2)))


def sandwich_covariance(cost: KStepCost, lag: int) -> np.ndarray:
    """The estimates' covariance ``H^-1 V H^-1`` of the k-step criterion (theta units).

    ``H`` is the Gauss-Newton Hessian, ``V`` the Newey-West long-run covariance of the per-sample
    gradient contributions with a Bartlett window of ``lag`` samples (the longest horizon: k-step
    errors overlap over ``k`` samples).

    Parameters
    ----------
    cost : KStepCost
        At the estimate.
    lag : int
        Bartlett window, samples.
    """
    g = cost.contributions
    V = g.T @ g
    for ell in range(1, min(lag, g.shape[0] - 1) + 1):
        w = 1.0 - ell / (lag + 1.0)
        G = g[ell:].T @ g[:-ell]
        V += w * (G + G.T)
    H = cost.gauss_newton
    d = np.sqrt(np.where(np.diag(H) > 0, np.diag(H), 1.0))  # R and C differ by 10 decades: invert in scale
    Hi = np.linalg.pinv(H / np.outer(d, d)) / np.outer(d, d)
    return Hi @ V @ Hi
