"""Conformal bands per horizon: split conformal on a calibration window, adaptive conformal online.

The Kalman filter's k-step band is the model's own extrapolation of its noise; a misspecified
model's errors outgrow it (docs/validation.md). A conformal band keeps the model's shape (its
k-step standard deviation ``s``, which varies with the inputs and the filter's uncertainty) and
replaces the factor 2 by a quantile of the *standardized* k-step errors ``|y - y_hat| / s`` on
samples the fit did not use:

* **split conformal** [1]_: on a calibration window (the last part of the data before the
  scored samples), per horizon ``k`` and output, ``q_k`` is the ``ceil((n + 1)(1 - alpha))``-th
  smallest of the ``n`` scores; if the scored errors are exchangeable with the window's, the band
  ``y_hat -+ q_k s`` holds them with probability at least ``1 - alpha``. One quantile per horizon
  is the multi-horizon scheme of [2]_ without its Bonferroni correction (the coverage asked for
  is per horizon, not of the whole trajectory);
* **adaptive conformal inference** (ACI, [3]_): while predicting, the level is updated after
  every error that becomes known, ``alpha_{t+1} = alpha_t + (gamma / k)(alpha - err_t)``
  (``err_t`` = 1 when the measurement fell outside its band), and the quantile is taken of the
  ``n`` most recent scores known at the prediction's origin. A k-step band for target ``t`` is
  issued at ``t - k``, so it uses the level and scores as they were after target ``t - k``. The
  step is divided by ``k`` because k-step errors overlap and come in runs of about ``k``: with the
  paper's ``gamma`` a run of misses drove the level below zero and the band to infinity on the
  Bacher & Madsen house at 1 h and longer (docs/validation.md). Whatever the data, the long-run
  share of misses is within ``(max(alpha_1, 1 - alpha_1) + gamma / k) / (gamma T / k)`` of
  ``alpha`` ([3]_, Proposition 4.1, with the step ``gamma / k``); a level below what ``n`` scores
  resolve gives an infinite band, as in [3]_ (counted, never hidden).

The interval score [4]_, ``(u - l) + (2 / alpha)(l - y) 1{y < l} + (2 / alpha)(y - u) 1{y > u}``
(K), is reported beside the coverage: it rewards a narrow band and punishes a miss by its
distance, so a band that covers only because it is wide scores badly.

References
----------
.. [1] V. Vovk, A. Gammerman, G. Shafer, *Algorithmic Learning in a Random World*, Springer 2005,
   chapter 4 (inductive conformal prediction).
.. [2] K. Stankeviciute, A. M. Alaa, M. van der Schaar, "Conformal time-series forecasting",
   Advances in Neural Information Processing Systems 34 (2021).
.. [3] I. Gibbs, E. J. Candes, "Adaptive conformal inference under distribution shift", Advances
   in Neural Information Processing Systems 34 (2021).
.. [4] T. Gneiting, A. E. Raftery, "Strictly proper scoring rules, prediction, and estimation",
   Journal of the American Statistical Association 102 (2007) 359-378, section 6.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rczone.calibration.bands import TWO_SIGMA_COVERAGE
from rczone.errors import DataError, ParameterError

#: Nominal miss rate of the conformal band: that of a 2-sigma normal band, so coverages compare.
ALPHA = 1.0 - TWO_SIGMA_COVERAGE

#: Default step of the adaptive level (Gibbs & Candes 2021 use 0.005).
GAMMA = 0.005

#: Fewest calibration scores a horizon's quantile is computed from.
MIN_SCORES = 20


@dataclass(frozen=True)
class ConformalSettings:
    """How a conformal band is calibrated.

    Attributes
    ----------
    window_s : float
        Length of the calibration window, s: the samples just before the first scored one.
    online : bool
        Update the band while predicting (adaptive conformal inference).
    gamma : float
        Step of the adaptive level at one step ahead (``gamma / k`` at ``k`` steps).
    alpha : float
        Nominal miss rate (default that of a 2-sigma band).
    """

    window_s: float
    online: bool = False
    gamma: float = GAMMA
    alpha: float = ALPHA

    def __post_init__(self) -> None:
        if not (math.isfinite(self.window_s) and self.window_s > 0):
            raise ParameterError(
                f"the conformal calibration window must be a positive duration, got {self.window_s!r} s"
            )
        if not 0 < self.alpha < 1:
            raise ParameterError(f"alpha must lie between 0 and 1, got {self.alpha!r}")
        if not 0 < self.gamma < 1:
            raise ParameterError(f"gamma (the adaptive step) must lie between 0 and 1, got {self.gamma!r}")

    def describe(self) -> str:
        """The band's source in words."""
        hours = self.window_s / 3600.0
        what = f"split conformal quantiles of the k-step standardized errors over the last {hours:g} h before the scored samples"
        if self.online:
            what += f", updated online (adaptive conformal inference, step {self.gamma:g})"
        return what


