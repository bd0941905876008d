"""Residual analysis of a fitted model: one-step innovations and their whiteness.

A stochastic grey-box model is adequate when its one-step-ahead prediction errors (the Kalman
filter's *innovations*) are white: what the model could predict from the past, it predicted;
what is left is new at every sample. A model that misses a state or an input leaves structure
in them, which shows as autocorrelation, as a cumulative periodogram that leaves the straight
line of white noise, and as correlation with past inputs. The open-loop error of a simulation
is a different thing: it accumulates the process noise and is never white, even for the true
model, so its whiteness carries no information about the model structure (it is reported, and
labelled, for least-squares fits, which have no innovations).

Every statistic is computed per output (a model with several outputs has one innovation
sequence per output, each standardized by its own innovation variance ``S_jj``):

* standardized innovations ``e_k / sqrt(S_k,jj)``, N(0, 1) and independent for a correct model;
* the sample autocorrelation (biased estimator, mean removed; missing samples are left out of
  the products and the divisor is the number of observed samples, as statsmodels'
  ``acf(..., missing="conservative")``), with the band ``+-1.96 / sqrt(n)`` of white noise;
* the Ljung-Box portmanteau statistic ``Q = n (n + 2) sum_k r_k^2 / (n - k)`` [1]_ over the first
  :data:`LJUNG_BOX_LAGS` lags, ``chi2(L)`` under whiteness (no degrees of freedom are subtracted:
  the innovations are not the residuals of a fitted ARMA model);
* the normalized cumulative periodogram ``C(f_j) = sum_{i<=j} I(f_i) / sum_i I(f_i)`` at the
  Fourier frequencies, which for white noise follows the line ``2 f`` (``f`` in cycles per
  sample), with the 95 % Kolmogorov-Smirnov band ``+-1.358 / (sqrt(q) + 0.12 + 0.11 / sqrt(q))``
  [2]_ [3]_;
* the cross-correlation ``corr(e_{k}, u_{k - l})`` with each input ``u`` at lags ``l >= 0`` (the
  input leading). Under whiteness of ``e`` its standard error is ``1 / sqrt(n)`` whatever the
  input's own autocorrelation (Bartlett's formula with one white series [4]_), so the same band
  applies; negative lags are not used because feedback (a thermostat reacting to the room)
  correlates the innovations with *future* inputs in a correct model.

References
----------
.. [1] G. M. Ljung, G. E. P. Box, "On a measure of lack of fit in time series models",
   Biometrika 65 (1978) 297-303.
.. [2] G. E. P. Box, G. M. Jenkins, G. C. Reinsel, *Time Series Analysis: Forecasting and
   Control*, 4th ed., Wiley 2008, section 8.2.6 (the cumulative periodogram check).
.. [3] M. A. Stephens, "EDF statistics for goodness of fit and some comparisons", J. Am. Stat.
   Assoc. 69 (1974) 730-737 (the modified Kolmogorov-Smirnov critical value).
.. [4] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 16.6 (residual analysis: whiteness and independence of past inputs).
.. [5] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007, section 6.4 (model checking of
   the one-step prediction errors).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import chdtrc

from rczone.errors import ParameterError
from rczone.estimation.costs import run_filter
from rczone.estimation.data import Dataset
from rczone.network import RCNetwork

#: Lags of the Ljung-Box test (fewer when the series is short: at most a fifth of its length).
LJUNG_BOX_LAGS = 20
#: Time span the autocorrelation and cross-correlations are shown over, s.
CORRELATION_SPAN_S = 6 * 3600.0
#: Level of every test and band.
ALPHA = 0.05
#: Two-sided normal quantile of :data:`ALPHA`.
Z_BAND = 1.959963984540054


# ----------------------------------------------------------------------------- statistics
def _centered(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean-removed series with missing samples set to 0, and the mask of observed samples."""
    x = np.asarray(x, dtype=float).reshape(-1)
    ok = np.isfinite(x)
    if ok.sum() < 3:
        raise ParameterError(f"a residual series needs at least 3 observed samples, got {int(ok.sum())}")
    xo = np.where(ok, x - x[ok].mean(), 0.0)
    return xo, ok


def acf(x: np.ndarray, n_lags: int) -> np.ndarray:
    """Sample autocorrelation at lags ``0..n_lags`` (biased, mean removed, NaN-aware).

    Parameters
    ----------
    x : ndarray, shape (N,)
        NaN marks a missing sample (left out of every product; the divisor is the number of
        observed samples).
    n_lags : int
        Largest lag, ``0 < n_lags < N``.

    Returns
    -------
    ndarray, shape (n_lags + 1,)
        ``r_0 = 1``.
    """
    xo, _ = _centered(x)
    if not 0 < n_lags < xo.size:
        raise ParameterError(f"n_lags must be between 1 and {xo.size - 1}, got {n_lags}")
    c = _lagged_products(xo, xo, n_lags)
    if c[0] == 0:
        raise ParameterError("the residuals are constant; their autocorrelation is undefined")
    return c / c[0]


