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
    OptionsOption,
    QuietOption,
    bounds,
    check_on_items,
    check_seed,
    constants,
    data_label,
    esc,
    fixed,
    free_list,
    method_options,
    model,
    out_console,
    parameter_kinds,
    read_frame,
    write_json,
)
from rczone.cli.main import app
from rczone.cli.progress import reporter
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
            help="Local method: auto (Gauss-Newton on the residual Jacobian for --method ls, L-BFGS with"
            " exact gradients otherwise), nelder-mead, powell or lbfgs. Not with --method mcmc."
        ),
    ] = "auto",
    starts: Annotated[
        str,
        typer.Option(
            help="Local searches: auto (global search over the bounds, default), 1 (one local search from"
            " the model's values) or N. Not with --method mcmc (one L-BFGS search places its chains)."
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
            " predict them with this fit. FILE:MAP.toml reads FILE with its own column map (a twin"
            " building with other column names); without, the --columns map is used.",
        ),
    ] = None,
    profiles: Annotated[
        bool,
        typer.Option(
            help="Profile each R and C over a factor of 10 (with --json or --report; a few seconds)."
        ),
    ] = True,
    holdout: Annotated[
        str | None,
        typer.Option(
            "--holdout",
            help="Fit on the data before this time (2009-02-09T12:00, in the column map's time zone) or all"
            " but this last fraction (0.25), then score the rest: one step, 1 h, 6 h, 24 h and open loop,"
            " next to persistence and ARX.",
        ),
    ] = None,
    floor_area: Annotated[
        float | None,
        typer.Option(
            "--floor-area",
            help="Heated floor area, m2: the fitted UA, heat capacity and slowest time constant are judged"
            " against reference ranges per m2 (docs/validation.md) instead of the model's declared values.",
        ),
    ] = None,
    option: OptionsOption = None,
    draws: Annotated[
        int | None, typer.Option(help="--method mcmc: draws kept per chain (default 1000; --option draws=N).")
    ] = None,
    tune: Annotated[
        int | None, typer.Option(help="--method mcmc: warm-up draws per chain, discarded (default 1000).")
    ] = None,
    chains: Annotated[
        int | None, typer.Option(help="--method mcmc: independent chains, --seed seeds them (default 4).")
    ] = None,
    quiet: QuietOption = False,
) -> None:
    """Identify the model's parameters from DATA.

    Exit code 0: a trustworthy fit; 3: the fit finished but is flagged (an estimate at a bound, no
    standard error, an indefinite Hessian, starts that disagree, or for --method mcmc R-hat >= 1.01,
    too few effective draws or divergent transitions; with --holdout also a held-out 2-sigma band
    covering less than 80 % at a horizon, a stable baseline beating the model by more than 10 %, or
    innovations far from white) - every output is still written; 2: a mistake in the input.
    """

    from rczone.files.atomic import refuse_link_in
    from rczone.workflow import FitSettings, fit_and_check
    from rczone.workflow.holdout import before, split_time

    check_seed(seed)
    if floor_area is not None:
        from rczone.models.plausibility import reference_ranges

        reference_ranges(floor_area)  # a bad area is a one-line error before the fit
    zm = model(model_name)
    n_starts = _starts(starts)
    full = read_frame(data, column_map, zm)
    at = split_time(full, holdout, model=zm, columns=column_map)
    if report_dir and at is not None:
        refuse_link_in(report_dir, HELD_OUT)  # before the fit, not after it
    frame = before(full, at)
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
        options=method_options(method, option, draws=draws, tune=tune, chains=chains),
    )
    others = {p: read_frame(Path(p), m, zm) for p, m in check_on_items(check_on, column_map)}
    label = data_label(data)
    with reporter(quiet=quiet) as report:
        cal = fit_and_check(zm, full, settings, label=label, others=others, progress=report, holdout=at)
    if floor_area is not None and cal.plausibility is not None:
        from rczone.calibration.reference import with_floor_area

        cal = with_floor_area(cal, zm, frame, floor_area)
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
        if cal.holdout is not None:
            held_out_report(cal.holdout, report_dir, out)
    if cal.exit_code:
        raise typer.Exit(cal.exit_code)


#: The subfolder of ``--report DIR`` that ``--holdout`` writes its report into.
HELD_OUT = "holdout"


