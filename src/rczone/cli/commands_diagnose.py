"""``rczone diagnose`` and ``rczone design``: can these data identify the parameters, and a test that can."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import (
    MODEL_HELP,
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


@app.command()
def diagnose(
    data: Annotated[Path, typer.Argument(help="CSV/Parquet file, or a built-in data set name (A, B, C).")],
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    free: Annotated[
        str | None,
        typer.Option(
            help="Comma-separated parameters to diagnose (default: the model's free R, C and gains)."
        ),
    ] = None,
    column_map: Annotated[
        Path | None, typer.Option("--columns", help="TOML column map for trend logs.")
    ] = None,
    const: Annotated[
        list[str] | None,
        typer.Option(
            "--const", help="Hold an input constant, NAME=VALUE in SI units (repeatable), e.g. Q=50."
        ),
    ] = None,
    sigma: Annotated[
        float, typer.Option(help="Error level a fit must see through (sensor noise + model error), K.")
    ] = 0.1,
    model_error: Annotated[
        float, typer.Option(help="Structural model error the verdicts allow for, K RMS (0: none).")
    ] = 0.2,
    operating_point: Annotated[
        str,
        typer.Option(
            help="Where to analyse: auto (the model's values if they reproduce the data, else a quick"
            " least-squares fit first), model (its values regardless) or fit (always fit first)."
        ),
    ] = "auto",
    seed: Annotated[int, typer.Option(help="Seed of the quick fit's global search.")] = 0,
    hold: Annotated[
        str | None,
        typer.Option(
            "--hold",
            metavar="zoh|foh",
            help="Inputs between samples: held (zoh) or linear (foh); default the one the model was fitted"
            " with, else zoh.",
        ),
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write the verdicts and evidence as JSON ('-': stdout).")
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html and figures.")
    ] = None,
) -> None:
    """Tell whether DATA can identify the model's parameters, and why.

    Every output of the model is used. The analysis is done where the parameters are: at the model's
    values if they reproduce DATA, else at the estimates of a quick least-squares fit (it says which).
    """
    import dataclasses

    from rich.console import Console

    from rczone.cli.common import check_seed
    from rczone.diagnostics import diagnose as run

    check_seed(seed)
    zm = model(model_name)
    frame = read_frame(data, column_map, zm)
    label = data_label(data)
    with Console(stderr=True).status(f"diagnosing {esc(zm.label)} on {esc(label)}"):
        rep = run(
            zm,
            frame,
            free=split(free),
            sigma_K=sigma,
            model_error_K=model_error,
            constants=constants(const),
            operating_point=operating_point,
            seed=seed,
            hold=hold,
        )
    rep = dataclasses.replace(rep, data_label=label)
    console = out_console(json_out)
    for line in rep.summary_lines():
        console.print(line)
    write_json(json_out, rep.to_dict())
    if report_dir:
        from rczone.report.diagnose import diagnose_report

        diagnose_report(rep, zm, label).write(report_dir)
        console.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")


#: Plausibility role (:data:`rczone.data.units.PLAUSIBLE`) of what a design request gives.
_ROLE = {"band": "room", "initial": "room", "boundary": "outdoor", "supply": "supply"}


def _numbers(text: str, option: str, n: int, example: str) -> tuple[float, ...]:
    """``"12,35"`` -> ``(12.0, 35.0)``: exactly ``n`` numbers, else a one-line error."""
    from rczone.errors import ParameterError

    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != n:
        raise ParameterError(f"{option} must be {example}; got {text!r}")
    return values


def _named(items: list[str] | None, option: str, n: int) -> dict[str, tuple[float, ...]]:
    """``["Ts=12,35"]`` -> ``{"Ts": (12.0, 35.0)}`` (``n`` numbers per name)."""
    from rczone.errors import ParameterError

    example = "NAME=LOW,HIGH, e.g. Ts=12,35" if n == 2 else "NAME=VALUE, e.g. To=18"
    out: dict[str, tuple[float, ...]] = {}
    for item in items or ():
        name, sep, rest = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ParameterError(f"{option} must be {example}; got {item!r}")
        if name in out:
            raise ParameterError(f"{option} gives {name!r} twice")
        out[name] = _numbers(rest, option, n, example)
    return out


def _unit_choice(text: str | None, zm, column_map) -> dict[str, str]:
    """The unit of each of the model's signals: --units by quantity, else the column map's, else SI."""
    from rczone.data.units import SI_UNITS, canonical_unit
    from rczone.errors import DataError, ParameterError, did_you_mean

    by_quantity: dict[str, str] = {}
    for token in split(text) or []:
        found = None
        for q in SI_UNITS:
            try:
                found = (q, canonical_unit(token, q, "--units"))
                break
            except DataError:
                continue
        if found is None:
            known = [u for q in SI_UNITS for u in _known(q)]
            raise ParameterError(f"--units: unknown unit {token!r}; " + did_you_mean(token, known))
        if found[0] in by_quantity:
            raise ParameterError(f"--units gives two {found[0]} units ({by_quantity[found[0]]}, {found[1]})")
        by_quantity[found[0]] = found[1]
    mapped = {c.name: c.unit for c in column_map.channels} if column_map is not None else {}
    return {s: by_quantity.get(q) or mapped.get(s) or SI_UNITS[q] for s, q in zm.signal_quantities().items()}


def _known(quantity: str) -> tuple[str, ...]:
    from rczone.data.units import known_units

    return known_units(quantity)


def _to_si(what: str, values: tuple[float, ...], unit: str, quantity: str, role: str, density: float):
    """User values in ``unit`` to SI, checked against the plausible range of ``role`` (with a unit hint)."""
    import numpy as np

    from rczone.data.units import PLAUSIBLE, SI_UNITS, to_si
    from rczone.errors import ParameterError

    raw = np.array(values, float)
    si = to_si(raw, unit, quantity, what, density)
    rng = PLAUSIBLE[role]
    if np.all((si >= rng.low) & (si <= rng.high)):
        return tuple(float(v) for v in si)
    fits = [
        u
        for u in _known(quantity)
        if u != unit
        and np.all((lambda a: (a >= rng.low) & (a <= rng.high))(to_si(raw, u, quantity, what, density)))
    ]
    hint = (
        f"the values look like {' or '.join(fits)}: give the unit with --units (e.g. --units {fits[-1]})"
        if fits
        else "check the numbers and their unit"
    )
    shown = ",".join(f"{v:g}" for v in values)
    raise ParameterError(
        f"{what}={shown} {unit} is not a plausible {rng.label} (after conversion outside"
        f" {rng.low:g}..{rng.high:g} {SI_UNITS[quantity]}); {hint}"
    )


def _start(text: str | None, column_map):
    """The test's start: a time of day ("18:00") or a date and time (localized in the map's time zone)."""
    import datetime as dt

    import pandas as pd

    from rczone.errors import ParameterError

    if text is None:
        text = column_map.night_start if column_map is not None else "18:00"
    text = text.strip()
    try:
        return dt.datetime.strptime(text, "%H:%M").time()
    except ValueError:
        pass
    try:
        ts = pd.Timestamp(text)
    except (ValueError, TypeError):
        ts = None
    if ts is None or ts is pd.NaT:
        raise ParameterError(
            f"--start must be a time of day HH:MM or a date and time (2026-10-24T18:00), got {text!r}"
        )
    if ts.tzinfo is None and column_map is not None:
        try:
            ts = ts.tz_localize(column_map.timezone, ambiguous="raise", nonexistent="raise")
        except (ValueError, TypeError) as exc:  # pytz/zoneinfo errors on DST gaps and repeats
            raise ParameterError(f"--start {text!r} in {column_map.timezone}: {exc}") from None
    return ts


@app.command()
def design(
    model_name: Annotated[str, typer.Option("--model", help=MODEL_HELP)] = "second-order-paper",
    actuate: Annotated[
        list[str] | None,
        typer.Option(
            "--actuate",
            help="An input the test may drive and its range, NAME=LOW,HIGH in the chosen units (repeatable),"
            " e.g. Ts=12,35 and m=0.02,0.12 for supply air, or Ph=0,2000 for a heater.",
        ),
    ] = None,
    condition: Annotated[
        list[str] | None,
        typer.Option(
            "--condition",
            help="Expected value of another input during the test, NAME=VALUE (repeatable), e.g. To=18;"
            " inputs the model gives a default may be left out.",
        ),
    ] = None,
    temperature_limits: Annotated[
        str,
        typer.Option(
            "--limits", help="Allowed zone temperature during the test, 'low,high' (default 17,28 degC)."
        ),
    ] = "",
    units: Annotated[
        str | None,
        typer.Option(
            help="Units of every number given and written, by quantity, e.g. degF,cfm or degC,L/s,kW"
            " (default: the column map's units, else SI)."
        ),
    ] = None,
    column_map: Annotated[
        Path | None,
        typer.Option(
            "--columns", help="The zone's column map: its units, time zone and night start are used."
        ),
    ] = None,
    free: Annotated[
        str | None,
        typer.Option(
            help="Comma-separated parameters the test should identify (default: the model's R and C)."
        ),
    ] = None,
    hours: Annotated[float, typer.Option(help="Length of the test, h.")] = 12.0,
    min_hold: Annotated[float, typer.Option(help="Shortest hold of a command, min.")] = 30.0,
    initial: Annotated[
        float | None, typer.Option(help="Zone temperature at the start (default: the middle of --limits).")
    ] = None,
    start: Annotated[
        str | None,
        typer.Option(
            help="When the test starts: HH:MM, or a date and time such as 2026-10-24T18:00 (default: the"
            " column map's night start, else 18:00)."
        ),
    ] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Schedule CSV for the BMS.")] = Path(
        "schedule.csv"
    ),
    json_out: Annotated[
        Path | None,
        typer.Option("--json", help="Write the design and its predictions as JSON ('-': stdout)."),
    ] = None,
) -> None:
    """Design a forced-response test (a D-optimal schedule of the inputs the building can drive).

    Every number is read, and the schedule written, in the chosen units (--units, else the column
    map's, else SI); the schedule has clock times from --start.
    """
    import dataclasses

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from rczone.data.units import DEFAULT_AIR_DENSITY
    from rczone.diagnostics.design import DesignLimits, actuatable, design_test
    from rczone.errors import ParameterError

    zm = model(model_name)
    net = zm.network
    cmap = None
    if column_map is not None:
        from rczone.data.columnmap import read_column_map

        cmap = read_column_map(column_map, zm.signal_quantities())
    density = cmap.air_density if cmap is not None else DEFAULT_AIR_DENSITY
    unit = _unit_choice(units, zm, cmap)
    quantity = zm.signal_quantities()
    out_name = net.outputs[0]
    t_unit = unit[out_name]
    ranges_in = _named(actuate, "--actuate", 2)
    if not ranges_in:
        can = actuatable(net)
        raise ParameterError(
            f"give the inputs the test may drive and their ranges with --actuate NAME=LOW,HIGH (model"
            f" {zm.label!r} can drive {', '.join(can) or 'none'}), e.g. "
            + " ".join(f"--actuate {a}=LOW,HIGH" for a in can[:2])
        )
    supply = {s.temperature for s in net.supply_air}
    ranges = {}
    for a, pair in ranges_in.items():
        if a not in quantity:
            raise ParameterError(
                f"--actuate {a}: not an input of model {zm.label!r}; drivable: {', '.join(actuatable(net))}"
            )
        role = "supply" if a in supply else ("flow" if quantity[a] == "flow" else quantity[a])
        ranges[a] = _to_si(f"--actuate {a}", pair, unit[a], quantity[a], _ROLE.get(role, role), density)
    conds = {}
    for k, (v,) in _named(condition, "--condition", 1).items():
        if k not in quantity:
            raise ParameterError(f"--condition {k}: not an input of model {zm.label!r}")
        role = "boundary" if k in net.boundaries else ("supply" if k in supply else quantity[k])
        conds[k] = _to_si(f"--condition {k}", (v,), unit[k], quantity[k], _ROLE.get(role, role), density)[0]
    band_si = (17.0, 28.0)
    if temperature_limits:
        pair = _numbers(temperature_limits, "--limits", 2, "two numbers 'low,high'")
        band_si = _to_si("--limits", pair, t_unit, "temperature", "room", density)
    ti0 = (
        _to_si("--initial", (initial,), t_unit, "temperature", "room", density)[0]
        if initial is not None
        else None
    )
    when = _start(start, cmap)
    free_list = split(free) or [
        n for n in net.default_free if net.parameters[n].kind in ("resistance", "capacitance")
    ]
    limits = DesignLimits(ranges, band_si, min_hold * 60.0)
    bar = Progress(
        TextColumn("designing"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
    )
    task = None

    def report(done: int, total: int) -> None:  # the bar appears once the request is valid
        nonlocal task
        if task is None:
            bar.start()
            task = bar.add_task("design", total=total)
        bar.update(task, completed=done, total=total)

    try:
        res = design_test(zm, free_list, hours * 3600.0, limits, conditions=conds, ti0=ti0, progress=report)
    finally:
        if task is not None:  # a bar never shown leaves no blank line before the error
            bar.stop()
    units_shown = {k: unit[k] for k in (*res.actuated, out_name)}
    res = dataclasses.replace(res, model_label=zm.label, start=when, display_units=units_shown)
    res.to_csv(out, when, {a: unit[a] for a in res.actuated})
    console = out_console(json_out)
    for line in res.summary_lines():
        console.print(line)
    console.print(f"schedule written to [bold]{esc(out)}[/]")
    write_json(json_out, res.to_dict())
