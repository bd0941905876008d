"""Validation of a fitted model on data: open-loop error, k-step prediction, residual whiteness.

All results are data objects; plotting is elsewhere.

References
----------
.. [1] G. M. Ljung, G. E. P. Box, "On a measure of lack of fit in time series models",
   Biometrika 65 (1978) 297-303.
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall
   1999, section 16.6 (residual analysis) and 7.3 (k-step-ahead predictors).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import chdtrc

from rczone.errors import InputShapeError, ParameterError
from rczone.estimation.costs import (
    filter_arrays,
    initial_state,
    measured_states,
    network_theta,
    simulate_output,
)
from rczone.estimation.data import Dataset
from rczone.estimation.innovations import acf, ljung_box_q
from rczone.estimation.kalman import kalman_filter_arrays
from rczone.network import RCNetwork
from rczone.network.stochastic import initial_state_names
from rczone.simulation.simulate import propagate, transition_matrices


@dataclass(frozen=True, eq=False)
class OpenLoopError:
    """Open-loop simulation error on a data set.

    Attributes
    ----------
    t : ndarray, shape (N,)
    y_hat : ndarray, shape (N, ny)
    error : ndarray, shape (N, ny)
        ``y - y_hat`` (NaN where ``y`` is missing).
    rmse_K, max_abs_K : float
    """

    t: np.ndarray
    y_hat: np.ndarray
    error: np.ndarray
    rmse_K: float
    max_abs_K: float


def per_output_errors(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """RMSE and largest absolute error of each column of ``e`` (NaN entries skipped), K.

    A column without any finite entry gets NaN for both.
    """
    e = np.asarray(e, dtype=float)
    ok = np.isfinite(e)
    n = ok.sum(axis=0)
    sq = np.where(ok, e * e, 0.0)
    rmse = np.where(n > 0, np.sqrt(sq.sum(axis=0) / np.maximum(n, 1)), np.nan)
    worst = np.where(n > 0, np.where(ok, np.abs(e), -np.inf).max(axis=0), np.nan)
    return rmse, worst


def open_loop_error(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> OpenLoopError:
    """Simulate ``network`` with ``values`` (base parameters, optional ``x0_*``) on ``data``."""
    data.check_against(network)
    _, yhat = simulate_output(network, values, data, hold)
    if not np.all(np.isfinite(yhat)):
        k = int(np.flatnonzero(~np.isfinite(yhat).all(axis=1))[0])
        raise InputShapeError(
            f"the model's prediction is not finite from sample {k} on; its parameter values or inputs"
            " are not usable"
        )
    e = data.y - yhat
    return OpenLoopError(data.t, yhat, e, float(np.sqrt(np.nanmean(e**2))), float(np.nanmax(np.abs(e))))


#: Prior standard deviation (K) of an unmeasured node's initial temperature around its conditional
#: steady state, for a model without its own ``sigma_x0_<state>``.
INITIAL_STATE_PRIOR_K = 1.0


@dataclass(frozen=True)
class InitialStateEstimate:
    """Initial temperatures of a model's nodes estimated from the data it is to predict.

    Attributes
    ----------
    values : dict
        ``x0_<state>`` of every state: measured states at their first measurement, the others
        estimated.
    steady : dict
        The conditional steady state the unmeasured ones would otherwise start at (``x0_<state>``).
    sd : dict
        Posterior standard deviation of each estimated one (``x0_<state>``), K.
    """

    values: dict[str, float]
    steady: dict[str, float]
    sd: dict[str, float]


def estimate_initial_state(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    noise_sd: Sequence[float],
    prior_sd: Mapping[str, float],
    hold: str = "zoh",
) -> InitialStateEstimate:
    """The unmeasured nodes' initial temperatures that best explain the open-loop error.

    The open-loop output is affine in the initial state, so its response to each unmeasured
    node's initial temperature is exact from one simulation per node. The estimate is the
    maximum a posteriori one under the Gaussian prior ``N(x_ss, prior_sd^2)`` around the
    conditional steady state of :func:`~rczone.estimation.engines.auto_initial_state` and
    measurement errors of ``noise_sd`` per output, neglecting process noise: regularized linear
    least squares. The prior keeps directions the data do not determine (two boards of one wall
    moving in opposite directions) at the steady state. The open-loop error is mostly model error
    and accumulated process noise, not measurement noise, so a second pass weighs each output by
    the larger of ``noise_sd`` and the RMS error the first estimate leaves (the standard deviations
    stay optimistic where that error is autocorrelated). Estimating the initial condition of an
    open-loop simulation on validation data is the usual practice of model validation
    (Ljung 1999, section 16.6): a slow node's unknown starting temperature otherwise shows as a
    bias that lasts its time constant.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Base parameter values (``x0_*`` entries are ignored).
    data : Dataset
    noise_sd : sequence of float
        Standard deviation of each output's error around the simulation, K.
    prior_sd : mapping
        State name to the prior standard deviation of its initial temperature, K.
    """
    ss = network.state_space(network_theta(network, values))
    x_ss = initial_state(ss, {}, data)
    names = initial_state_names(ss.state_names)
    measured = measured_states(ss)
    free = [i for i in range(ss.n_states) if i not in measured]
    steady = {names[i]: float(x_ss[i]) for i in free}
    if not free:
        return InitialStateEstimate(dict(zip(names, map(float, x_ss), strict=True)), steady, {})
    # discretized once: the output from x_ss, and the response to each unit initial temperature
    # (inputs zero; the flows still set the matrices)
    Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, hold)
    y0 = propagate(Phi, G0, G1, which, data.u, x_ss) @ ss.C.T + data.u @ ss.D.T
    zero = np.zeros_like(data.u)
    eye = np.eye(ss.n_states)
    psi = np.stack(
        [propagate(Phi, G0, G1, which, zero, eye[i]) @ ss.C.T for i in free], axis=-1
    )  # (N, ny, k)
    p = np.array([1.0 / prior_sd[ss.state_names[i]] for i in free])
    level = np.asarray(noise_sd, dtype=float)
    for _ in range(2):  # the second pass weighs the outputs by what the start leaves unexplained
        w = 1.0 / level
        e = (data.y - y0) * w
        ok = np.isfinite(e)
        lhs = np.vstack([(psi * w[None, :, None])[ok], np.diag(p)])
        rhs = np.concatenate([e[ok], np.zeros(len(free))])
        delta = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
        rest = data.y - y0 - psi @ delta
        level = np.maximum(level, np.sqrt(np.nanmean(rest**2, axis=0)))
    cov = np.linalg.pinv(lhs.T @ lhs)
    x = x_ss.copy()
    x[free] += delta
    sd = {names[i]: float(math.sqrt(max(cov[j, j], 0.0))) for j, i in enumerate(free)}
    return InitialStateEstimate(dict(zip(names, map(float, x), strict=True)), steady, sd)


def open_loop_band(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh", *, known: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop prediction and its standard deviation from the model's noise levels.

    The Kalman filter of the stochastic model is run with every measurement after the first
    ``known`` ones removed (default: all but the first; a warm-up's length to start from the
    filter's estimate at its end): it conditions the state on them and then only predicts, so its
    mean is the open-loop simulation and its innovation covariance ``C P C' + R`` is the variance
    of the measurement around it (process noise accumulated since the start, plus measurement
    noise). ``values`` must hold the noise levels (``sigma_v``, ``sigma_w_*``, ``sigma_x0_*``).

    Returns
    -------
    y_hat : ndarray, shape (N, ny)
    sd : ndarray, shape (N, ny)
    """
    y = np.full_like(data.y, np.nan)
    y[:known] = data.y[:known]
    masked = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    arrays = filter_arrays(network, values, masked, hold)
    out = kalman_filter_arrays(arrays)
    y_hat = out.x_pred @ arrays.C.T + arrays.u @ arrays.D.T
    sd = np.sqrt(np.einsum("kii->ki", out.S))
    return y_hat, sd


