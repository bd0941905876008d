"""The console text of a model selection: what ``rczone select`` prints, and :meth:`Selection.summary`.

Plain functions over a :class:`~rczone.selection.compare.Selection`; rich renders them.
"""

from __future__ import annotations

from rich.text import Text

from rczone.results.fit_text import esc
from rczone.results.verdict import EXIT_UNTRUSTED


def candidates_table(sel, title: str):
    """The candidates' log-likelihoods, information criteria and innovation whiteness."""
    from rich.table import Table

    table = Table(title=title)
    for c in ("model", "log L", "k", "AIC", "BIC", "ΔBIC", "Ljung-Box p", "white", ""):
        table.add_column(c)
    for row in sel.table():
        p = row["Ljung-Box p"]
        white = row["white"]
        table.add_row(
            esc(row["model"]),
            f"{row['log L']:.1f}",
            str(row["k"]),
            f"{row['AIC']:.1f}",
            f"{row['BIC']:.1f}",
            f"{row['dBIC']:.1f}",
            "n/a" if p is None else f"{p:.2g}",
            f"[green]{white}[/]" if white == "yes" else f"[red]{white}[/]",
            "[bold]selected[/]"
            if row["selected"]
            else ("[yellow]flagged: passed over[/]" if row["passed over"] else ""),
        )
    return table


def tests_table(sel):
    """The likelihood-ratio tests between nested candidates."""
    from rich.table import Table

    table = Table(title="Likelihood-ratio tests between nested candidates (p: chi2(df), conservative)")
    for c in ("simple ⊂ rich", "restriction", "LR", "df", "p", "p (chi-bar²)"):
        table.add_column(c)
    for t in sel.tests:
        table.add_row(
            f"{esc(t.simple)} ⊂ {esc(t.rich)}",
            esc(t.nesting.describe()),
            f"{t.statistic:.2f}",
            str(t.df),
            f"{t.p_value:.3g}",
            f"{t.p_value_chi_bar:.3g}",
        )
    return table


def vuong_table(sel):
    """Vuong's tests between non-nested candidates."""
    from rich.table import Table

    table = Table(
        title=f"Vuong tests between non-nested candidates ({esc(sel.basis.describe())}; two-sided, level {sel.alpha:g})"
    )
    for c in ("a vs b", "log L_a - log L_b", "Z", "p", "Z (Schwarz)", "p (Schwarz)", "closer"):
        table.add_column(c)
    for v in sel.vuong:
        table.add_row(
            f"{esc(v.a)} vs {esc(v.b)}",
            f"{v.loglik_ratio:.1f}",
            f"{v.statistic:.2f}",
            f"{v.p_value:.3g}",
            f"{v.statistic_bic:.2f}",
            f"{v.p_value_bic:.3g}",
            esc(v.closer(sel.alpha) or "neither (not significant)"),
        )
    return table


def selection_lines(sel) -> list:
    """What ``rczone select`` prints after fitting the candidates, in order (rich markup).

    Parameters
    ----------
    sel : Selection
        The selection (its ``data_label``, ``source`` and ``noise`` name the data and the fit).

    Returns
    -------
    list
    """
    how = f"forward selection, alpha = {sel.alpha:g}" if sel.rule == "forward" else sel.rule.upper()
    title = f"Candidates fitted to {esc(sel.data_label)} by ML ({sel.samples['n']} samples)"
    if sel.basis is not None and sel.basis.conditional:
        title += f"; log L of {esc(', '.join(sel.basis.targets))} {esc(sel.basis.describe())}"
    lines: list = [candidates_table(sel, title)]
    if sel.basis is not None and sel.basis.conditional:
        lines.append(
            f"the candidates measure different outputs: compared on the likelihood of"
            f" {esc(', '.join(sel.basis.targets))} {esc(sel.basis.describe())} (the measured"
            f" {esc(', '.join(sel.basis.given))}, an output of some candidates and an input of the others)"
        )
    if sel.tests:
        lines.append(tests_table(sel))
    elif not sel.vuong:
        lines.append("no candidate is nested in another: no likelihood-ratio test")
    if sel.vuong:
        lines.append(vuong_table(sel))
    for step in sel.steps:
        if step["accepted"]:
            verdict = "accepted"
        elif step.get("refused_flagged"):
            verdict = f"refused: the fit of {esc(step['best'])} is flagged, stop"
        else:
            verdict = "rejected: stop"
        lines.append(
            f"forward: {esc(step['from'])} -> {esc(step['best'])} (of {', '.join(map(esc, step['tried']))}):"
            f" LR {step['statistic']:.2f}, df {step['df']}, p = {step['p_value']:.3g}, {verdict}"
        )
    if sel.not_fitted:
        lines.append("not reached (not fitted): " + ", ".join(map(esc, sel.not_fitted)))
    for name, why in sel.passed_over.items():
        lines.append(
            f"[yellow]passed over:[/] {esc(name)}, whose fit is flagged ({esc(why)}): a flagged fit is never"
            " selected while a sound one remains"
        )
    lines.append(f"selected: [bold]{esc(sel.selected)}[/] ({how})")
    lines.append(
        "the same fit alone (check its open-loop prediction on held-out data with rczone predict before"
        " using it for control: process noise on every state raises the likelihood but can leave the"
        " deterministic part poor):"
    )
    lines.append(Text(fit_command(sel)))  # a Text is printed unwrapped, so it pastes as one line
    best = sel.best.calibration
    inn = best.innovations
    if inn is not None and not inn.white:
        lines.append(
            f"[yellow]warning:[/] the innovations of {esc(sel.selected)} are not white (Ljung-Box p ="
            f" {inn.ljung_box_p:.2g}): every candidate misses some dynamics or input"
        )
    return lines