def ccf(x: np.ndarray, u: np.ndarray, n_lags: int) -> np.ndarray | None:
    """Cross-correlation ``corr(x_k, u_{k-l})`` at lags ``l = 0..n_lags`` (``u`` leading).

    Biased estimator, both series mean removed; NaN in ``x`` marks a missing sample. Returns
    None when ``u`` is constant over the observed samples (no correlation is defined).
    """
    xo, ok = _centered(x)
    u = np.asarray(u, dtype=float).reshape(-1)
    if u.shape != xo.shape:
        raise ParameterError(f"x and u must have the same length, got {xo.size} and {u.size}")
    uo = np.where(ok, u - u[ok].mean(), 0.0)
    su, sx = math.sqrt(float(uo @ uo)), math.sqrt(float(xo @ xo))
    if su <= 1e-12 * max(1.0, float(np.abs(u[ok]).max())) * math.sqrt(ok.sum()) or sx == 0:
        return None
    return _lagged_products(xo, uo, n_lags) / (sx * su)


def _lagged_products(x: np.ndarray, u: np.ndarray, n_lags: int) -> np.ndarray:
    """``sum_j x[j + l] u[j]`` for ``l = 0..n_lags``: one matrix product over lagged windows of ``x``."""
    n = x.size
    windows = np.lib.stride_tricks.sliding_window_view(np.concatenate([x, np.zeros(n_lags)]), n)
    return windows[: n_lags + 1] @ u


def ljung_box_q(r: np.ndarray, n: int) -> float:
    """``Q = n (n + 2) sum_{k=1..L} r_k^2 / (n - k)`` from autocorrelations ``r`` at lags ``1..L``."""
    r = np.asarray(r, dtype=float)
    k = np.arange(1, r.size + 1)
    return float(n * (n + 2) * np.sum(r**2 / (n - k)))