@dataclass(frozen=True, eq=False)
class ResidualTest:
    """Autocorrelation of residuals and the Ljung-Box portmanteau test.

    Attributes
    ----------
    lags : ndarray of int, shape (L,)
    acf : ndarray, shape (L,)
        Sample autocorrelation at ``lags``.
    q_statistic : float
        ``Q = n (n + 2) sum_k r_k^2 / (n - k)``.
    p_value : float
        ``P(chi2(L - dof) > Q)``; small values reject whiteness.
    white_at_5pct : bool
    """

    lags: np.ndarray
    acf: np.ndarray
    q_statistic: float
    p_value: float
    white_at_5pct: bool


def ljung_box(residuals: np.ndarray, n_lags: int = 20, dof: int = 0) -> ResidualTest:
    """Ljung-Box test of whiteness of a residual series (NaNs dropped).

    Parameters
    ----------
    residuals : ndarray, shape (N,) or (N, 1)
    n_lags : int
        Number of lags ``L``.
    dof : int
        Degrees of freedom to subtract (e.g. number of fitted ARMA terms; 0 for
        Kalman innovations).
    """
    r = np.asarray(residuals, dtype=float).reshape(-1)
    r = r[np.isfinite(r)]
    n = r.size
    if not 0 < n_lags < n - 1:
        raise ParameterError(f"n_lags must be between 1 and n-2 = {n - 2}, got {n_lags}")
    if not 0 <= dof < n_lags:
        raise ParameterError(f"dof must be in [0, n_lags), got {dof}")
    r_k = acf(r, n_lags)[1:]
    q = ljung_box_q(r_k, n)
    p = float(chdtrc(n_lags - dof, q))  # chi2 survival function
    return ResidualTest(np.arange(1, n_lags + 1), r_k, q, p, p > 0.05)
