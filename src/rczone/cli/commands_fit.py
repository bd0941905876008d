"""``rczone fit`` and ``rczone predict``: identify R and C from data, and use the fitted model."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from rczone.cli.common import model, read_frame
from rczone.cli.main import app


def _split(text: str | None) -> list[str] | None:
    return [s.strip() for s in text.split(",") if s.strip()] if text else None


@app.command()
def fit(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    model_name: Annotated[str, typer.Option("--model", help="Model name.")] = "second-order-paper",
    method: Annotated[
        str, typer.Option(help="ls (output error), ml (Kalman likelihood) or map (ML + prior).")
    ] = "ml",
    free: Annotated[str | None, typer.Option(help="Comma-separated free parameters.")] = None,
    optimizer: Annotated[str, typer.Option(help="nelder-mead, powell or lbfgs.")] = "nelder-mead",
    starts: Annotated[
        int, typer.Option(help="Number of starts (Latin hypercube around construction values).")
    ] = 1,
    seed: Annotated[int, typer.Option(help="Seed of the multistart draw.")] = 0,
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write estimates and statistics as JSON.")
    ] = None,
    save_model: Annotated[
        Path | None, typer.Option("--save-model", help="Write the fitted model as JSON.")
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
    """Identify the model's R and C from DATA."""
    from rczone.atomic import write_json_atomic
    from rczone.calibrate import calibrate

    net = model(model_name)
    frame = read_frame(data, column_map)
    console = Console(stderr=True)
    with console.status(f"fitting {model_name} to {data.name} ({method})"):
        cal = calibrate(
            net,
            frame,
            method,
            _split(free),
            optimizer,
            starts,
            seed,
            provenance={"data": str(data), "model": model_name},
        )
    r = cal.result
    table = Table(title=f"{model_name} fitted to {data.name} by {method.upper()}")
    for c in ("parameter", "estimate", "std. error", "construction", "ratio", ""):
        table.add_column(c)
    for n in r.names:
        c = r.construction[n]
        ratio = r.ratio_to_construction(n)
        table.add_row(
            n,
            f"{r.estimates[n]:.4g}",
            f"{r.std_errors[n]:.2g}",
            f"{c:.4g}" if c == c else "",
            f"{ratio:.2f}" if ratio == ratio else "",
            "[red]at bound[/]" if r.at_bound[n] else "",
        )
    out = Console()
    out.print(table)
    out.print(
        f"open-loop RMSE {cal.open_loop.rmse_K:.3f} K, max {cal.open_loop.max_abs_K:.3f} K; {r.n_evals} evaluations"
    )
    for f in r.flags:
        out.print(f"[yellow]warning:[/] {f}")
    others = {p: read_frame(Path(p), column_map) for p in _split(check_on) or []}
    checks = None
    if report_dir or json_out or others:
        checks = _post_fit_checks(
            net, frame, cal, data, others, profiles, method, _split(free), optimizer, console
        )
        for d in checks["disagreements"]:
            if d["disagree"]:
                out.print(
                    f"[yellow]warning:[/] {d['name']} fitted to {d['data_a']} ({d['estimate_a']:.3g}) and to"
                    f" {d['data_b']} ({d['estimate_b']:.3g}) disagree beyond their standard errors"
                )
        for name, v in checks["profiles"].items():
            if v["flat_low"] or v["flat_high"]:
                side = "ten times smaller" if v["flat_low"] else "ten times larger"
                out.print(f"[yellow]warning:[/] a value of {name} {side} fits these data about as well")
    diag = None
    if report_dir or json_out:
        from rczone.diagnostics import diagnose

        rc = [n for n in r.names if n in net.parameters]
        if rc:
            diag = diagnose(net, frame, free=rc, constants=cal.model.provenance.get("constants"))
    if json_out:
        payload = r.to_dict()
        payload.update(
            data=str(data),
            model=model_name,
            open_loop_rmse_K=cal.open_loop.rmse_K,
            open_loop_max_error_K=cal.open_loop.max_abs_K,
            ljung_box_p=cal.residuals.p_value,
            identifiability={
                k: {"verdict": v.verdict, "reason": v.reason} for k, v in diag.parameters.items()
            }
            if diag
            else {},
            checks=checks,
        )
        write_json_atomic(json_out, payload)
    if save_model:
        cal.model.save(save_model)
        out.print(f"model written to [bold]{save_model}[/]")
    if report_dir:
        from rczone.report.fit import fit_report

        fit_report(cal, frame, str(data), model_name, diag, checks).write(report_dir)
        out.print(f"report written to [bold]{report_dir / 'report.html'}[/]")


def _post_fit_checks(net, frame, cal, data, others, profiles, method, free, optimizer, console) -> dict:
    """Profiles, estimates at bounds or far from construction, and fits to the other data sets."""
    from rczone.calibrate import calibrate, predict
    from rczone.diagnostics.postfit import compare_fits, far_from_construction, profile_checks

    r = cal.result
    constants = cal.model.provenance.get("constants")
    prof = {}
    if profiles:
        with console.status("profiling the estimates"):
            prof = {k: v.to_dict() for k, v in profile_checks(net, frame, r, constants=constants).items()}
    fits = {str(data): r}
    validation = {}
    for name, f in others.items():
        with console.status(f"fitting {name} for comparison"):
            fits[name] = calibrate(net, f, method, free, optimizer).result
        ol = predict(cal.model, f)
        validation[name] = {"rmse_K": ol.rmse_K, "max_error_K": ol.max_abs_K}
    return {
        "profiles": prof,
        "at_bound": [n for n in r.names if r.at_bound[n]],
        "far_from_construction": far_from_construction(r),
        "other_fits": {k: {n: v.estimates[n] for n in v.names} for k, v in fits.items() if k != str(data)},
        "disagreements": [{"name": d.name, **d.to_dict()} for d in compare_fits(fits)],
        "validation": validation,
    }


@app.command()
def predict(
    model_file: Annotated[Path, typer.Argument(help="Model JSON written by `rczone fit --save-model`.")],
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    json_out: Annotated[Path | None, typer.Option("--json", help="Write RMSE and max error as JSON.")] = None,
) -> None:
    """Simulate a saved model open loop on DATA and report the error."""
    from rczone.atomic import write_json_atomic
    from rczone.calibrate import predict as run
    from rczone.mpc import ZoneModel

    zm = ZoneModel.load(model_file)
    frame = read_frame(data, column_map)
    ol = run(zm, frame)
    Console().print(f"{data.name}: open-loop RMSE {ol.rmse_K:.3f} K, max error {ol.max_abs_K:.3f} K")
    if json_out:
        write_json_atomic(
            json_out,
            {"model": str(model_file), "data": str(data), "rmse_K": ol.rmse_K, "max_error_K": ol.max_abs_K},
        )
