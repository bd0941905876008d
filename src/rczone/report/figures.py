"""Figures drawn from rczone's data objects. Each function returns a new matplotlib Figure.

No pyplot and no global style: figures are created with :class:`matplotlib.figure.Figure`,
so nothing here depends on or changes a display backend.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
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