def conformal_quantile(scores: np.ndarray, alpha: float) -> float:
    """The ``ceil((n + 1)(1 - alpha))``-th smallest of the finite ``scores`` (inf beyond the ``n``-th).

    Parameters
    ----------
    scores : ndarray
        Nonconformity scores (NaN skipped).
    alpha : float
        Miss rate; at or below 0 the quantile is infinite, at or above 1 it is 0.

    Returns
    -------
    float
    """
    s = np.sort(np.asarray(scores, dtype=float)[np.isfinite(scores)])
    if alpha >= 1.0:
        return 0.0
    rank = math.ceil((s.size + 1) * (1.0 - alpha))
    if alpha <= 0.0 or rank > s.size:
        return math.inf
    return float(s[max(rank, 1) - 1])


def interval_score(y: np.ndarray, lower: np.ndarray, upper: np.ndarray, alpha: float) -> np.ndarray:
    """Gneiting & Raftery's interval score of the central ``1 - alpha`` band per sample (K; NaN where no measurement).

    Parameters
    ----------
    y, lower, upper : ndarray
        Measurements and the band's ends, same shape.
    alpha : float
        The band's nominal miss rate.
    """
    y, lo, hi = (np.asarray(a, dtype=float) for a in (y, lower, upper))
    with np.errstate(invalid="ignore"):
        below = np.where(y < lo, lo - y, 0.0)
        above = np.where(y > hi, y - hi, 0.0)
        out = (hi - lo) + (2.0 / alpha) * (below + above)
    return np.where(np.isfinite(y), out, np.nan)


@dataclass(frozen=True, eq=False)
class ConformalBand:
    """A conformal band's half-widths per horizon, sample and output, and how it was made.

    Attributes
    ----------
    half_width : ndarray, shape (H, N, ny)
        ``q s`` per horizon, sample and output (inf where the adaptive level asks more than the
        scores resolve; NaN where there is no prediction).
    quantile : ndarray, shape (H, ny)
        The split-conformal quantile of the calibration window (NaN: too few scores).
    online_quantile : ndarray, shape (H, N, ny) or None
        The adaptive quantile used at each target (None without the online update).
    recent_quantile : ndarray, shape (H, N, ny) or None
        The quantile at the nominal level of the scores the adaptive one is taken over.
    n_calibration : ndarray of int, shape (H, ny)
        Scores in the calibration window.
    settings : ConformalSettings
    """

    half_width: np.ndarray
    quantile: np.ndarray
    online_quantile: np.ndarray | None
    recent_quantile: np.ndarray | None
    n_calibration: np.ndarray
    settings: ConformalSettings

    def widening(self) -> np.ndarray | None:
        """The recent errors' quantile over the calibration one, shape (H, N, ny) (None without the online update).

        At the nominal level, not ACI's adapted one: the level swings after a run of misses
        (k-step errors come in runs) even when nothing changed, the errors' quantile does not.
        """
        if self.recent_quantile is None:
            return None
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.recent_quantile / self.quantile[:, None, :]

    def to_dict(self) -> dict:
        """JSON-ready: the settings and the calibration quantile per horizon and output."""
        from rczone.results.protocol import json_number

        return {
            "window_s": self.settings.window_s,
            "online": self.settings.online,
            "gamma": self.settings.gamma,
            "alpha": self.settings.alpha,
            "quantile": [[json_number(v) for v in row] for row in self.quantile],
            "n_calibration": self.n_calibration.tolist(),
            "infinite_samples": int(np.isinf(self.half_width).sum()),
        }


