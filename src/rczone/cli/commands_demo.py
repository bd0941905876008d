"""``rczone demo``: the paper's study on the built-in virtual building."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import QuietOption
from rczone.cli.console import console as console_for
from rczone.cli.main import app
from rczone.cli.progress import reporter


@app.command()
def demo(
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Folder for report.html, figures, results.json.")
    ] = Path("demo-output"),
    quiet: QuietOption = False,
) -> None:
    """Reproduce the paper's study on the virtual building and write a report."""
    from rczone.report.demo import run_demo

    console = console_for(stderr=True)
    t0 = time.perf_counter()
    with reporter(quiet=quiet) as report:
        path = run_demo(out, progress=report)
    console.print(f"report written to [bold]{path}[/] in {time.perf_counter() - t0:.1f} s")
