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

    from rczone.models import builtin_models, load_model
    from rczone.models.library import OPTIONS

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
    console = Console()
    console.print(table)
    console.print(
        f"Options of Ti, TiTe, TiTh, TiTeTh, TiTm (append with +, e.g. TiTe+heater+solar): {', '.join(OPTIONS)}."
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
    from rczone.files.atomic import write_text_atomic
    from rczone.models import load_model, model_to_toml

    zm = load_model(name)
    text = model_to_toml(zm, header=f"rczone model file, written from {zm.label}\nValues in SI units.")
    if out is None:
        typer.echo(text, nl=False)
    else:
        write_text_atomic(out, text)
        typer.echo(f"model file written to {out}", err=True)