class OnlineQuantiles(NamedTuple):
    """The online quantiles of one horizon and output, shape (N,) each (NaN before the first target).

    Attributes
    ----------
    adaptive : ndarray
        ACI's: the recent scores' quantile at the adapted level (the band).
    nominal : ndarray
        The recent scores' quantile at the nominal level: how the errors themselves moved, free of
        the level's swings (what :mod:`rczone.calibration.drift` watches).
    """

    adaptive: np.ndarray
    nominal: np.ndarray


def adaptive_quantiles(
    scores: np.ndarray, first: int, steps: int, calibration: int, settings: ConformalSettings
) -> OnlineQuantiles:
    """ACI's quantile for every target from ``first`` on, and the nominal one of the same scores.

    Parameters
    ----------
    scores : ndarray, shape (N,)
        Standardized absolute errors ``|y - y_hat| / s`` (NaN where none).
    first : int
        Index of the first scored target; the ``calibration`` finite scores before it start the window.
    steps : int
        Horizon: the band of target ``t`` is issued at ``t - steps`` and uses what was known then.
    calibration : int
        Number of scores the quantile is taken over (the most recent ones known).
    settings : ConformalSettings
    """
    N = scores.shape[0]
    known = [float(v) for v in scores[:first] if math.isfinite(v)][-calibration:]
    q = np.full(N, np.nan)
    nominal = np.full(N, np.nan)
    level = np.full(N, settings.alpha)  # the level after each target's feedback
    window_at = np.zeros(N, dtype=int)  # scores known after target t: known[:window_at[t]]
    start_level, start_len = settings.alpha, len(known)
    for t in range(first, N):
        origin = t - steps
        a = level[origin] if origin >= first else start_level
        n_known = window_at[origin] if origin >= first else start_len
        recent = np.asarray(known[max(0, n_known - calibration) : n_known])
        q[t] = conformal_quantile(recent, a)
        nominal[t] = conformal_quantile(recent, settings.alpha)
        previous = level[t - 1] if t > first else start_level
        s = scores[t]
        if math.isfinite(s):
            miss = 1.0 if s > q[t] else 0.0
            level[t] = previous + settings.gamma / steps * (settings.alpha - miss)
            known.append(float(s))
        else:
            level[t] = previous
        window_at[t] = len(known)
    return OnlineQuantiles(q, nominal)


def conformal_band(
    error: np.ndarray,
    sd: np.ndarray,
    steps: tuple,
    first: int,
    window: int,
    settings: ConformalSettings,
) -> ConformalBand:
    """The conformal band of every horizon from the model's errors and standard deviations.

    Parameters
    ----------
    error : ndarray, shape (H, N, ny)
        ``y - y_hat`` per horizon (NaN where no prediction or measurement).
    sd : ndarray, shape (H, N, ny)
        The model's standard deviation of each prediction.
    steps : tuple
        Steps ahead per horizon (None: open loop, left uncalibrated: the samples before the scored
        ones are filtered there, not predicted, so they give no open-loop errors).
    first : int
        Index of the first scored sample; the calibration window is ``[first - window, first)``.
    window : int
        Samples in the calibration window.
    settings : ConformalSettings

    Returns
    -------
    ConformalBand
    """
    H, N, ny = error.shape
    if first < 1:
        raise DataError(
            "a conformal band needs a calibration window before the scored samples; give --warmup"
        )
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.abs(error) / sd
    z[~np.isfinite(z)] = np.nan
    lo = max(0, first - window)
    quantile = np.full((H, ny), np.nan)
    count = np.zeros((H, ny), dtype=int)
    online = np.full((H, N, ny), np.nan) if settings.online else None
    recent = np.full((H, N, ny), np.nan) if settings.online else None
    for h in range(H):
        for j in range(ny):
            cal = z[h, lo:first, j]
            count[h, j] = int(np.isfinite(cal).sum())
            if count[h, j] < MIN_SCORES or steps[h] is None:
                continue
            quantile[h, j] = conformal_quantile(cal, settings.alpha)
            if online is not None:
                online[h, :, j], recent[h, :, j] = adaptive_quantiles(
                    z[h, :, j], first, steps[h], count[h, j], settings
                )
    use = online if online is not None else np.broadcast_to(quantile[:, None, :], (H, N, ny))
    with np.errstate(invalid="ignore"):
        half = np.where(np.isfinite(sd), use * sd, np.nan)
    half[:, :first] = np.nan
    return ConformalBand(half, quantile, online, recent, count, settings)
