"""A fitted model on data: its open-loop error and the whiteness of residuals.

All results are data objects; plotting is elsewhere. The open-loop prediction with its band and the
initial state it starts from are predictions (:mod:`rczone.estimation.forecast`,
:mod:`rczone.estimation.initial`).

References
----------
.. [1] G. M. Ljung, G. E. P. Box, "On a measure of lack of fit in time series models",
   Biometrika 65 (1978) 297-303.
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall
   1999, section 16.6 (residual analysis).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.special import chdtrc

from rczone.errors import InputShapeError, ParameterError
from rczone.estimation.costs import simulate_output
from rczone.estimation.data import Dataset
from rczone.network import RCNetwork
from rczone.postfit.innovations import acf, ljung_box_q


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
