"""The console text of a fit: the parameter table, the search line, the residual verdicts.

Shared by :meth:`rczone.estimation.result.FitResult.summary` and
:meth:`rczone.calibration.Calibration.summary` (what ``rczone fit`` prints). Plain functions over a
result's attributes; rich renders them (``[red]...[/]`` is rich markup, and every user string
goes through :func:`esc`).
"""

from __future__ import annotations

import math

from rich.markup import escape


def esc(text: object) -> str:
    """``text`` as rich markup that prints literally (``[vav-3]`` stays ``[vav-3]``).

    Parameters
    ----------
    text : object
        Any text a user could have written (a name, a file name).

    Returns
    -------
    str
    """
    return escape(str(text))


def parameter_table(r, title: str, *, generic: bool = False):
    """The estimates with units, standard errors, construction values and a flag per parameter.

    Parameters
    ----------
    r : FitResult
        The fit.
    title : str
        Title of the table (rich markup).
    generic : bool
        The model's values before the fit are generic starting points (a built-in model of the
        Bacher & Madsen family), not construction data: the column says so, and no ratio is shown.

    Returns
    -------
    rich.table.Table
    """
    from rich.table import Table

    table = Table(title=title)
    table.add_column("parameter", no_wrap=True)
    post = getattr(r, "posterior", None)
    heads = (
        "estimate",
        "unit",
        "std. error",
        "generic start" if generic else "construction",
        "ratio",
        "flag",
    )
    if post is not None:
        heads = ("posterior mean", "unit", "sd", "90 % interval", "R-hat", "flag")
        q90 = post.interval(0.9)
    for c in heads:
        table.add_column(c, overflow="fold")
    search = r.search
    for i, (n, e) in enumerate(r.parameters.items()):
        flags = []
        if e.at_bound and not any(n in note for note in r.notes):
            flags.append("[red]at bound[/]")
        elif e.at_bound:
            flags.append("[dim]at floor[/]")
        if not math.isfinite(e.std_error) and not e.at_bound:
            flags.append("[red]no std. error[/]")
        if search is not None and search.n_best >= 2 and n in search.spread:
            lo, hi = search.spread[n]
            if lo > 0 and hi / lo > 1.1 and e.unit in ("K/W", "J/K"):
                flags.append(f"[yellow]starts: x{hi / lo:.2g}[/]")
        c, ratio = e.construction, math.nan if generic else e.ratio_to_construction
        cells = [
            esc(n),
            f"{e.value:.4g}",
            esc(e.unit),
            f"{e.std_error:.2g}" if math.isfinite(e.std_error) else "n/a",
            f"{c:.4g}" if math.isfinite(c) else "",
            f"{ratio:.2f}" if math.isfinite(ratio) else "",
            " ".join(flags),
        ]
        if post is not None:
            rhat = post.rhat[i]
            mark = "" if rhat < 1.01 else "[red]"
            cells[4:6] = [f"{q90[i, 0]:.3g} to {q90[i, 1]:.3g}", f"{mark}{rhat:.3f}{'[/]' if mark else ''}"]
        table.add_row(*cells)
    return table


def search_line(r) -> str:
    """How the optimum was found, in one line.

    Parameters
    ----------
    r : FitResult
        The fit.

    Returns
    -------
    str
    """
    post = getattr(r, "posterior", None)
    if post is not None:
        return posterior_line(post)
    s = r.search
    if s is None:
        return f"{r.n_evals} evaluations"
    head = (
        f"{s.strategy} search: {s.n_sampled} sampled points, {s.n_local} local searches,"
        f" {len(s.optima)} distinct optim{'um' if len(s.optima) == 1 else 'a'}; {s.reason}"
    )
    if len(s.optima) > 1:
        head += f" (next best optimum {s.optima[1].cost - s.optima[0].cost:+.3g} in cost)"
    return head


def posterior_line(post) -> str:
    """What the sampler did and whether its draws can be used, in one line.

    Parameters
    ----------
    post : Posterior
        The draws and diagnostics (:class:`rczone.estimation.posterior.Posterior`).

    Returns
    -------
    str
    """
    ess = float(min(post.ess_bulk.min(), post.ess_tail.min()))
    verdict = "[green]converged[/]" if not post.issues() else "[red]not converged[/]"
    return (
        f"{esc(post.sampler)}: {post.n_chains} chains x {post.n_draws} draws ({post.tune} warm-up),"
        f" {post.draws_per_second:.0f} draws/s ({post.seconds:.1f} s, {post.n_gradients} gradients;"
        f" the ML search that placed the chains {post.mode_seconds:.2f} s); R-hat max {float(post.rhat.max()):.3f},"
        f" ESS min {ess:.0f}, {post.divergences} divergences: {verdict}"
    )


def residual_lines(analysis) -> list[str]:
    """What the residuals say: the innovations of an ML fit, or the labelled open-loop error of LS.

    Parameters
    ----------
    analysis : ResidualAnalysis or None
        Innovations (preferred) or open-loop residuals.

    Returns
    -------
    list of str
    """
    an = analysis
    if an is None:
        return []
    lines = []
    for o in an.outputs:
        lag = f"{an.lags_h[1] * 60:.0f} min" if an.lags_h[1] < 1 else f"{an.lags_h[1]:.2g} h"
        if an.kind == "innovations":
            verdict = "[green]white[/]" if o.white else "[red]not white[/]"
            head = f"innovations of {esc(o.output)} (one-step, standardized): {verdict},"
        else:
            head = f"open-loop residuals of {esc(o.output)} (not expected to be white: fit by ML to test):"
        text = (
            f"{head} Ljung-Box p = {o.p_value:.2g} over {o.lb_lags} lags, ACF at {lag} {o.acf[1]:.2f},"
            f" cumulative periodogram {'inside' if o.periodogram.inside_band else 'outside'} its band"
        )
        worst = o.worst_input()
        if worst is not None and an.kind == "innovations":
            name, value, k = worst
            text += f"; largest input cross-correlation {esc(name)} {value:.2f} at {k * an.dt_s / 3600:.2g} h"
        lines.append(text)
    return lines