def verdict_lines(sel) -> list[str]:
    """The selected fit's verdict, last: its flags, and with held-out data the verdict line ``fit`` prints."""
    best = sel.best.calibration
    lines = [f"[yellow]warning:[/] {esc(sel.selected)}: {esc(f)}" for f in best.verdict.reasons]
    if best.evidence is not None:
        from rczone.calibration.calibration import verdict_line

        lines.append(verdict_line(best))
    elif not best.verdict.trustworthy:
        lines.append(f"[red]the selected model's fit is flagged[/] (exit code {EXIT_UNTRUSTED})")
    return lines


def fit_command(sel) -> str:
    """The ``rczone fit`` command line that fits the selected model alone, as ``select`` fitted it.

    Every argument is quoted for a POSIX shell (:func:`shlex.join`), so the line can be pasted.

    Parameters
    ----------
    sel : Selection
        The selection (its ``source``, ``model_specs``, ``noise`` and ``fit_args``).

    Returns
    -------
    str
    """
    import shlex

    spec = sel.model_specs.get(sel.selected, sel.selected)
    args = ["rczone", "fit", sel.source or sel.data_label, "--model", spec, "--noise", sel.noise]
    return shlex.join([*args, *sel.fit_args])


def fit_arguments(sel, settings, *, columns=None):
    """The ``rczone fit`` options that repeat the selected model's fit as ``select`` made it.

    Parameters
    ----------
    sel : Selection
        The selection (the selected fit's free parameters decide which bounds apply).
    settings : FitSettings
        The selection's settings: its constants (SI units), hold, starts (None: the global search,
        the default of both commands), seed, bounds (those of parameters the selected fit
        estimates are kept) and fixed parameters (None: the model's value; those the selected model
        has are kept, and the parameters its fit estimated beyond ``rczone fit``'s default set are
        freed with ``+NAME``).
    columns : str or path, optional
        The column map.

    Returns
    -------
    tuple of str
    """
    free = set(sel.best.calibration.result.names)
    args: list[str] = []
    if columns is not None:
        args += ["--columns", str(columns)]
    for name, value in settings.constants.items():
        args += ["--const", f"{name}={value!r}"]
    if settings.hold != "zoh":
        args += ["--hold", settings.hold]
    if settings.n_starts is not None:
        args += ["--starts", str(settings.n_starts)]
    if settings.seed:
        args += ["--seed", str(settings.seed)]
    for name, (lo, hi) in settings.bounds.items():
        if name in free:
            args += ["--bounds", f"{name}={lo!r},{hi!r}"]
    from rczone.estimation.fit import default_free
    from rczone.selection.compare import parameter_names

    net = sel.best.calibration.model.network
    for name, value in settings.fixed.items():
        if name in parameter_names(net):
            args += ["--fix", name if value is None else f"{name}={value!r}"]
    default = set(default_free(net, "ml", noise=sel.noise))
    args += [
        a for name in sel.best.calibration.result.names if name not in default for a in ("--free", "+" + name)
    ]
    return tuple(args)
