"""``rczone select``: fit candidate models to the same data and choose one."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import (
    MODEL_HELP,
    BoundsOption,
    ColumnMapOption,
    ConstantsOption,
    FixOption,
    HoldOption,
    QuietOption,
    bounds,
    constants,
    data_label,
    esc,
    fixed,
    free_list,
    model,
    out_console,
    parameter_kinds,
    write_json,
)
from rczone.cli.main import app
from rczone.cli.progress import Steps, reporter


def _read(data: Path, column_map: Path | None, zms: list, required: list[str] | None = None) -> object:
    """The data with every candidate's signals (:func:`rczone.workflow.api.read_for_models`)."""
    from rczone.cli.common import note_ignored
    from rczone.workflow.api import read_for_models

    frame = read_for_models(data, column_map, zms, required)
    note_ignored(frame, column_map, "no candidate uses")
    return frame


@app.command()
def select(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    models: Annotated[
        list[str] | None,
        typer.Option(
            "--model",
            help=MODEL_HELP + " Repeat for each candidate (at least two). Default: the Bacher & Madsen"
            " family (Ti, TiTe, TiTh, TiTeTh, TiTm; with --forward every model of the family, Tm, Te, Th,"
            " Tsn, Ae, As and Ria added one at a time) with the inputs the data have (Ph, Ps, Q, m and Ts).",
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
    hold: HoldOption = "zoh",
    bound: BoundsOption = None,
    free: Annotated[
        list[str] | None,
        typer.Option(
            metavar="+NAME",
            help="Estimate NAME too in every candidate that has it, e.g. --free +x0_Te or, with --noise"
            " measured, --free +sigma_w_Te (repeatable or comma-separated).",
        ),
    ] = None,
    fix: FixOption = None,
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
    holdout: Annotated[
        str | None,
        typer.Option(
            "--holdout",
            help="Select on the data before this time (2009-02-09T12:00) or all but this last fraction"
            " (0.25), then score the selected model on the rest next to persistence and ARX.",
        ),
    ] = None,
    quiet: QuietOption = False,
) -> None:
    """Fit candidate models to DATA by maximum likelihood on the same samples and choose one.

    Prints log-likelihood, number of parameters, AIC, BIC and the whiteness of each candidate's
    innovations; likelihood-ratio tests between the pairs where one model is nested in the other
    (detected from the networks); and the selected model. Candidates that measure different
    outputs (two coupled rooms fitted jointly, and one room with the neighbour's measured
    temperature as a boundary) are compared on the likelihood of their common outputs
    conditional on the others' measurements, with Vuong's test between non-nested pairs. Exit code 0; 3 when the selected
    model's fit is flagged (with --holdout also when it fails a held-out check, as rczone fit
    --holdout: a 2-sigma band covering less than 80 % at a horizon, a stable baseline beating it by
    more than 10 %, or innovations far from white); 2 for a mistake in the input.
    """
    import dataclasses

    from rczone.cli.commands_fit import _save, _starts, held_out_report
    from rczone.cli.common import check_seed
    from rczone.errors import ParameterError

    check_seed(seed)
    from rczone.selection.compare import family_candidates, select_models, with_held_out
    from rczone.selection.text import fit_arguments

    n_starts = _starts(starts)
    criterion = criterion.strip().lower()
    if criterion not in ("bic", "aic"):
        raise ParameterError(f"--criterion must be bic or aic, got {criterion!r}")
    out = out_console(json_out)
    label = data_label(data)
    hold = hold.strip().lower()
    specs: dict[str, str] = {}
    if models:
        zms = [model(m) for m in models]
        specs = {zm.label: m for zm, m in zip(zms, models)}
        frame = _read(data, column_map, zms)
    else:
        from rczone.models import load_model

        widest = load_model("TiTeTh+heater+solar+gain+air")
        frame = _read(data, column_map, [widest], required=list(widest.network.outputs))
        zms = [model(m) for m in family_candidates(list(frame.columns), extended=forward)]
        if forward:
            out.print(
                f"candidates: the Bacher & Madsen family, {len(zms)} models grown one part at a time from {esc(zms[0].label)}"
            )
        else:
            out.print("candidates: " + ", ".join(esc(zm.label) for zm in zms))
    if len(zms) < 2:
        raise ParameterError("give at least two candidate models (--model A --model B ...)")
    from rczone.estimation.settings import FitSettings
    from rczone.workflow.holdout import before, score_held_out, split_time

    full = frame
    at = split_time(frame, holdout, model=zms[0], columns=column_map)
    if report_dir and at is not None:
        from rczone.cli.commands_fit import HELD_OUT
        from rczone.files.atomic import refuse_link_in

        refuse_link_in(report_dir, HELD_OUT)  # before the fits, not after them
    frame = before(full, at)
    box = bounds(bound, parameter_kinds(*zms))
    held = fixed(fix, parameter_kinds(*zms))
    settings = FitSettings(
        method="ml",
        free=free_list(free),
        fixed=held,
        bounds=box,
        hold=hold,
        n_starts=n_starts,
        seed=seed,
        noise=noise.strip().lower(),
        constants=constants(const) or {},
    )

    with reporter(quiet=quiet) as report:
        progress = Steps(report, len(zms), "fitting {name} (ML), candidate {i} of {n}")
        sel = select_models(
            zms, frame, settings, rule=criterion, forward=forward, alpha=alpha, progress=progress
        )
        if at is not None:
            held = score_held_out(sel.best.calibration.model, full, at, settings.constants, label)
            sel = with_held_out(sel, held)  # its checks enter the selected fit's verdict and exit code
    sel = dataclasses.replace(
        sel,
        data_label=label,
        source=str(data),
        noise=noise.strip().lower(),
        fit_args=fit_arguments(sel, settings, columns=column_map),
        model_specs=specs,
    )
    from rczone.results.protocol import print_lines

    print_lines(out, sel.summary_lines())  # the command to paste stays one line
    best = sel.best
    write_json(json_out, sel.to_dict())
    if save_model:
        _save(best.calibration.model, save_model)
        out.print(f"model written to [bold]{esc(save_model)}[/]")
    if report_dir:
        from rczone.report.select import selection_report

        selection_report(sel, label).write(report_dir)
        out.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
        if sel.holdout is not None:
            held_out_report(sel.holdout, report_dir, out)
    if sel.exit_code:
        raise typer.Exit(sel.exit_code)