def held_out_report(held, report_dir: Path, out) -> None:
    """``--holdout --report DIR``: the held-out scores' report in ``DIR/holdout``."""
    from rczone.report.predict import horizons_report

    horizons_report(held).write(report_dir, under=HELD_OUT)
    out.print(f"held-out report written to [bold]{esc(report_dir / HELD_OUT / 'report.html')}[/]")


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
    model_file: Annotated[
        str | None,
        typer.Argument(
            metavar="MODEL", help=MODEL_HELP + " Or give it by --model, as other commands, and DATA alone."
        ),
    ] = None,
    data: Annotated[
        Path | None,
        typer.Argument(metavar="DATA", help="CSV/Parquet file, or a built-in data set name (A, B, C)."),
    ] = None,
    model_opt: Annotated[
        str | None, typer.Option("--model", help="The model, as other commands take it (then DATA alone).")
    ] = None,
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
            help="Open loop: start the unmeasured nodes (walls, furniture) at the Kalman filter's estimate"
            " after the warm-up ('warmup', default; without --warmup from the first sample only: the others"
            " at the steady state for its inputs), at that steady state ('steady'), or at temperatures fitted"
            " to the scored data themselves ('estimated': uses the data it scores, not a held-out score).",
        ),
    ] = "warmup",
    hold: Annotated[
        str | None,
        typer.Option(
            "--hold",
            help="Inputs between samples: held (zoh) or linear (foh); default the one the model was fitted with.",
        ),
    ] = None,
    warmup: Annotated[
        str | None,
        typer.Option(
            "--warmup",
            help="The first part of DATA only warms the filter up and is not scored: a duration (1d, 6h,"
            " 30min) or the time the scored part starts (2009-02-09T12:00, in the column map's time zone).",
        ),
    ] = None,
    horizons: Annotated[
        str | None,
        typer.Option(
            "--horizons",
            help="Score several horizons at once, comma-separated steps ahead and 'open' (e.g."
            " 1,12,72,open): one table of RMSE, MAE, bias and 2-sigma coverage per horizon.",
        ),
    ] = None,
    baselines: Annotated[
        bool,
        typer.Option(
            "--baselines",
            help="Score 'persistence' (the measurement at the origin) and 'arx' (an ARX(2,2) model fitted by"
            " least squares on the model's calibration data) next to the model.",
        ),
    ] = False,
    conformal: Annotated[
        str | None,
        typer.Option(
            "--conformal",
            help="Replace the k-step bands by split conformal ones calibrated on the last part of the"
            " warm-up, this long (e.g. 1d, 12h); needs --warmup. Scores per horizon as --horizons.",
        ),
    ] = None,
    online: Annotated[
        bool,
        typer.Option(
            "--online",
            help="With --conformal: update the bands while predicting (adaptive conformal inference) and"
            " watch the model for drift.",
        ),
    ] = False,
) -> None:
    """Predict DATA with a model, open loop or k steps ahead: the error, the series and a 2-sigma band.

    The band adds the process and measurement noise of a model fitted by ML (widened per horizon
    by the factors its fit calibrated on its own errors; or the RMSE of an LS fit) and the
    uncertainty of the estimates saved with a fitted model. No prediction uses a measurement after
    its start. The series file (-o) also has every node's estimated temperature.
    """
    from rczone.calibration import prediction
    from rczone.errors import ParameterError
    from rczone.validation import integer, steps_ahead

    if model_opt is not None:
        if data is not None:
            raise ParameterError(
                "give the model once: `rczone predict --model MODEL DATA` or `rczone predict MODEL DATA`"
            )
        model_file, data = model_opt, None if model_file is None else Path(model_file)
    if model_file is None or data is None:
        raise ParameterError("rczone predict needs a model and data: `rczone predict --model MODEL DATA`")
    if steps is not None:
        integer(steps, "--steps", low=1)
    zm = model(model_file)
    frame = read_frame(data, column_map, zm)
    if steps is not None:
        steps_ahead(steps, len(frame), "--steps")
    label = data_label(data)
    from rczone.workflow.holdout import split_time

    start = split_time(frame, warmup, model=zm, columns=column_map, warmup=True)
    from rczone.workflow.holdout import conformal_settings

    settings = conformal_settings(conformal, online, start)
    if horizons is not None or baselines or settings is not None:
        from rczone.calibration.horizons import horizon_scores, parse_horizons
        from rczone.report.predict import horizons_report

        if steps is not None and horizons is not None:
            raise ParameterError("give --steps or --horizons, not both")
        chosen = parse_horizons(horizons) if horizons is not None else [steps or 1]
        scores = horizon_scores(
            zm,
            frame,
            constants(const),
            horizons=chosen,
            baselines=baselines,
            start=start,
            label=label,
            hold=hold,
            conformal=settings,
        )
        _emit(scores, lambda: horizons_report(scores), json_out, out, report_dir)
        return
    from rczone.report.predict import prediction_report

    pred = prediction(
        zm,
        frame,
        constants(const),
        steps=steps,
        initial_state=initial_state,
        label=label,
        start=start,
        hold=hold,
    )
    _emit(pred, lambda: prediction_report(pred, label, zm.label), json_out, out, report_dir)


def _emit(result, report, json_out: Path | None, out: Path | None, report_dir: Path | None) -> None:
    """Print a prediction result's summary, write its series, its report (built by ``report()``) and its JSON."""
    console = out_console(json_out)
    for line in result.summary_lines():
        console.print(line)
    if out is not None:
        result.write(out)
        console.print(f"series written to [bold]{esc(out)}[/]")
    if report_dir is not None:
        report().write(report_dir)
        console.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    write_json(json_out, result.to_dict())
