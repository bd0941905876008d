"""``rczone fit`` and ``rczone predict``: identify R and C from data, and use the fitted model."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import (
    EXIT_UNTRUSTED,
    MODEL_HELP,
    check_seed,
    constants,
    data_label,
    esc,
    model,
    out_console,
    read_frame,
    split,
    write_json,
)
from rczone.cli.main import app

_FLAG_TEXT = {"at_bound": "at bound"}


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


def _parameter_table(r, title: str):
    """The estimates with units, standard errors, construction values and a flag per parameter."""
    from rich.table import Table

    table = Table(title=title)
    table.add_column("parameter", no_wrap=True)
    for c in ("estimate", "unit", "std. error", "construction", "ratio", "flag"):
        table.add_column(c, overflow="fold")
    search = r.search
    for n in r.names:
        c = r.construction[n]
        ratio = r.ratio_to_construction(n)
        se = r.std_errors[n]
        flags = []
        if r.at_bound[n] and not any(n in note for note in r.notes):
            flags.append("[red]at bound[/]")
        elif r.at_bound[n]:
            flags.append("[dim]at floor[/]")
        if not math.isfinite(se) and not r.at_bound[n]:
            flags.append("[red]no std. error[/]")
        if search is not None and search.n_best >= 2 and n in search.spread:
            lo, hi = search.spread[n]
            if lo > 0 and hi / lo > 1.1 and r.units.get(n, "") in ("K/W", "J/K"):
                flags.append(f"[yellow]starts: x{hi / lo:.2g}[/]")
        table.add_row(
            esc(n),
            f"{r.estimates[n]:.4g}",
            esc(r.units.get(n, "")),
            f"{se:.2g}" if math.isfinite(se) else "n/a",
            f"{c:.4g}" if math.isfinite(c) else "",
            f"{ratio:.2f}" if math.isfinite(ratio) else "",
            " ".join(flags),
        )
    return table


def _search_line(r) -> str:
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


@app.command()
def fit(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    method: Annotated[
        str, typer.Option(help="ls (output error), ml (Kalman likelihood) or map (ML + prior).")
    ] = "ml",
    free: Annotated[
        str | None,
        typer.Option(
            help="Comma-separated free parameters (default: the model's, plus noise levels for ML)."
        ),
    ] = None,
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

    from rczone.calibrate import calibrate
    from rczone.estimation.parameters import measurement_noise_names

    check_seed(seed)
    zm = model(model_name)
    n_starts = _starts(starts)
    frame = read_frame(data, column_map, zm)
    consts = constants(const)
    console = Console(stderr=True)
    label = data_label(data)
    with console.status(f"fitting {esc(zm.label)} to {esc(label)} ({method})"):
        cal = calibrate(
            zm,
            frame,
            method,
            split(free),
            optimizer,
            n_starts,
            seed,
            constants=consts,
            provenance={"data": label, "model": zm.label},
            noise=noise,
        )
    r = cal.result
    out = out_console(json_out)
    out.print(_parameter_table(r, f"{esc(zm.label)} fitted to {esc(label)} by {method.upper()}"))
    out.print(_search_line(r))
    out.print(
        f"open-loop RMSE {cal.open_loop.rmse_K:.3f} K, max {cal.open_loop.max_abs_K:.3f} K;"
        f" {r.rmse_kind} RMSE {r.rmse_K:.3f} K; {r.n_evals} evaluations"
    )
    stretch = cal.model.provenance.get("stretch") or {}
    if stretch.get("samples", 0) < stretch.get("of", 0):
        out.print(
            f"[yellow]note:[/] fitted on {stretch['samples']} of {stretch['of']} samples"
            f" ({stretch['fraction']:.0%}), the longest stretch where every input is known"
        )
    per_output = cal.output_errors()
    if len(per_output) > 1:
        out.print(
            "open loop per output: "
            + "; ".join(f"{esc(o)} RMSE {rmse:.3f} K, max {worst:.3f} K" for o, rmse, worst in per_output)
        )
    for line in _residual_lines(cal):
        out.print(line)
    used = cal.model.provenance.get("constants") or {}
    if used:
        out.print("held constant: " + ", ".join(f"{esc(k)} = {v:g}" for k, v in used.items()))
    for note in r.notes:
        out.print(f"note: {esc(note)}")
    for f in r.flags:
        out.print(f"[yellow]warning:[/] {esc(f)}")
    others = {p: read_frame(Path(p), column_map, zm) for p in split(check_on) or []}
    checks = None
    if report_dir or json_out or others:
        checks = _post_fit_checks(
            zm, frame, cal, label, others, profiles, method, split(free), optimizer, console, consts
        )
        for d in checks["disagreements"]:
            if d["disagree"]:
                out.print(
                    f"[yellow]warning:[/] {esc(d['name'])} fitted to {esc(d['data_a'])} ({d['estimate_a']:.3g}) and"
                    f" to {esc(d['data_b'])} ({d['estimate_b']:.3g}) disagree beyond their standard errors"
                )
        for name, v in checks["profiles"].items():
            if v["flat_low"] or v["flat_high"]:
                side = "ten times smaller" if v["flat_low"] else "ten times larger"
                out.print(f"[yellow]warning:[/] a value of {esc(name)} {side} fits these data about as well")
    diag = None
    if report_dir or json_out:
        from rczone.diagnostics import diagnose

        rc = [n for n in r.names if n in zm.network.parameters and cal.model.theta[n] > 0]
        if rc:
            diag = diagnose(
                cal.model, frame, free=rc, constants=used, heat_input=None, operating_point="model"
            )
    if json_out:
        payload = r.to_dict()
        payload.update(
            data=label,
            model=zm.label,
            data_used=stretch,
            open_loop_rmse_K=cal.open_loop.rmse_K,
            open_loop_max_error_K=cal.open_loop.max_abs_K,
            outputs={
                o: {
                    "open_loop_rmse_K": rmse,
                    "open_loop_max_error_K": worst,
                    "sigma_v_K": r.estimates.get(noise),
                }
                for (o, rmse, worst), noise in zip(
                    per_output, measurement_noise_names(zm.network.outputs), strict=True
                )
            },
            ljung_box_p=cal.residuals.p_value,
            innovations=cal.innovations.to_dict() if cal.innovations is not None else None,
            open_loop_residuals=cal.open_loop_residuals.to_dict() if cal.open_loop_residuals else None,
            constants=used,
            identifiability={
                k: {"verdict": v.verdict, "reason": v.reason} for k, v in diag.parameters.items()
            }
            if diag
            else {},
            checks=checks,
            exit_code=0 if r.trustworthy else EXIT_UNTRUSTED,
        )
        write_json(json_out, payload)
    if save_model:
        _save(cal.model, save_model)
        out.print(f"model written to [bold]{esc(save_model)}[/]")
    if report_dir:
        from rczone.report.fit import fit_report

        fit_report(cal, frame, label, zm.label, diag, checks).write(report_dir)
        out.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    if not r.trustworthy:
        out.print(
            f"[red]result flagged[/] (exit code {EXIT_UNTRUSTED}): do not use these estimates without"
            " checking the warnings above"
        )
        raise typer.Exit(EXIT_UNTRUSTED)


def _residual_lines(cal) -> list[str]:
    """What the residuals say: the innovations of an ML fit, or the labelled open-loop error of LS."""
    an = cal.innovations or cal.open_loop_residuals
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


def _save(zm, path: Path) -> None:
    """A fitted model as JSON (everything) or as a model file (structure and values)."""
    from rczone.atomic import write_text_atomic
    from rczone.errors import ParameterError
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


def _post_fit_checks(
    zm, frame, cal, label, others, profiles, method, free, optimizer, console, consts
) -> dict:
    """Profiles, estimates at bounds or far from construction, and fits to the other data sets."""
    from rczone.calibrate import calibrate, predict
    from rczone.diagnostics.postfit import compare_fits, far_from_construction, profile_checks

    r = cal.result
    used = cal.model.provenance.get("constants")
    prof = {}
    if profiles and len(zm.network.outputs) == 1:
        with console.status("profiling the estimates"):
            prof = {k: v.to_dict() for k, v in profile_checks(zm, frame, r, constants=used).items()}
    fits = {label: r}
    validation = {}
    for name, f in others.items():
        with console.status(f"fitting {esc(name)} for comparison"):
            fits[name] = calibrate(zm, f, method, free, optimizer, constants=consts).result
        ol = predict(cal.model, f, consts)
        validation[name] = {"rmse_K": ol.rmse_K, "max_error_K": ol.max_abs_K}
    return {
        "profiles": prof,
        "at_bound": [n for n in r.names if r.at_bound[n]],
        "far_from_construction": far_from_construction(r),
        "other_fits": {k: {n: v.estimates[n] for n in v.names} for k, v in fits.items() if k != label},
        "disagreements": [{"name": d.name, **d.to_dict()} for d in compare_fits(fits)],
        "validation": validation,
    }


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
    import numpy as np

    from rczone.calibrate import prediction
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
    pred = prediction(zm, frame, constants(const), steps=steps, initial_state=initial_state)
    console = out_console(json_out)
    start = pred.initial_state
    if start is not None and start.sd:
        console.print(
            "initial temperatures of the unmeasured nodes, estimated from the data (steady state for the"
            " first sample in brackets): "
            + ", ".join(
                f"{esc(k.removeprefix('x0_'))} {start.values[k]:.2f} ({start.steady[k]:.2f}) ± {sd:.2f} K"
                for k, sd in start.sd.items()
            )
        )
    for j, o in enumerate(zm.network.outputs):
        console.print(
            f"{esc(label)}: {esc(o)} {pred.horizon} RMSE {pred.rmse_K[j]:.3f} K, max error {pred.max_abs_K[j]:.3f} K;"
            f" {pred.coverage[j]:.0%} of the measurements inside the 2-sigma band ({esc(pred.band_source)})"
        )
    if out is not None:
        pred.write(out)
        console.print(f"series written to [bold]{esc(out)}[/]")
    if report_dir is not None:
        from rczone.report.predict import prediction_report

        prediction_report(pred, label, zm.label).write(report_dir)
        console.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")
    if json_out:
        write_json(
            json_out,
            {
                "model": zm.label,
                "data": label,
                "rmse_K": float(pred.rmse_K[0])
                if len(pred.rmse_K) == 1
                else dict(zip(pred.outputs, map(float, pred.rmse_K))),
                "max_error_K": float(pred.max_abs_K[0])
                if len(pred.max_abs_K) == 1
                else dict(zip(pred.outputs, map(float, pred.max_abs_K))),
                "band": pred.band_source,
                "horizon": pred.horizon,
                "steps": pred.steps,
                "initial_state": {
                    k.removeprefix("x0_"): {
                        "estimate_degC": v,
                        "steady_degC": start.steady[k],
                        "sd_K": start.sd[k],
                    }
                    for k, v in start.values.items()
                    if k in start.sd
                }
                if start is not None
                else None,
                "coverage_2sigma": dict(zip(pred.outputs, map(float, pred.coverage))),
                "mean_sd_K": {
                    part: {o: float(np.nanmean(a[:, j])) for j, o in enumerate(pred.outputs)}
                    for part, a in (("noise", pred.sd_noise), ("estimates", pred.sd_parameters))
                    if a is not None and np.isfinite(a).any()
                },
            },
        )
