"""``rczone diagnose`` and ``rczone design``: can these data identify the parameters, and a test that can."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import MODEL_HELP, esc, model, read_frame, split, write_json
from rczone.cli.main import app

VERDICT_STYLE = {"identifiable": "green", "weak": "yellow", "not identifiable": "red"}


def _pair(text: str, what: str) -> tuple[float, float]:
    from rczone.errors import ParameterError

    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise ParameterError(f"--{what} must be two numbers 'low,high', got {text!r}") from None
    return lo, hi


def _rc(net) -> list[str]:
    """The model's default free resistances and capacities."""
    return [n for n in net.default_free if net.parameters[n].kind in ("resistance", "capacitance")]


@app.command()
def diagnose(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    free: Annotated[
        str | None,
        typer.Option(help="Comma-separated free parameters (default: the model's free R and C)."),
    ] = None,
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    sigma: Annotated[
        float, typer.Option(help="Error level a fit must see through (sensor noise + model error), K.")
    ] = 0.1,
    q: Annotated[
        float | None,
        typer.Option(
            "--q", help="Constant internal gain Q in W if the data have none (default: the model's)."
        ),
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write the verdicts and evidence as JSON ('-': stdout).")
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html and figures.")
    ] = None,
) -> None:
    """Tell, before fitting, whether DATA can identify the model's parameters, and why."""
    from rich.table import Table

    from rczone.cli.common import out_console
    from rczone.diagnostics import diagnose as run

    zm = model(model_name)
    net = zm.network
    frame = read_frame(data, column_map, zm)
    free_list = split(free) or _rc(net)
    constants = zm.constants_used(frame, {"Q": q} if q is not None else None) or None
    rep = run(net, frame, free=free_list, theta=dict(zm.theta), sigma_K=sigma, constants=constants)
    table = Table(title=f"Can {esc(data.name)} identify {esc(zm.label)}?")
    for c in ("parameter", "construction", "expected ± (rel.)", "verdict", "reason"):
        table.add_column(c, overflow="fold")
    for name, v in rep.parameters.items():
        style = VERDICT_STYLE[v.verdict]
        table.add_row(
            esc(name),
            f"{v.construction:.4g}",
            f"{v.expected_rel_se:.0%}",
            f"[{style}]{v.verdict}[/]",
            esc(v.reason),
        )
    console = out_console(json_out)
    console.print(table)
    for name, v in rep.parameters.items():
        if v.advice:
            console.print(f"[bold]{esc(name)}[/]: {esc(v.advice)}")
    if json_out:
        write_json(json_out, {"data": data.name, "model": zm.label, **rep.to_dict()})
    if report_dir:
        from rczone.report.diagnose import diagnose_report

        diagnose_report(rep, frame, data.name, zm.label).write(report_dir)


@app.command()
def design(
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    free: Annotated[
        str | None,
        typer.Option(
            help="Comma-separated parameters the test should identify (default: the model's R and C)."
        ),
    ] = None,
    hours: Annotated[float, typer.Option(help="Length of the test, h.")] = 12.0,
    ts_range: Annotated[str, typer.Option(help="Supply-air temperature range 'low,high', degC.")] = "12,35",
    m_range: Annotated[str, typer.Option(help="Supply mass-flow range 'low,high', kg/s.")] = "0.02,0.12",
    band: Annotated[str, typer.Option(help="Allowed room temperature 'low,high', degC.")] = "17,28",
    min_hold: Annotated[float, typer.Option(help="Shortest hold of a command, min.")] = 30.0,
    outdoor: Annotated[float, typer.Option(help="Expected outdoor temperature, degC.")] = 18.0,
    surroundings: Annotated[
        float, typer.Option(help="Expected temperature of the neighbouring spaces, degC.")
    ] = 22.0,
    q: Annotated[float, typer.Option("--q", help="Internal gain, W.")] = 50.0,
    out: Annotated[Path, typer.Option("--out", "-o", help="Schedule CSV for the BMS.")] = Path(
        "schedule.csv"
    ),
    json_out: Annotated[
        Path | None,
        typer.Option("--json", help="Write the design and its predictions as JSON ('-': stdout)."),
    ] = None,
) -> None:
    """Design a forced-response test (D-optimal supply-air schedule) that can identify the parameters."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
    from rich.table import Table

    from rczone.cli.common import out_console
    from rczone.diagnostics.design import DesignLimits, design_test

    zm = model(model_name)
    net = zm.network
    free_list = split(free) or _rc(net)
    limits = DesignLimits(
        _pair(ts_range, "ts-range"), _pair(m_range, "m-range"), _pair(band, "band"), min_hold * 60.0
    )
    cond = {k: v for k, v in {"To": outdoor, "Tsd": surroundings, "Q": q}.items() if k in net.input_names}
    with Progress(
        TextColumn("designing"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
    ) as bar:
        task = bar.add_task("design", total=None)
        res = design_test(
            net,
            free_list,
            hours * 3600.0,
            limits,
            theta=dict(zm.theta),
            conditions=cond,
            progress=lambda done, total: bar.update(task, completed=done, total=total),
        )
    res.to_csv(str(out))
    console = out_console(json_out)
    table = Table(title="Forced-response schedule")
    for c in ("from (h)", "to (h)", "Ts (degC)", "m (kg/s)"):
        table.add_column(c)
    for r in res.schedule.itertuples():
        table.add_row(f"{r.start_s / 3600:.1f}", f"{r.end_s / 3600:.1f}", f"{r.Ts:.1f}", f"{r.m:.3f}")
    console.print(table)
    se = ", ".join(f"{esc(k)} ±{v:.0%}" for k, v in res.expected_se.items())
    console.print(
        f"predicted room temperature {res.ti_predicted.min():.1f}..{res.ti_predicted.max():.1f} degC; expected {se}"
    )
    console.print(f"schedule written to [bold]{esc(out)}[/]")
    write_json(json_out, res.to_dict())
