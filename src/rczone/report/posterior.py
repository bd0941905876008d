"""The posterior in a fit's report: trace plots, pair plots and the convergence diagnostics.

Trace plots show whether the chains mix and agree (each chain should look like the others and
like noise around one level); pair plots show what the standard deviations hide, the correlation
of R and C and a curved or bounded posterior (Gabry, Simpson, Vehtari, Betancourt & Gelman 2019,
sec. 4). Divergent transitions are not marked: their count is in the table.

References
----------
Gabry, J., Simpson, D., Vehtari, A., Betancourt, M. & Gelman, A. (2019). Visualization in Bayesian
workflow. *J. R. Stat. Soc. A* 182(2), 389-402.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from rczone.report.html import Report, literal

if TYPE_CHECKING:  # pragma: no cover
    from rczone.estimation.posterior import Posterior

#: Largest number of parameters drawn in the pair plot (the first ones: R and C come first).
PAIR_MAX = 6
_CHAIN_COLORS = ("#2b6cb0", "#dd6b20", "#38a169", "#805ad5", "#d53f8c", "#718096")


def trace_figure(post: Posterior) -> Figure:
    """One row per parameter: the draws of each chain against the draw number, and their histograms.

    Parameters
    ----------
    post : Posterior
        The draws.

    Returns
    -------
    Figure
    """
    d = len(post.names)
    fig = Figure(figsize=(8.5, 1.5 * d + 0.6))
    axes = fig.subplots(d, 2, squeeze=False, gridspec_kw={"width_ratios": (3, 1)})
    for i, name in enumerate(post.names):
        for c in range(post.n_chains):
            color = _CHAIN_COLORS[c % len(_CHAIN_COLORS)]
            axes[i, 0].plot(post.draws[c, :, i], lw=0.5, color=color, alpha=0.8)
            axes[i, 1].hist(
                post.draws[c, :, i], bins=30, histtype="step", color=color, orientation="horizontal"
            )
        axes[i, 0].set_ylabel(literal(name), fontsize=8)
        axes[i, 0].tick_params(labelsize=7)
        axes[i, 1].tick_params(labelsize=7, labelleft=False)
        axes[i, 0].grid(alpha=0.3)
    axes[-1, 0].set_xlabel("draw (after warm-up)")
    fig.tight_layout()
    return fig


def pair_figure(post: Posterior) -> Figure:
    """Scatter plots of every pair of the first :data:`PAIR_MAX` parameters, histograms on the diagonal.

    Parameters
    ----------
    post : Posterior
        The draws.

    Returns
    -------
    Figure
    """
    k = min(len(post.names), PAIR_MAX)
    flat = post.flat[:, :k]
    fig = Figure(figsize=(1.7 * k + 0.8, 1.7 * k + 0.6))
    axes = fig.subplots(k, k, squeeze=False)
    for i in range(k):
        for j in range(k):
            ax = axes[i, j]
            ax.tick_params(labelsize=6)
            ax.xaxis.set_major_locator(MaxNLocator(3))
            if j > i:
                ax.set_visible(False)
                continue
            if i == j:
                ax.hist(flat[:, i], bins=30, color="#90cdf4")
            else:
                ax.plot(flat[:, j], flat[:, i], ",", color="#2b6cb0", alpha=0.5)
            if i == k - 1:
                ax.set_xlabel(literal(post.names[j]), fontsize=7)
            if j == 0 and i > 0:
                ax.set_ylabel(literal(post.names[i]), fontsize=7)
    fig.tight_layout()
    return fig


def diagnostics_rows(post: Posterior) -> list[dict[str, object]]:
    """One row per parameter: mean, sd, 90 % interval, R-hat, bulk and tail ESS."""
    q = post.interval(0.9)
    mean, sd = post.mean, post.sd
    return [
        {
            "parameter": n,
            "posterior mean": mean[i],
            "sd": sd[i],
            "5 %": q[i, 0],
            "95 %": q[i, 1],
            "R-hat": post.rhat[i],
            "ESS bulk": post.ess_bulk[i],
            "ESS tail": post.ess_tail[i],
        }
        for i, n in enumerate(post.names)
    ]


def add_posterior(rep: Report, post: Posterior) -> None:
    """The posterior's section of a fit report: what ran, the diagnostics, the trace and pair plots.

    Parameters
    ----------
    rep : Report
        The report to extend.
    post : Posterior
        The draws and diagnostics.
    """
    rep.heading("Posterior draws")
    rep.paragraph(
        f"{html.escape(post.sampler)}: {post.n_chains} chains of {post.n_draws} draws after {post.tune}"
        f" warm-up draws, {post.draws_per_second:.0f} draws per second ({post.seconds:.1f} s,"
        f" {post.n_gradients} log-density gradients; the ML search that placed the chains took"
        f" {post.mode_seconds:.2f} s); {post.divergences} divergent transitions."
    )
    for _, text in post.issues():
        rep.paragraph(html.escape(text), "warn")
    rep.table(diagnostics_rows(post), "Posterior summaries and convergence diagnostics", digits=4)
    rep.figure("trace", trace_figure(post), "Trace of each chain (left) and the chains' histograms (right)")
    if len(post.names) > 1:
        rep.figure("pairs", pair_figure(post), "Pairs of parameters: the draws of all chains")
    if not np.isfinite(post.rhat).all():
        rep.paragraph("R-hat could not be computed for every parameter.", "warn")
