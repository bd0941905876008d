"""``rczone emulate``: run an EnergyPlus prototype building and write what its BMS would log."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import QuietOption, esc, out_console
from rczone.cli.main import app
from rczone.cli.progress import reporter


@app.command("emulate")
def emulate(
    building: Annotated[
        str | None, typer.Option("--building", help="A prototype building: office_small, office_medium...")
    ] = None,
    weather: Annotated[
        str, typer.Option("--weather", help="A TMY3 weather file (see --list).")
    ] = "usa_il_chicago",
    start: Annotated[str, typer.Option("--start", help="First day, MM-DD.")] = "01-15",
    days: Annotated[int, typer.Option("--days", help="Whole days to run.")] = 2,
    step: Annotated[int, typer.Option("--step", help="Zone time step and trend interval, minutes.")] = 5,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the sensor noise.", min=0)] = 0,
    test: Annotated[
        str,
        typer.Option(
            "--test", help="normal: the building's own control; forced: a designed test in --zones."
        ),
    ] = "normal",
    zones: Annotated[
        str | None, typer.Option("--zones", help="Zones the forced test drives, comma-separated.")
    ] = None,
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Folder for trend.csv, column maps, building.toml.")
    ] = None,
    list_: Annotated[
        bool, typer.Option("--list", help="List the buildings, their zones and the weather files.")
    ] = False,
    quiet: QuietOption = False,
) -> None:
    """Run an ASHRAE 90.1-2019 prototype in EnergyPlus (extra rczone[energyplus]) and export its trends."""
    from rczone.errors import ParameterError

    if list_:
        from rczone.emulators.listing import listing

        out_console(None).print(esc(listing(building)))
        return
    if building is None or out is None:
        raise ParameterError("rczone emulate needs --building and -o DIR (or --list)")
    from rczone.emulators.runs import emulate_to_folder

    with reporter(quiet=quiet) as report:
        report(f"EnergyPlus: {building}, {weather}, simulated days")
        res = emulate_to_folder(
            building,
            weather,
            out,
            start=start,
            days=days,
            step_minutes=step,
            seed=seed,
            test=test,
            zones=zones,
            progress=report,
        )
    out_console(None).print(esc(res.summary()))
