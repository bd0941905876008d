"""Figures drawn from rczone's data objects. Each function returns a new matplotlib Figure.

No pyplot and no global style: figures are created with :class:`matplotlib.figure.Figure`,
so nothing here depends on or changes a display backend.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from rczone.models.comparison import FrequencyComparison, TimeComparison
from rczone.models.reduction import F_PER_K
from rczone.report.html import literal

if TYPE_CHECKING:  # pragma: no cover
    from rczone.postfit.innovations import ResidualAnalysis

COLORS = {"measured": "black", "full-scale": "#2b6cb0", "second-order": "#dd6b20", "first-order": "#38a169"}
LABELS = {"full-scale": "full-scale (13 states)", "second-order": "2nd order", "first-order": "1st order"}


def _hours(t: np.ndarray) -> np.ndarray:
    return (t - t[0]) / 3600.0


def time_comparison(comparisons: Sequence[TimeComparison], title: str = "") -> Figure:
    """Measured and predicted room temperature, one panel per data set (the paper's Fig. 4)."""
    fig = Figure(figsize=(8.5, 2.6 * len(comparisons)))
    axes = fig.subplots(len(comparisons), 1, squeeze=False)[:, 0]
    for ax, c in zip(axes, comparisons, strict=True):
        h = _hours(c.t)
        ax.plot(h, c.measured, color=COLORS["measured"], lw=1.0, label="measured")
        for name, y in c.predicted.items():
            ax.plot(h, y, color=COLORS.get(name), lw=1.3, label=literal(LABELS.get(name, name)))
        ax.set_ylabel("Ti (°C)")
        ax.set_title(literal(c.label), fontsize=10, loc="left")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("hours from start (6 pm)")
    axes[0].legend(fontsize=8, ncol=4, loc="best")
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def gains(fc: FrequencyComparison, inputs: Sequence[str] = ("Ts", "Tsd")) -> Figure:
    """|H| from each input to Ti for every model (the paper's Fig. 5)."""
    fig = Figure(figsize=(8.5, 3.2))
    axes = fig.subplots(1, len(inputs), squeeze=False)[0]
    for ax, i in zip(axes, inputs, strict=True):
        for name, g in fc.gains.items():
            ax.semilogx(fc.freq_hz, g[i], color=COLORS.get(name), label=literal(LABELS.get(name, name)))
        ax.set_title(literal(f"|H_{i}| at m = {fc.m:g} kg/s"), fontsize=10)
        ax.set_xlabel("frequency (Hz)")
        period_axis(ax, per_hour=False)
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("gain (K/K)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def gain_errors(fc: FrequencyComparison, inputs: Sequence[str] = ("Ts", "Tsd")) -> Figure:
    """Weighted gain error e_i(w) of each low-order model (the paper's Fig. 6)."""
    fig = Figure(figsize=(8.5, 3.2))
    axes = fig.subplots(1, len(inputs), squeeze=False)[0]
    for ax, i in zip(axes, inputs, strict=True):
        for name, e in fc.errors.items():
            ax.semilogx(fc.freq_hz, e[i], color=COLORS.get(name), label=literal(LABELS.get(name, name)))
        ax.set_title(literal(f"e_{i} (du = {fc.du[i]:.1f} K)"), fontsize=10)
        ax.set_xlabel("frequency (Hz)")
        period_axis(ax, per_hour=False)
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("error (K)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def signals_overview(
    frame: pd.DataFrame, panels: Sequence[tuple[str, Sequence[str]]], title: str = ""
) -> Figure:
    """Any model's signals over time: one panel per ``(y label, columns)``; absent columns are skipped."""
    panels = [(label, [c for c in cols if c in frame]) for label, cols in panels]
    panels = [(label, cols) for label, cols in panels if cols]
    fig = Figure(figsize=(8.5, 1.2 + 1.5 * max(len(panels), 1)))
    axes = fig.subplots(max(len(panels), 1), 1, sharex=True, squeeze=False)[:, 0]
    h = _hours(frame["time"].to_numpy(float))
    for ax, (label, cols) in zip(axes, panels, strict=False):
        for c in cols:
            ax.plot(h, frame[c].to_numpy(float), lw=1.0, label=literal(c))
        ax.set_ylabel(literal(label))
        ax.legend(fontsize=7, ncol=min(len(cols), 6), loc="best")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("hours from start")
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def fit_overview(
    t: np.ndarray, measured: np.ndarray, predicted: np.ndarray, title: str = "", label: str = "Ti"
) -> Figure:
    """Measured and open-loop predicted temperature of output ``label``, and the error."""
    fig = Figure(figsize=(8.5, 4.2))
    ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    h = _hours(t)
    ax1.plot(h, measured, color="black", lw=1.0, label="measured")
    ax1.plot(h, predicted, color="#dd6b20", lw=1.4, label="model (open loop)")
    ax1.set_ylabel(literal(f"{label} (°C)"))
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.plot(h, measured - predicted, color="#c53030", lw=0.9)
    ax2.axhline(0, color="black", lw=0.6)
    ax2.set_ylabel("error (K)")
    ax2.set_xlabel("hours from start")
    ax2.grid(alpha=0.3)
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def residual_acf(
    lags: np.ndarray, acf: np.ndarray, n: int, title: str = "", dt_s: float | None = None
) -> Figure:
    """Sample autocorrelation of residuals with the 95 % band of white noise (lags in hours with ``dt_s``)."""
    fig = Figure(figsize=(6.0, 2.8))
    ax = fig.subplots()
    x = np.asarray(lags) * dt_s / 3600.0 if dt_s else np.asarray(lags)
    ax.bar(x, acf, color="#2b6cb0", width=0.6 * (x[1] - x[0] if x.size > 1 else 1.0))
    band = 1.96 / np.sqrt(max(n, 1))
    ax.axhspan(-band, band, color="#a0aec0", alpha=0.3, label="95 % band of white noise")
    ax.set_xlabel("lag (h)" if dt_s else "lag (samples)")
    ax.set_ylabel("autocorrelation")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(literal(title), fontsize=10)
    fig.tight_layout()
    return fig


def _variant_style(name: str) -> dict[str, object]:
    """Colour of the model a variant derives from; dashed for band-matched values."""
    base = name.removesuffix("-band").replace("second-order-paper", "second-order")
    style: dict[str, object] = {"color": COLORS.get(base)}
    if name.endswith("-band"):
        style["ls"] = "--"
    elif name.startswith("second-order-paper"):
        style["ls"] = ":"
    return style


def paper_figs_5_6(
    fc: FrequencyComparison, limit_F: float = 1.0, inputs: Sequence[str] = ("Ts", "Tsd")
) -> Figure:
    """The paper's Figs. 5 and 6 together: gains (top) and eq.-7 errors in F (bottom).

    Band-matched variants (names ending ``-band``) are dashed in their model's colour; the
    paper's bound for the 2nd-order model (``limit_F``) is a grey line.
    """
    fig = Figure(figsize=(8.5, 6.0))
    axes = fig.subplots(2, len(inputs), squeeze=False)
    for j, i in enumerate(inputs):
        top, bottom = axes[0, j], axes[1, j]
        for name, g in fc.gains.items():
            top.semilogx(fc.freq_hz, g[i], label=literal(LABELS.get(name, name)), **_variant_style(name))  # type: ignore[arg-type]
        for name, e in fc.errors.items():
            bottom.semilogx(
                fc.freq_hz, e[i] * F_PER_K, label=literal(LABELS.get(name, name)), **_variant_style(name)
            )  # type: ignore[arg-type]
        bottom.axhline(limit_F, color="grey", lw=0.8)
        period_axis(top, per_hour=False)
        top.set_title(literal(f"|H_{i}| at m = {fc.m:g} kg/s"), fontsize=10)
        bottom.set_title(literal(f"e_{i}, du = {fc.du[i] * F_PER_K:.0f} F"), fontsize=10)
        bottom.set_xlabel("frequency (Hz)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("gain (K/K)")
    axes[1, 0].set_ylabel("error (F)")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


#: Periods (h) labelled on the period axes, the most useful first (they win where labels crowd).
_PERIODS_H = (1.0, 24.0, 1 / 6, 168.0, 6.0, 1 / 3, 3.0, 12.0, 0.5, 2.0, 48.0, 720.0, 1 / 12)


def _period_label(p: float) -> str:
    return f"{p * 60:.0f} min" if p < 1 else f"{p / 24:.0f} d" if p >= 24 else f"{p:.0f} h"


def period_axis(ax, per_hour: bool = True) -> None:
    """A top axis labelling the bottom axis' frequencies (cycles per hour, or Hz) by their periods.

    Call it after the bottom axis' limits are final; labels closer than 10 % of the axis are thinned.
    """
    lo, hi = ax.get_xlim()
    log = ax.get_xscale() == "log"
    scale = 1.0 if per_hour else 1.0 / 3600.0
    kept: list[tuple[float, float, str]] = []  # (position along the axis, frequency, label)
    for p in _PERIODS_H:
        f = scale / p
        if not lo <= f <= hi or f <= 0:
            continue
        x = (np.log(f) - np.log(lo)) / (np.log(hi) - np.log(lo)) if log and lo > 0 else (f - lo) / (hi - lo)
        if all(abs(x - other) >= 0.1 for other, _, _ in kept):
            kept.append((x, f, _period_label(p)))
    kept.sort()
    pos, labels = [f for _, f, _ in kept], [text for _, _, text in kept]
    top = ax.secondary_xaxis("top")
    top.set_xticks(pos, labels)
    top.minorticks_off()
    top.set_xlabel("period", fontsize=8)
    top.tick_params(labelsize=7)


def _cpgram(ax, analysis: ResidualAnalysis, j: int, color: str = "#2b6cb0", label: str = "") -> None:
    """The cumulative periodogram of output ``j`` against frequency in cycles per hour, with its band."""
    cp = analysis.outputs[j].periodogram
    f = cp.freq * 3600.0 / analysis.dt_s
    ax.step(f, cp.cumulative, where="post", color=color, lw=1.1, label=literal(label) if label else None)


def _cpgram_band(ax, analysis: ResidualAnalysis, j: int) -> None:
    cp = analysis.outputs[j].periodogram
    f = cp.freq * 3600.0 / analysis.dt_s
    line = np.arange(1, f.size + 1) / f.size
    ax.plot(f, line, color="black", lw=0.8, label="white noise")
    ax.fill_between(f, line - cp.band, line + cp.band, color="#a0aec0", alpha=0.3, lw=0, label="95 % band")
    ax.set_xlim(0, f[-1])
    ax.set_ylim(0, 1)
    ax.set_xlabel("frequency (cycles per hour)")
    ax.set_ylabel("cumulative periodogram")


def residual_panels(analysis: ResidualAnalysis, output: int = 0, title: str = "") -> Figure:
    """Four panels on one output's residuals: the series, the autocorrelation, the cumulative
    periodogram and the cross-correlation with each input, every band at 95 %.

    Lags are in hours; the periodogram's frequency axis also reads as periods (top axis).
    """
    o = analysis.outputs[output]
    innov = analysis.kind == "innovations"
    fig = Figure(figsize=(9.0, 6.2))
    (a1, a2), (a3, a4) = fig.subplots(2, 2)
    h = _hours(analysis.t)
    a1.plot(h, o.standardized, color="#2b6cb0", lw=0.6)
    if innov:
        for v in (-1.96, 1.96):
            a1.axhline(v, color="#c53030", lw=0.7, ls="--")
    a1.axhline(0, color="black", lw=0.6)
    a1.set_xlabel("hours from start")
    a1.set_ylabel("standardized" if innov else "error / RMS")
    a1.set_title(("innovations" if innov else "open-loop error") + literal(f" of {o.output}"), fontsize=10)
    lag_h = analysis.lags_h
    a2.vlines(lag_h[1:], 0, o.acf[1:], color="#2b6cb0", lw=1.2)
    a2.axhspan(-o.band, o.band, color="#a0aec0", alpha=0.3, label="95 % band of white noise")
    a2.axhline(0, color="black", lw=0.6)
    a2.set_xlabel("lag (h)")
    a2.set_ylabel("autocorrelation")
    a2.set_title(f"Ljung-Box p = {o.p_value:.2g} over {o.lb_lags} lags", fontsize=10)
    a2.legend(fontsize=7)
    _cpgram(a3, analysis, output)
    _cpgram_band(a3, analysis, output)
    period_axis(a3)
    a3.legend(fontsize=7, loc="lower right")
    for k, (name, r) in enumerate(o.ccf.items()):
        if r is not None:
            a4.plot(lag_h, r, lw=1.0, color=f"C{k}", label=literal(name))
    a4.axhspan(-o.band, o.band, color="#a0aec0", alpha=0.3)
    a4.axhline(0, color="black", lw=0.6)
    a4.set_xlabel("lag (h), input leading")
    a4.set_ylabel("cross-correlation")
    a4.legend(fontsize=7, ncol=2)
    for ax in (a1, a2, a3, a4):
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def residual_comparison(analyses: dict[str, ResidualAnalysis], output: int = 0, title: str = "") -> Figure:
    """Autocorrelation (lags in hours) and cumulative periodogram of several models' innovations."""
    fig = Figure(figsize=(9.0, 3.4))
    a1, a2 = fig.subplots(1, 2)
    first = None
    for k, (name, an) in enumerate(analyses.items()):
        o = an.outputs[output]
        a1.plot(an.lags_h[1:], o.acf[1:], color=f"C{k}", lw=1.1, marker=".", ms=3, label=literal(name))
        _cpgram(a2, an, output, color=f"C{k}", label=literal(name))
        first = first or an
    if first is not None:
        band = first.outputs[output].band
        a1.axhspan(-band, band, color="#a0aec0", alpha=0.3)
        _cpgram_band(a2, first, output)
        period_axis(a2)
    a1.axhline(0, color="black", lw=0.6)
    a1.set_xlabel("lag (h)")
    a1.set_ylabel("autocorrelation of innovations")
    a1.legend(fontsize=7)
    a2.legend(fontsize=7, loc="lower right")
    for ax in (a1, a2):
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def profile_curves(profiles: dict[str, dict], estimates: dict[str, float], units: dict[str, str]) -> Figure:
    """Profile likelihood of each parameter: the rise of the cost against the parameter's value.

    ``profiles`` maps a parameter to ``{"values", "rise", "interval"}`` (the JSON form of
    :class:`rczone.postfit.profiles.ProfileCheck`); the dashed line is the 95 % threshold
    ``chi2(1, 0.95) / 2``, the shaded span the profile interval.
    """
    from rczone.postfit.profiles import PROFILE_THRESHOLD

    names = list(profiles)
    cols = min(3, max(1, len(names)))
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(3.1 * cols, 2.6 * rows))
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    thr = PROFILE_THRESHOLD
    for ax, name in zip(axes, names):
        p = profiles[name]
        x, rise = np.asarray(p["values"], float), np.asarray(p["rise"], float)
        ax.semilogx(x, rise, color="#2b6cb0", marker="o", ms=3, lw=1.2)
        ax.set_yscale("symlog", linthresh=2.0)  # the threshold stays visible under a steep rise
        ax.axhline(thr, color="#c53030", ls="--", lw=0.8)
        ax.axvline(estimates[name], color="black", lw=0.7)
        lo, hi = p.get("interval", (np.nan, np.nan))
        lo = x[0] if lo is None or not np.isfinite(lo) else lo
        hi = x[-1] if hi is None or not np.isfinite(hi) else hi
        ax.axvspan(lo, hi, color="#90cdf4", alpha=0.3, lw=0)
        unit = units.get(name, "")
        ax.set_xlabel(literal(f"{name} ({unit})" if unit else name))
        ax.set_ylabel("rise of the cost")
        ax.grid(alpha=0.3, which="both")
    for ax in axes[len(names) :]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig
