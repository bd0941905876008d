"""``rczone demo``: the paper's study on the built-in virtual building."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from rczone.cli.main import app


@app.command()
def demo(
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Folder for report.html, figures, results.json.")
    ] = Path("demo-output"),
) -> None:
    """Reproduce the paper's study on the virtual building and write a report."""
    from rczone.report.demo import run_demo

    console = Console(stderr=True)
    t0 = time.perf_counter()
    with console.status("starting") as status:
        path = run_demo(out, progress=lambda msg: status.update(msg))
    console.print(f"report written to [bold]{path}[/] in {time.perf_counter() - t0:.1f} s")
