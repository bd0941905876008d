"""Predictions with uncertainty: k-step-ahead and open-loop, from the noise and the estimates' covariance.

Two sources of uncertainty are separated, as they answer different questions:

* **process and measurement noise** (the stochastic model of an ML fit): the Kalman filter's
  k-step prediction covariance ``C P_{j|j-k} C' + R``, where ``P_{j|j-k}`` propagates the filtered
  covariance ``k`` steps with the process noise. Open loop is the filter conditioned on the
  first measurement only (:func:`open_loop_band`);
* **the estimates' uncertainty**: the covariance ``Sigma`` of the fitted parameters carried to the
  prediction by linearization, ``var_theta(y_j) = J_j Sigma J_j'`` with ``J_j = d y_hat_j / d theta``
  by central differences of the predictor (first-order delta method [1]_).

The two are independent to first order, so the total variance is their sum.

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 9.6 (variance of the estimated model's output) and 7.3 (k-step-ahead predictors).
.. [2] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007, section 10.3 (k-step prediction
   with the Kalman filter).
.. [3] S. Saerkkae, *Bayesian Filtering and Smoothing*, Cambridge University Press 2013,
   chapters 4 and 8 (Kalman filter and Rauch-Tung-Striebel smoother).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.costs import filter_arrays
from rczone.estimation.data import Dataset
from rczone.estimation.kalman import input_drive, kalman_filter_arrays
from rczone.kernels.arrays import writable
from rczone.kernels.forecast import Origins, Propagation, Readout, k_step_moments
from rczone.network import RCNetwork

#: Central-difference step of the parameter sensitivities, in standard errors.
SENSITIVITY_STEP = 0.01


class Band(NamedTuple):
    """A prediction and its standard deviation, each of shape (N, ny) (NaN where there is none)."""

    y_hat: np.ndarray
    sd: np.ndarray


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


def _check_steps(k: object) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ParameterError(f"k must be a positive integer (steps ahead), got {k!r}")
    return int(k)


def k_step_bands(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    steps: Sequence[int],
    hold: str = "zoh",
    *,
    origins: np.ndarray | None = None,
) -> dict[int, Band]:
    """k-step-ahead predictions ``y_hat[j | j - k]`` and their noise standard deviations, for several k.

    One Kalman filter pass: the filtered state and covariance at every origin ``j - k`` are
    propagated with the known inputs and the process noise, and read off after each requested
    number of steps (the k-step predictor from the filtered state, Madsen 2007, section 10.3).
    ``values`` must hold the noise levels. The first ``k`` samples have no k-step prediction (NaN).

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Parameter values and noise levels.
    data : Dataset
    steps : sequence of int
        Steps ahead, each a positive integer.
    hold : {"zoh", "foh"}
        Inputs between samples.
    origins : ndarray of int, optional
        Predict only from these samples (increasing indices; the other targets stay NaN), to bound
        the memory of the propagated covariances on long records. Default every sample.

    Returns
    -------
    dict
        Steps ahead to :class:`Band`.
    """
    ks = sorted({_check_steps(k) for k in steps})
    data.check_against(network)
    args = filter_arrays(network, values, data, hold)
    Phi, Qd, which, u, y, C, R = args.Phi, args.Qd, args.which, args.u, args.y, args.C, args.R
    out = kalman_filter_arrays(args)
    N = y.shape[0]
    bands = {k: Band(np.full(y.shape, np.nan), np.full(y.shape, np.nan)) for k in ks}
    reach = [k for k in ks if k < N]
    if not reach:
        return bands
    drive = input_drive(args.G0, args.G1, which, u)
    origin = np.arange(N) if origins is None else np.asarray(origins, dtype=int)
    origin = origin[(origin >= 0) & (origin < N - reach[0])].astype(np.int64)
    slot = np.full(reach[-1] + 1, -1, dtype=np.int64)
    slot[reach] = np.arange(len(reach))
    c = writable  # one array type (np.diag of one output is a read-only view): one specialization
    y_hat, var = k_step_moments(
        Propagation(c(Phi), c(Qd), c(which, np.int64), c(drive)),
        Readout(c(C), c(u @ args.D.T), c(np.diag(R))),
        Origins(c(out.x_filt), c(out.P_filt), c(origin, np.int64), c(slot, np.int64)),
    )
    for j, k in enumerate(reach):
        bands[k] = Band(y_hat[j], np.sqrt(var[j]))
    return bands


def k_step_band(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, k: int, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray]:
    """k-step-ahead prediction ``y_hat[j | j - k]`` and its standard deviation from the noise.

    The filtered state and covariance at ``j - k`` are propagated ``k`` intervals with the known
    inputs and the process noise (:func:`k_step_bands` for one ``k``); ``values`` must hold the
    noise levels. The first ``k`` samples have no prediction (NaN).

    Returns
    -------
    y_hat, sd : ndarray, shape (N, ny)
    """
    k = _check_steps(k)
    return tuple(k_step_bands(network, values, data, [k], hold)[k])


def noise_band(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    k: int | None = None,
    hold: str = "zoh",
    *,
    known: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """Prediction and its noise standard deviation: ``k`` steps ahead, or open loop (``k=None``).

    Open loop, the filter uses the first ``known`` measurements (a warm-up) and then only predicts.
    """
    if k is None:
        return open_loop_band(network, values, data, hold, known=known)
    return k_step_band(network, values, data, k, hold)


def parameter_sd(
    predict: Callable[[Mapping[str, float]], np.ndarray],
    values: Mapping[str, float],
    names: Sequence[str],
    cov: np.ndarray,
) -> np.ndarray:
    """Standard deviation of a prediction due to the estimates' covariance (delta method).

    Parameters
    ----------
    predict : callable
        Values (every parameter the predictor needs) to the prediction, shape (N, ny).
    values : mapping
        The estimates and the other values ``predict`` needs.
    names : sequence of str
        Parameters the covariance is over (physical units).
    cov : ndarray, shape (d, d)
        Their covariance; a parameter with a NaN variance (held at a bound) counts as known.

    Returns
    -------
    ndarray, shape (N, ny)
        ``sqrt(J Sigma J')`` per sample and output, with ``J`` by central differences of
        :data:`SENSITIVITY_STEP` standard errors.
    """
    cov = np.asarray(cov, dtype=float)
    d = len(names)
    if cov.shape != (d, d):
        raise ParameterError(f"the covariance must be ({d}, {d}) for {list(names)}, got {cov.shape}")
    var = np.diag(cov)
    use = [i for i in range(d) if math.isfinite(var[i]) and var[i] > 0]
    base = predict(values)
    if not use:
        return np.zeros_like(base)
    J = np.empty((*base.shape, len(use)))
    for col, i in enumerate(use):
        name = names[i]
        h = SENSITIVITY_STEP * math.sqrt(var[i])
        v0 = values[name]
        if v0 > 0:  # resistances, capacities, noise levels stay positive
            h = min(h, 0.5 * v0)
        up = predict({**values, name: v0 + h})
        down = predict({**values, name: v0 - h})
        J[..., col] = (up - down) / (2 * h)
    sub = cov[np.ix_(use, use)]
    sub = np.where(np.isfinite(sub), sub, 0.0)
    v = np.einsum("...i,ij,...j->...", J, sub, J)
    return np.sqrt(np.maximum(v, 0.0))


#: Two-sided probability of the posterior predictive band: that of plus or minus two standard deviations.
TWO_SIGMA = math.erf(2.0 / math.sqrt(2.0))


def posterior_band(
    band: Callable[[Mapping[str, float]], tuple[np.ndarray, np.ndarray]],
    values: Mapping[str, float],
    names: Sequence[str],
    draws: np.ndarray,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A posterior predictive band: each draw pushed through the predictor, its noise added, quantiles.

    For each posterior draw ``theta_k`` the predictor gives the mean ``y_k`` and the noise's standard
    deviation ``s_k``; ``y_k + s_k eps`` (``eps`` standard normal) is a draw of the posterior
    predictive distribution, and the band is its equal-tailed :data:`TWO_SIGMA` interval at each
    sample (Gelman et al. 2013, sec. 6.3). Unlike :func:`parameter_sd`, nothing is linearized.

    Parameters
    ----------
    band : callable
        Values (every parameter the predictor needs) to ``(mean, sd)``, each of shape (N, ny);
        a NaN ``sd`` counts as no noise.
    values : mapping
        The other values ``band`` needs (the draws replace those in ``names``).
    names : sequence of str
        The parameters of the draws' columns.
    draws : ndarray, shape (k, len(names))
        Posterior draws, physical units.
    rng : numpy.random.Generator
        Draws the noise.

    Returns
    -------
    lower, upper : ndarray, shape (N, ny)
        The band.
    sd_parameters : ndarray, shape (N, ny)
        The standard deviation of the means ``y_k`` over the draws: the estimates' part.

    References
    ----------
    Gelman, A., Carlin, J. B., Stern, H. S., Dunson, D. B., Vehtari, A. & Rubin, D. B. (2013).
    *Bayesian Data Analysis*, 3rd ed. CRC Press.
    """
    draws = np.asarray(draws, dtype=float)
    if draws.ndim != 2 or draws.shape[1] != len(names) or draws.shape[0] < 2:
        raise ParameterError(f"draws must be (k >= 2, {len(names)}) for {list(names)}, got {draws.shape}")
    means, predictive = [], []
    for row in draws:
        y, sd = band({**values, **dict(zip(names, map(float, row)))})
        sd = np.where(np.isfinite(sd), sd, 0.0)
        means.append(y)
        predictive.append(y + sd * rng.standard_normal(y.shape))
    tail = (1.0 - TWO_SIGMA) / 2.0
    lower, upper = np.quantile(np.array(predictive), [tail, 1.0 - tail], axis=0)
    return lower, upper, np.std(np.array(means), axis=0, ddof=1)
