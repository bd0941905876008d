"""``rczone fit`` and ``rczone predict``: identify R and C from data, and use the fitted model."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import (
    MODEL_HELP,
    BoundsOption,
    FixOption,
    HoldOption,
    bounds,
    check_seed,
    constants,
    data_label,
    esc,
    fixed,
    free_list,
    model,
    out_console,
    parameter_kinds,
    read_frame,
    split,
    write_json,
)
from rczone.cli.main import app
from rczone.estimation.methods import DEFAULT_METHOD, REGISTRY

#: The methods of the registry, for --help.
METHOD_HELP = "; ".join(f"{m.name}: {m.title}" for m in REGISTRY.values()) + "."


def _starts(text: str) -> int | None:
    from rczone.errors import ParameterError

    if text.strip().lower() == "auto":
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise ParameterError(f"--starts must be 'auto' or a positive integer, got {text!r}")
    return n


@app.command()
def fit(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    method: Annotated[str, typer.Option(help=METHOD_HELP)] = DEFAULT_METHOD,
    free: Annotated[
        list[str] | None,
        typer.Option(
            metavar="NAMES|+NAME",
            help="Free parameters, comma-separated or repeated (default: the model's, plus noise levels"
            " for ML); +NAME adds NAME to the default set instead, e.g. --free +sigma_w_Te.",
        ),
    ] = None,
    fix: FixOption = None,
    bound: BoundsOption = None,
    hold: HoldOption = "zoh",
    optimizer: Annotated[
        str,
        typer.Option(
            help="Local method: auto (compiled Nelder-Mead for 2-state models, L-BFGS with exact gradients"
            " otherwise), nelder-mead, powell or lbfgs."
        ),
    ] = "auto",
    starts: Annotated[
        str,
        typer.Option(
            help="Local searches: auto (global search over the bounds, default), 1 (one local search from"
            " the model's values) or N."
        ),
    ] = "auto",
    seed: Annotated[int, typer.Option(help="Seed of the global search.")] = 0,
    noise: Annotated[
        str,
        typer.Option(
            help="ML/MAP process noise on the measured states (default: the model's R and C must explain"
            " the rest) or on all states."
        ),
    ] = "measured",
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    const: Annotated[
        list[str] | None,
        typer.Option(
            "--const", help="Hold an input constant, NAME=VALUE in SI units (repeatable), e.g. Q=50."
        ),
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write estimates and statistics as JSON ('-': stdout).")
    ] = None,
    save_model: Annotated[
        Path | None,
        typer.Option(
            "--save-model", help="Write the fitted model (.json keeps everything; .toml a model file)."
        ),
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html and figures.")
    ] = None,
    check_on: Annotated[
        str | None,
        typer.Option(
            "--check-on",
            help="Comma-separated other data (files or A, B, C): fit them too, compare the estimates and"
            " predict them with this fit.",
        ),
    ] = None,
    profiles: Annotated[
        bool,
        typer.Option(
            help="Profile each R and C over a factor of 10 (with --json or --report; a few seconds)."
        ),
    ] = True,
) -> None:
    """Identify the model's parameters from DATA.

    Exit code 0: a trustworthy fit; 3: the fit finished but is flagged (an estimate at a bound, no
    standard error, an indefinite Hessian, or starts that disagree) - every output is still
    written; 2: a mistake in the input.
    """
    from rich.console import Console

    from rczone.workflow import FitSettings, fit_and_check

    check_seed(seed)
    zm = model(model_name)
    n_starts = _starts(starts)
    frame = read_frame(data, column_map, zm)
    settings = FitSettings(
        method=method,
        free=free_list(free),
        fixed=fixed(fix, parameter_kinds(zm)),
        bounds=bounds(bound, parameter_kinds(zm)),
        hold=hold.strip().lower(),
        optimizer=optimizer,
        n_starts=n_starts,
        seed=seed,
        noise=noise,
        constants=constants(const) or {},
        checks=bool(report_dir or json_out),
        profiles=profiles,
    )
    others = {p: read_frame(Path(p), column_map, zm) for p in split(check_on) or []}
    label = data_label(data)
    with Console(stderr=True).status("fitting") as status:
        cal = fit_and_check(
            zm, frame, settings, label=label, others=others, progress=lambda m: status.update(esc(m))
        )
    out = out_console(json_out)
    for line in cal.summary_lines():
        out.print(line)
    if json_out:
        write_json(json_out, cal.to_dict())
    if save_model:
        _save(cal.model, save_model)
        out.print(f"model written to [bold]{esc(save_model)}[/]")
    if report_dir:
        from rczone.report.fit import fit_report

        fit_report(cal, frame, label, zm.label, cal.identifiability, cal.checks).write(report_dir)
        out.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    if cal.exit_code:
        raise typer.Exit(cal.exit_code)


def _save(zm, path: Path) -> None:
    """A fitted model as JSON (everything) or as a model file (structure and values)."""
    from rczone.errors import ParameterError
    from rczone.files.atomic import write_text_atomic
    from rczone.models import model_to_toml

    suffix = path.suffix.lower()
    if suffix == ".toml":
        header = f"fitted by rczone ({zm.provenance.get('method', '?')}) to {zm.provenance.get('data', '?')}"
        write_text_atomic(path, model_to_toml(zm, header=header))
    elif suffix == ".json":
        zm.save(path)
    else:
        raise ParameterError(
            f"--save-model must end in .json (everything) or .toml (a model file), got {str(path)!r}"
        )


@app.command()
def predict(
    model_file: Annotated[str, typer.Argument(help=MODEL_HELP)],
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    const: Annotated[
        list[str] | None,
        typer.Option("--const", help="Hold an input constant, NAME=VALUE in SI units (repeatable)."),
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write RMSE and max error as JSON ('-': stdout).")
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="Write the series (time, measured, predicted, lower and upper 2-sigma band) as .csv or .parquet.",
        ),
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html with the prediction plot.")
    ] = None,
    steps: Annotated[
        int | None,
        typer.Option(
            "--steps",
            help="Predict each sample this many steps ahead from the Kalman filter (needs a model fitted"
            " by ML); default open loop.",
        ),
    ] = None,
    initial_state: Annotated[
        str,
        typer.Option(
            "--initial-state",
            help="Open loop: start the unmeasured nodes (walls, furniture) at temperatures estimated from"
            " DATA ('estimated') or at the steady state for the first sample ('steady').",
        ),
    ] = "estimated",
) -> None:
    """Predict DATA with a model, open loop or k steps ahead: the error, the series and a 2-sigma band.

    The band adds the process and measurement noise of a model fitted by ML (or the RMSE of an
    LS fit) and the uncertainty of the estimates saved with a fitted model.
    """
    from rczone.calibration import prediction
    from rczone.errors import ParameterError

    if steps is not None and steps < 1:
        raise ParameterError(f"--steps must be a positive integer, got {steps}")
    zm = model(model_file)
    frame = read_frame(data, column_map, zm)
    if steps is not None and steps >= len(frame):
        raise ParameterError(
            f"--steps {steps} is not less than the {len(frame)} samples of {data_label(data)}: no sample would"
            " be predicted; give fewer steps"
        )
    label = data_label(data)
    pred = prediction(zm, frame, constants(const), steps=steps, initial_state=initial_state, label=label)
    console = out_console(json_out)
    for line in pred.summary_lines():
        console.print(line)
    if out is not None:
        pred.write(out)
        console.print(f"series written to [bold]{esc(out)}[/]")
    if report_dir is not None:
        from rczone.report.predict import prediction_report

        prediction_report(pred, label, zm.label).write(report_dir)
        console.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    write_json(json_out, pred.to_dict())