def ljung_box_lags(n: int) -> int:
    """The number of Ljung-Box lags for ``n`` observed samples: 20, at most a fifth of ``n``."""
    return max(1, min(LJUNG_BOX_LAGS, n // 5))


@dataclass(frozen=True, eq=False)
class CumulativePeriodogram:
    """The normalized cumulative periodogram and its Kolmogorov-Smirnov check.

    Attributes
    ----------
    freq : ndarray, shape (q,)
        Fourier frequencies ``j / n``, cycles per sample, ``j = 1..q`` with ``q = (n - 1) // 2``.
    cumulative : ndarray, shape (q,)
        ``C(f_j)``; ends at 1.
    band : float
        Half-width of the 95 % band around the white-noise line ``2 f``.
    max_deviation : float
        ``max_j |C(f_j) - 2 f_j|`` (the Kolmogorov-Smirnov statistic).
    """

    freq: np.ndarray
    cumulative: np.ndarray
    band: float
    max_deviation: float

    @property
    def inside_band(self) -> bool:
        """Whether the periodogram stays inside the band (consistent with white noise)."""
        return self.max_deviation <= self.band

    def periods_s(self, dt_s: float) -> np.ndarray:
        """The period of each frequency, s, for samples ``dt_s`` apart."""
        return dt_s / self.freq


def cumulative_periodogram(x: np.ndarray) -> CumulativePeriodogram:
    """The cumulative periodogram of a series (missing samples dropped, mean removed).

    The periodogram ``I(f_j) = |sum_k x_k e^{-2 pi i f_j k}|^2 / n`` at the Fourier frequencies
    ``f_j = j / n``, ``j = 1..(n - 1) // 2`` (the zero frequency carries the mean and the Nyquist
    frequency of an even ``n`` is left out, as in Box, Jenkins & Reinsel), normalized and summed.
    """
    x = np.asarray(x, dtype=float).reshape(-1)
    x = x[np.isfinite(x)]
    n = x.size
    q = (n - 1) // 2
    if q < 2:
        raise ParameterError(f"the cumulative periodogram needs at least 5 observed samples, got {n}")
    power = np.abs(np.fft.rfft(x - x.mean())[1 : q + 1]) ** 2 / n
    total = float(power.sum())
    if total == 0:
        raise ParameterError("the residuals are constant; their periodogram is undefined")
    freq = np.arange(1, q + 1) / n
    c = np.cumsum(power) / total
    # the band is on the q - 1 ordinates before the last, which is 1 by construction
    m = q - 1
    band = 1.358 / (math.sqrt(m) + 0.12 + 0.11 / math.sqrt(m))
    line = np.arange(1, q + 1) / q
    return CumulativePeriodogram(freq, c, float(band), float(np.max(np.abs(c - line))))


# ----------------------------------------------------------------------------- per output
@dataclass(frozen=True, eq=False)
class OutputResiduals:
    """Whiteness statistics of one output's residual series.

    Attributes
    ----------
    output : str
    residuals : ndarray, shape (N,)
        The residuals, K (NaN where the output is not measured).
    standardized : ndarray, shape (N,)
        Innovations divided by their predicted standard deviation (open-loop errors: by their RMS).
    n : int
        Observed samples.
    acf : ndarray, shape (L + 1,)
        Autocorrelation at lags ``0..L``.
    q_statistic, p_value : float
        Ljung-Box over the first ``lb_lags`` lags.
    lb_lags : int
    periodogram : CumulativePeriodogram
    ccf : dict of str to ndarray or None
        Cross-correlation with each input at lags ``0..L`` (None for a constant input).
    """

    output: str
    residuals: np.ndarray
    standardized: np.ndarray
    n: int
    acf: np.ndarray
    q_statistic: float
    p_value: float
    lb_lags: int
    periodogram: CumulativePeriodogram
    ccf: Mapping[str, np.ndarray | None]

    @property
    def band(self) -> float:
        """Half-width of the 95 % band of a white series' correlations, ``1.96 / sqrt(n)``."""
        return Z_BAND / math.sqrt(self.n)

    @property
    def white(self) -> bool:
        """Ljung-Box does not reject whiteness at 5 %."""
        return self.p_value >= ALPHA

    def worst_input(self) -> tuple[str, float, int] | None:
        """``(input, |ccf|, lag)`` of the largest cross-correlation, or None without inputs."""
        best = None
        for name, r in self.ccf.items():
            if r is None:
                continue
            k = int(np.argmax(np.abs(r)))
            if best is None or abs(r[k]) > best[1]:
                best = (name, float(abs(r[k])), k)
        return best


@dataclass(frozen=True, eq=False)
class ResidualAnalysis:
    """Whiteness of a fit's residuals, per output.

    Attributes
    ----------
    kind : {"innovations", "open-loop"}
        One-step-ahead innovations of the Kalman filter (ML, MAP), or the open-loop simulation
        error (LS; never white, reported for what it shows).
    t : ndarray, shape (N,)
        Sample times, s.
    dt_s : float
        Median sample interval, s (lags and periods in hours use it).
    outputs : tuple of OutputResiduals
    """

    kind: str
    t: np.ndarray
    dt_s: float
    outputs: tuple[OutputResiduals, ...]

    @property
    def lags(self) -> np.ndarray:
        """Lags ``0..L`` in samples."""
        return np.arange(self.outputs[0].acf.size)

    @property
    def lags_h(self) -> np.ndarray:
        """Lags ``0..L`` in hours."""
        return self.lags * self.dt_s / 3600.0

    @property
    def ljung_box_p(self) -> float:
        """Ljung-Box p-value, Bonferroni-corrected over outputs (``min(1, ny min_j p_j)``)."""
        return min(1.0, len(self.outputs) * min(o.p_value for o in self.outputs))

    @property
    def white(self) -> bool:
        """No output's residuals reject whiteness (at 5 % overall, Bonferroni over outputs)."""
        return self.ljung_box_p >= ALPHA

    @property
    def note(self) -> str:
        if self.kind == "innovations":
            return (
                "one-step-ahead innovations of the Kalman filter, standardized; white for an adequate"
                " model (Ljung-Box p >= 0.05, periodogram inside its band, no correlation with past inputs)"
            )
        return (
            "open-loop simulation errors: they accumulate the process noise and are not expected to be"
            " white even for the true model; fit by ML to test the model structure on its innovations"
        )

    def to_dict(self) -> dict:
        """JSON-ready summary (the autocorrelation with its lags in hours; no long series)."""
        outs = {}
        for o in self.outputs:
            band = o.band
            ccf = {}
            for name, r in o.ccf.items():
                if r is None:
                    ccf[name] = None
                    continue
                k = int(np.argmax(np.abs(r)))
                ccf[name] = {
                    "max_abs": float(abs(r[k])),
                    "lag_h_of_max": float(k * self.dt_s / 3600.0),
                    "fraction_outside_band": float(np.mean(np.abs(r) > band)),
                }
            outs[o.output] = {
                "n": o.n,
                "mean_K": float(np.nanmean(o.residuals)),
                "std_K": float(np.nanstd(o.residuals)),
                "ljung_box_q": o.q_statistic,
                "ljung_box_p": o.p_value,
                "ljung_box_lags": o.lb_lags,
                "white": o.white,
                "acf": {
                    "lag_h": self.lags_h.tolist(),
                    "value": o.acf.tolist(),
                    "band": band,
                    "fraction_outside_band": float(np.mean(np.abs(o.acf[1:]) > band)),
                },
                "cumulative_periodogram": {
                    "max_deviation": o.periodogram.max_deviation,
                    "band": o.periodogram.band,
                    "inside_band": o.periodogram.inside_band,
                },
                "cross_correlation": ccf,
            }
        return {
            "kind": self.kind,
            "note": self.note,
            "ljung_box_p": self.ljung_box_p,
            "white": self.white,
            "outputs": outs,
        }


def analyse_residuals(
    residuals: np.ndarray,
    scale: np.ndarray,
    t: np.ndarray,
    inputs: np.ndarray,
    input_names: Sequence[str],
    output_names: Sequence[str],
    kind: str,
    n_lags: int | None = None,
) -> ResidualAnalysis:
    """Whiteness statistics of residual series (see the module notes).

    Parameters
    ----------
    residuals : ndarray, shape (N, ny)
        K; NaN where the output is not measured.
    scale : ndarray, shape (N, ny)
        Standard deviation each residual is divided by (the innovation's, or a constant).
    t : ndarray, shape (N,)
        Sample times, s.
    inputs : ndarray, shape (N, p)
        Inputs (and flows) to cross-correlate with, columns ``input_names``.
    kind : {"innovations", "open-loop"}
    n_lags : int, optional
        Lags of the autocorrelation and cross-correlations; default those spanning
        :data:`CORRELATION_SPAN_S`, at least the Ljung-Box lags, at most a quarter of the samples.
    """
    if kind not in ("innovations", "open-loop"):
        raise ParameterError(f"kind must be 'innovations' or 'open-loop', got {kind!r}")
    e = np.asarray(residuals, dtype=float)
    if e.ndim != 2 or e.shape[1] != len(output_names):
        raise ParameterError(f"residuals must have shape (N, {len(output_names)}), got {e.shape}")
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t))) if t.size > 1 else math.nan
    z = e / np.asarray(scale, dtype=float)
    outs = []
    for j, name in enumerate(output_names):
        n = int(np.isfinite(z[:, j]).sum())
        lb = ljung_box_lags(n)
        if n_lags is None:
            span = round(CORRELATION_SPAN_S / dt) if math.isfinite(dt) and dt > 0 else lb
            lags = max(lb, min(span, z.shape[0] // 4, 500))
        else:
            lags = int(n_lags)
        lags = max(lb, min(lags, z.shape[0] - 1))
        r = acf(z[:, j], lags)
        q = ljung_box_q(r[1 : lb + 1], n)
        corr = {name_u: ccf(z[:, j], inputs[:, i], lags) for i, name_u in enumerate(input_names)}
        outs.append(
            OutputResiduals(
                name,
                e[:, j],
                z[:, j],
                n,
                r,
                q,
                float(chdtrc(lb, q)),
                lb,
                cumulative_periodogram(z[:, j]),
                corr,
            )
        )
    return ResidualAnalysis(kind, t, dt, tuple(outs))


def innovations(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray]:
    """One-step-ahead innovations of the Kalman filter and their predicted standard deviations.

    ``values`` must hold the noise levels (``sigma_v``, ``sigma_w_*``, ``sigma_x0_*``), as the
    values of an ML fit do.

    Returns
    -------
    e : ndarray, shape (N, ny)
        ``y_k - y_k|k-1``, K (NaN where ``y`` is missing).
    sd : ndarray, shape (N, ny)
        ``sqrt(S_k,jj)``, K.
    """
    out = run_filter(network, values, data, hold)
    return out.innovations, np.sqrt(np.einsum("kii->ki", out.S))


def _signals(data: Dataset) -> tuple[np.ndarray, tuple[str, ...]]:
    m = data.m if data.m is not None and data.m.size else np.zeros((data.n_samples, 0))
    return np.column_stack([data.u, m]), (*data.input_names, *data.flow_names)


def innovation_analysis(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    hold: str = "zoh",
    n_lags: int | None = None,
) -> ResidualAnalysis:
    """Whiteness of the standardized one-step innovations of a stochastic model on ``data``."""
    e, sd = innovations(network, values, data, hold)
    u, names = _signals(data)
    return analyse_residuals(e, sd, data.t, u, names, data.output_names, "innovations", n_lags)


def open_loop_analysis(error: np.ndarray, data: Dataset, n_lags: int | None = None) -> ResidualAnalysis:
    """The same statistics on open-loop simulation errors (``y - y_hat``), scaled by their RMS."""
    e = np.asarray(error, dtype=float)
    rms = np.sqrt(np.nanmean(e**2, axis=0))
    scale = np.broadcast_to(np.where(rms > 0, rms, 1.0), e.shape)
    u, names = _signals(data)
    return analyse_residuals(e, scale, data.t, u, names, data.output_names, "open-loop", n_lags)
