"""``rczone select``: fit candidate models to the same data and choose one."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import (
    EXIT_UNTRUSTED,
    MODEL_HELP,
    ColumnMapOption,
    ConstantsOption,
    constants,
    data_label,
    esc,
    model,
    out_console,
    write_json,
)
from rczone.cli.main import app


def _read(data: Path, column_map: Path | None, zms: list, required: list[str] | None = None) -> object:
    """The data with every candidate's signals (default: each candidate's required columns must be there)."""
    from rczone.sources import read_frame

    signals: dict[str, str] = {}
    needed: list[str] = []
    for zm in zms:
        signals.update(zm.signal_quantities())
        needed += [s for s in zm.required_signals() if s not in needed]
    outputs = list(dict.fromkeys(o for zm in zms for o in zm.network.outputs))
    return read_frame(data, column_map, signals, needed if required is None else required, outputs)


def _table(sel, title: str):
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
            "[bold]selected[/]" if row["selected"] else "",
        )
    return table


def _tests_table(sel):
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


def _vuong_table(sel):
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


@app.command()
def select(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    models: Annotated[
        list[str] | None,
        typer.Option(
            "--model",
            help=MODEL_HELP + " Repeat for each candidate (at least two). Default: the Bacher & Madsen"
            " family (Ti, TiTe, TiTh, TiTeTh, TiTm) with the inputs the data have (Ph, Ps, Q, m and Ts).",
        ),
    ] = None,
    forward: Annotated[
        bool,
        typer.Option(
            "--forward",
            help="Forward selection (Bacher & Madsen 2011): from the simplest candidate, move to its best"
            " smallest extension while the likelihood-ratio test rejects the current model.",
        ),
    ] = False,
    criterion: Annotated[
        str, typer.Option(help="Without --forward: choose the smallest bic (default) or aic.")
    ] = "bic",
    alpha: Annotated[float, typer.Option(help="Level of the likelihood-ratio tests.")] = 0.05,
    noise: Annotated[
        str,
        typer.Option(
            help="Process noise estimated on every state (all, default, as Bacher & Madsen) or on the"
            " measured states only (measured, as rczone fit)."
        ),
    ] = "all",
    starts: Annotated[
        str, typer.Option(help="Local searches per fit: auto (global search, default), 1 or N.")
    ] = "auto",
    seed: Annotated[int, typer.Option(help="Seed of the global searches.")] = 0,
    column_map: ColumnMapOption = None,
    const: ConstantsOption = None,
    json_out: Annotated[
        Path | None,
        typer.Option("--json", help="Write the table, tests and selection as JSON ('-': stdout)."),
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html and figures.")
    ] = None,
    save_model: Annotated[
        Path | None,
        typer.Option("--save-model", help="Write the selected fitted model (.json or .toml)."),
    ] = None,
) -> None:
    """Fit candidate models to DATA by maximum likelihood on the same samples and choose one.

    Prints log-likelihood, number of parameters, AIC, BIC and the whiteness of each candidate's
    innovations; likelihood-ratio tests between the pairs where one model is nested in the other
    (detected from the networks); and the selected model. Candidates that measure different
    outputs (two coupled rooms fitted jointly, and one room with the neighbour's measured
    temperature as a boundary) are compared on the likelihood of their common outputs
    conditional on the others' measurements, with Vuong's test between non-nested pairs. Exit code 0; 3 when the selected
    model's fit is flagged; 2 for a mistake in the input.
    """
    from rczone.cli.commands_fit import _save, _starts
    from rczone.cli.common import check_seed
    from rczone.cli.console import console as make_console
    from rczone.errors import ParameterError

    check_seed(seed)
    from rczone.selection.compare import family_candidates, select_models

    n_starts = _starts(starts)
    criterion = criterion.strip().lower()
    if criterion not in ("bic", "aic"):
        raise ParameterError(f"--criterion must be bic or aic, got {criterion!r}")
    console = make_console(stderr=True)
    out = out_console(json_out)
    label = data_label(data)
    if models:
        zms = [model(m) for m in models]
        frame = _read(data, column_map, zms)
    else:
        from rczone.models import load_model

        widest = load_model("TiTeTh+heater+solar+gain+air")
        frame = _read(data, column_map, [widest], required=list(widest.network.outputs))
        zms = [model(m) for m in family_candidates(list(frame.columns))]
        out.print("candidates: " + ", ".join(esc(zm.label) for zm in zms))
    if len(zms) < 2:
        raise ParameterError("give at least two candidate models (--model A --model B ...)")

    def progress(name: str) -> None:
        console.print(f"fitting {esc(name)} (ML)")

    with console.status(f"selecting among {len(zms)} models on {esc(label)}"):
        sel = select_models(
            zms,
            frame,
            constants(const),
            rule=criterion,
            forward=forward,
            alpha=alpha,
            n_starts=n_starts,
            seed=seed,
            progress=progress,
            noise=noise.strip().lower(),
        )
    how = f"forward selection, alpha = {alpha:g}" if forward else criterion.upper()
    title = f"Candidates fitted to {esc(label)} by ML ({sel.samples['n']} samples)"
    if sel.basis is not None and sel.basis.conditional:
        title += f"; log L of {esc(', '.join(sel.basis.targets))} {esc(sel.basis.describe())}"
    out.print(_table(sel, title))
    if sel.basis is not None and sel.basis.conditional:
        out.print(
            f"the candidates measure different outputs: compared on the likelihood of"
            f" {esc(', '.join(sel.basis.targets))} {esc(sel.basis.describe())} (the measured"
            f" {esc(', '.join(sel.basis.given))}, an output of some candidates and an input of the others)"
        )
    if sel.tests:
        out.print(_tests_table(sel))
    elif not sel.vuong:
        out.print("no candidate is nested in another: no likelihood-ratio test")
    if sel.vuong:
        out.print(_vuong_table(sel))
    for step in sel.steps:
        verdict = "accepted" if step["accepted"] else "rejected: stop"
        out.print(
            f"forward: {esc(step['from'])} -> {esc(step['best'])} (of {', '.join(map(esc, step['tried']))}):"
            f" LR {step['statistic']:.2f}, df {step['df']}, p = {step['p_value']:.3g}, {verdict}"
        )
    if sel.not_fitted:
        out.print("not reached (not fitted): " + ", ".join(map(esc, sel.not_fitted)))
    best = sel.best
    out.print(f"selected: [bold]{esc(sel.selected)}[/] ({how})")
    out.print(
        f"the same fit alone: rczone fit {esc(data)} --model {esc(sel.selected)} --noise {esc(noise.strip().lower())};"
        " check its open-loop prediction on held-out data (rczone predict) before using it for control:"
        " process noise on every state raises the likelihood but can leave the deterministic part poor"
    )
    inn = best.calibration.innovations
    if inn is not None and not inn.white:
        out.print(
            f"[yellow]warning:[/] the innovations of {esc(sel.selected)} are not white (Ljung-Box p ="
            f" {inn.ljung_box_p:.2g}): every candidate misses some dynamics or input"
        )
    for f in best.calibration.result.flags:
        out.print(f"[yellow]warning:[/] {esc(sel.selected)}: {esc(f)}")
    trusted = best.calibration.result.trustworthy
    if json_out:
        write_json(
            json_out,
            {
                "data": label,
                **sel.to_dict(),
                "exit_code": 0 if trusted else EXIT_UNTRUSTED,
            },
        )
    if save_model:
        _save(best.calibration.model, save_model)
        out.print(f"model written to [bold]{esc(save_model)}[/]")
    if report_dir:
        from rczone.report.select import selection_report

        selection_report(sel, label).write(report_dir)
        out.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    if not trusted:
        out.print(f"[red]the selected model's fit is flagged[/] (exit code {EXIT_UNTRUSTED})")
        raise typer.Exit(EXIT_UNTRUSTED)
