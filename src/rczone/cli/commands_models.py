"""``rczone models``: the built-in models, and any model written out as a model file to start from."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import esc
from rczone.cli.main import app

models_app = typer.Typer(
    help="Built-in models; `rczone models show NAME` prints one as a model file to edit.",
    invoke_without_command=True,
    no_args_is_help=False,
)
app.add_typer(models_app, name="models")


@models_app.callback()
def models(ctx: typer.Context) -> None:
    """List the built-in models (without a subcommand)."""
    if ctx.invoked_subcommand is not None:
        return
    from rich.console import Console
    from rich.table import Table

    from rczone.cli.console import unwrapped
    from rczone.models import builtin_models, load_model
    from rczone.models.library import OPTIONS, PARTS

    table = Table(
        title="Built-in models (`--model NAME`; any model file .toml or saved model .json works too)"
    )
    table.add_column("name", no_wrap=True)
    for c in ("states", "inputs", "estimated by default", "what"):
        table.add_column(c, overflow="fold")
    for name, text in builtin_models():
        net = load_model(name).network
        table.add_row(
            name,
            ", ".join(net.state_names) if len(net.state_names) <= 4 else f"{len(net.state_names)} states",
            ", ".join((*net.input_names, *net.flow_names)),
            ", ".join(net.default_free) if len(net.default_free) <= 6 else f"{len(net.default_free)} R and C",
            esc(text),
        )
    console = unwrapped(Console())
    console.print(table)
    console.print(
        f"Options of Ti, TiTe, TiTh, TiTeTh, TiTm (append with +, e.g. TiTe+heater+solar): {', '.join(OPTIONS)}."
        f" The rest of the family is Ti with any of {', '.join(PARTS)} (e.g. TiTmTeThAeRia+heater+solar)."
        " `rczone models show NAME > mine.toml` writes a model file to edit."
    )


@models_app.command("show")
def show(
    name: Annotated[str, typer.Argument(help="A built-in name, a model file or a saved model.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write the model file here instead of printing it.")
    ] = None,
) -> None:
    """Print a model as a model file (TOML), the format `--model FILE.toml` reads."""
    from rczone.models import load_model, model_to_toml

    zm = load_model(name)
    text = model_to_toml(zm, header=f"rczone model file, written from {zm.label}\nValues in SI units.")
    _emit(text, out)


@models_app.command("generate")
def generate(
    rooms: Annotated[
        str | None,
        typer.Option("--rooms", help="Number of rooms (named 1..N) or their names, comma-separated (a,b,c)."),
    ] = None,
    wall: Annotated[
        list[str] | None,
        typer.Option("--wall", help="Two rooms that share a wall, A-B (repeat for each wall)."),
    ] = None,
    circuit: Annotated[
        list[str] | None,
        typer.Option(
            "--circuit",
            help="A heating circuit and the rooms it serves, NAME=A,B (its heat is split by estimated shares);"
            " repeat for each. Default: one heat input Q<room> per room.",
        ),
    ] = None,
    mass: Annotated[bool, typer.Option("--mass", help="An internal-mass node in every room.")] = False,
    solar: Annotated[
        bool,
        typer.Option(
            "--solar", help="Solar irradiance Ps (W/m2) into every room through an aperture Aw_<room>."
        ),
    ] = False,
    boundary: Annotated[
        list[str] | None,
        typer.Option(
            "--boundary",
            help="A measured neighbouring space and the rooms sharing a wall with it, NAME=A,B (NAME is its"
            " temperature column, e.g. Tcorr=1,2); repeat for each.",
        ),
    ] = None,
    measured: Annotated[
        str | None,
        typer.Option("--measured", help="Rooms whose air temperature is measured (default all): A,B."),
    ] = None,
    name: Annotated[str, typer.Option("--name", help="Name of the model.")] = "multizone",
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write the model file here instead of printing it.")
    ] = None,
    from_: Annotated[
        Path | None,
        typer.Option("--from", help="A building.toml of `rczone emulate`: the joint model of one --floor."),
    ] = None,
    floor: Annotated[
        int | None, typer.Option("--floor", help="With --from: the floor (1 is the lowest).")
    ] = None,
) -> None:
    """Generate a multi-zone model file (TOML): rooms, the walls between them, the heating circuits, the sun and measured neighbours."""
    from rczone.errors import ParameterError
    from rczone.models import model_to_toml
    from rczone.models.multizone import multizone

    if from_ is not None or floor is not None:
        from rczone.emulators.floor import floor_model_file

        if from_ is None or floor is None or rooms or wall or circuit:
            raise ParameterError(
                "give --from building.toml with --floor N (and no --rooms, --wall, --circuit)"
            )
        net = floor_model_file(from_, floor)
        _emit(
            model_to_toml(
                net, header=f"rczone model file, generated: {net.description}\nValues in SI units."
            ),
            out,
        )
        return
    if rooms is None:
        raise ParameterError("give --rooms (or --from building.toml --floor N)")

    def names(text: str, what: str) -> list[str]:
        out = [p.strip() for p in text.split(",")]
        if not all(out):
            raise ParameterError(f"{what} {text!r}: give room names separated by commas (A,B)")
        return out

    from rczone.validation import ascii_count

    count = ascii_count(rooms)
    room_list: int | list[str] = count if count is not None else names(rooms, "--rooms")
    walls = []
    for w in wall or []:
        pair = [p.strip() for p in w.split("-")]
        if len(pair) != 2 or not all(pair):
            raise ParameterError(f"--wall {w!r}: give two rooms joined by a dash (1-2)")
        walls.append(pair)
    circuits = None
    if circuit:
        circuits = {}
        for c in circuit:
            key, sep, served = c.partition("=")
            if not sep or not key.strip():
                raise ParameterError(f"--circuit {c!r}: give NAME=ROOM,ROOM (Ph1=1,2)")
            circuits[key.strip()] = names(served, f"--circuit {key.strip()}")
    zones = {}
    for b in boundary or []:
        key, sep, served = b.partition("=")
        if not sep or not key.strip():
            raise ParameterError(f"--boundary {b!r}: give NAME=ROOM,ROOM (Tcorr=1,2)")
        zones[key.strip()] = names(served, f"--boundary {key.strip()}")
    net = multizone(
        room_list,
        walls,
        circuits=circuits,
        mass=mass,
        measured=names(measured, "--measured") if measured else None,
        name=name,
        solar=solar,
        boundary_zones=zones,
    )
    text = model_to_toml(net, header=f"rczone model file, generated: {net.description}\nValues in SI units.")
    _emit(text, out)


def _emit(text: str, out: Path | None) -> None:
    """Print a model file, or write it atomically to ``out``."""
    from rczone.files.atomic import write_text_atomic

    if out is None:
        typer.echo(text, nl=False)
    else:
        write_text_atomic(out, text)
        typer.echo(f"model file written to {out}", err=True)
