"""``rczone fit-many``: calibrate every zone of a manifest, locally or on a Dask cluster."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import EXIT_INFRASTRUCTURE as EXIT_TASKS_LOST
from rczone.cli.common import EXIT_UNTRUSTED, EXIT_ZONES_FAILED, QuietOption
from rczone.cli.main import app
from rczone.cli.progress import reporter


@app.command("fit-many")
def fit_many(
    manifest: Annotated[Path, typer.Argument(help="Manifest (TOML) listing zones, data, model and methods.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Results folder (default: next to the manifest).")
    ] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler address, e.g. tcp://host:8786 (default: local).")
    ] = None,
    workers: Annotated[int | None, typer.Option(help="Local worker processes (default: cores).")] = None,
    backend: Annotated[str, typer.Option(help="Local engine: auto, dask or processes.")] = "auto",
    zones_per_task: Annotated[
        int | None,
        typer.Option(help="Zones per Dask task (default: about 16 tasks per worker, at most 64 zones)."),
    ] = None,
    quiet: QuietOption = False,
) -> None:
    """Calibrate many zones; resumes where an earlier run stopped.

    Exit code 0 when every zone is calibrated, 4 when some zones failed with their own errors
    (stored, listed in the summary), 5 when some calibrations could not run (a worker or the
    scheduler was lost; rerun to compute them), 2 for a mistake in the manifest or options.
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from rczone.batch import read_manifest, run_batch
    from rczone.cli.console import console, escape
    from rczone.errors import ParameterError

    if workers is not None and workers < 1:
        raise ParameterError(f"--workers must be at least 1, got {workers}")
    if zones_per_task is not None and zones_per_task < 1:
        raise ParameterError(f"--zones-per-task must be at least 1, got {zones_per_task}")
    m = read_manifest(manifest)
    folder = out or manifest.with_suffix("").with_name(manifest.stem + "-results")
    err = console(stderr=True)
    columns = (
        TextColumn("calibrating"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeRemainingColumn(),
    )
    # a bar on a terminal; elsewhere a line at most every 10 s (a bar off a terminal prints at the end)
    progress = Progress(*columns, console=err, transient=False, disable=quiet or not err.is_terminal)
    lines = reporter(quiet=quiet or err.is_terminal, stream=sys.stderr, heartbeat=False)
    bar = progress.add_task("fit", total=None, failed=0)
    state = {"failed": 0}

    def on_start(resumed: int, to_do: int) -> None:
        err.print(
            f"{len(m.tasks)} calibrations of {len(m.zones)} zones; {resumed} already done in {escape(folder)}"
        )
        progress.update(bar, total=to_do)
        state["started"] = 1
        progress.start()  # only now: an error before the run prints its one line and nothing else

    def on_result(row: dict, done: int, total: int) -> None:
        state["failed"] += row["status"] != "ok"
        progress.update(bar, completed=done, failed=state["failed"])
        lines(f"calibrating, {state['failed']} failed")
        lines.advance(done, total)

    try:
        run = run_batch(
            m,
            folder,
            scheduler=scheduler,
            workers=workers,
            backend=backend,
            unit=zones_per_task,
            on_result=on_result,
            on_start=on_start,
            title=f"rczone fit-many {manifest.name}",
        )
    except BaseException:
        if state.get("started"):
            progress.live.transient = True  # the bar goes: the error is the one line left
            progress.stop()
        raise
    if state.get("started"):
        progress.stop()
    for line in run.summary_lines(lost=False):
        console().print(line)
    for line in run.lost_lines():
        err.print(line)
    if run.lost:
        raise typer.Exit(EXIT_TASKS_LOST)
    if run.totals["failed"]:
        raise typer.Exit(EXIT_ZONES_FAILED)
    if run.totals["flagged"]:
        raise typer.Exit(EXIT_UNTRUSTED)
