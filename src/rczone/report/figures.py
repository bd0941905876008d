"""Figures drawn from rczone's data objects. Each function returns a new matplotlib Figure.

No pyplot and no global style: figures are created with :class:`matplotlib.figure.Figure`,
so nothing here depends on or changes a display backend.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from rczone.comparison import FrequencyComparison, TimeComparison

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
            ax.plot(h, y, color=COLORS.get(name), lw=1.3, label=LABELS.get(name, name))
        ax.set_ylabel("Ti (°C)")
        ax.set_title(c.label, fontsize=10, loc="left")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("hours from start (6 pm)")
    axes[0].legend(fontsize=8, ncol=4, loc="best")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def gains(fc: FrequencyComparison, inputs: Sequence[str] = ("Ts", "Tsd")) -> Figure:
    """|H| from each input to Ti for every model (the paper's Fig. 5)."""
    fig = Figure(figsize=(8.5, 3.2))
    axes = fig.subplots(1, len(inputs), squeeze=False)[0]
    for ax, i in zip(axes, inputs, strict=True):
        for name, g in fc.gains.items():
            ax.semilogx(fc.freq_hz, g[i], color=COLORS.get(name), label=LABELS.get(name, name))
        ax.set_title(f"|H_{i}| at m = {fc.m:g} kg/s", fontsize=10)
        ax.set_xlabel("frequency (Hz)")
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
            ax.semilogx(fc.freq_hz, e[i], color=COLORS.get(name), label=LABELS.get(name, name))
        ax.set_title(f"e_{i} (du = {fc.du[i]:.1f} K)", fontsize=10)
        ax.set_xlabel("frequency (Hz)")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("error (K)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def data_overview(frame: pd.DataFrame, title: str = "") -> Figure:
    """Room, surrounding, outdoor and supply temperatures, and the supply flow, over time."""
    fig = Figure(figsize=(8.5, 5.2))
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1.2, 1]})
    h = _hours(frame["time"].to_numpy(float))
    ax1.plot(h, frame["Ti"], color="black", lw=1.2, label="Ti (room)")
    for c, col in (
        ("Tf", "#805ad5"),
        ("Tc", "#d53f8c"),
        ("Tn1", "#dd6b20"),
        ("Tn2", "#38a169"),
        ("Thw", "#3182ce"),
    ):
        if c in frame:
            ax1.plot(h, frame[c], color=col, lw=0.8, alpha=0.8, label=c)
    if "Tsd" in frame and "Tf" not in frame:
        ax1.plot(h, frame["Tsd"], color="#3182ce", lw=0.9, label="Tsd")
    ax1.set_ylabel("°C")
    ax1.legend(fontsize=7, ncol=6, loc="best")
    ax1.grid(alpha=0.3)
    for c, col in (("Ts", "#c53030"), ("To", "#718096")):
        if c in frame:
            ax2.plot(h, frame[c], color=col, lw=1.0, label=c)
    ax2.set_ylabel("°C")
    ax2.legend(fontsize=7, ncol=2)
    ax2.grid(alpha=0.3)
    if "m" in frame:
        ax3.step(h, frame["m"], where="post", color="#2b6cb0", lw=1.0)
    ax3.set_ylabel("m (kg/s)")
    ax3.set_xlabel("hours from start")
    ax3.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
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
            ax.plot(h, frame[c].to_numpy(float), lw=1.0, label=c)
        ax.set_ylabel(label)
        ax.legend(fontsize=7, ncol=min(len(cols), 6), loc="best")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("hours from start")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def fit_overview(t: np.ndarray, measured: np.ndarray, predicted: np.ndarray, title: str = "") -> Figure:
    """Measured and open-loop predicted room temperature, and the error."""
    fig = Figure(figsize=(8.5, 4.2))
    ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    h = _hours(t)
    ax1.plot(h, measured, color="black", lw=1.0, label="measured")
    ax1.plot(h, predicted, color="#dd6b20", lw=1.4, label="model (open loop)")
    ax1.set_ylabel("Ti (°C)")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.plot(h, measured - predicted, color="#c53030", lw=0.9)
    ax2.axhline(0, color="black", lw=0.6)
    ax2.set_ylabel("error (K)")
    ax2.set_xlabel("hours from start")
    ax2.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def residual_acf(lags: np.ndarray, acf: np.ndarray, n: int, title: str = "") -> Figure:
    """Sample autocorrelation of residuals with the 95 % band of white noise."""
    fig = Figure(figsize=(6.0, 2.8))
    ax = fig.subplots()
    ax.bar(lags, acf, color="#2b6cb0", width=0.6)
    band = 1.96 / np.sqrt(max(n, 1))
    ax.axhspan(-band, band, color="#a0aec0", alpha=0.3, label="95 % band of white noise")
    ax.set_xlabel("lag (samples)")
    ax.set_ylabel("autocorrelation")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig
