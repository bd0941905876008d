"""``rczone fit-many``: calibrate every zone of a manifest, locally or on a Dask cluster."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from rczone.cli.main import app


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
) -> None:
    """Calibrate many zones; resumes where an earlier run stopped."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from rczone.batch import read_manifest, run_batch, write_summary
    from rczone.batch.store import ResultStore

    m = read_manifest(manifest)
    folder = out or manifest.with_suffix("").with_name(manifest.stem + "-results")
    console = Console(stderr=True)
    done_before = len(ResultStore(folder).done() & {t.key for t in m.tasks})
    console.print(
        f"{len(m.tasks)} calibrations of {len(m.zones)} zones; {done_before} already done in {folder}"
    )
    columns = (
        TextColumn("calibrating"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console, transient=False) as progress:
        bar = progress.add_task("fit", total=len(m.tasks) - done_before, failed=0)
        state = {"failed": 0}

        def on_result(row: dict, done: int, total: int) -> None:
            state["failed"] += row["status"] != "ok"
            progress.update(bar, completed=done, failed=state["failed"])

        run = run_batch(m, folder, scheduler=scheduler, workers=workers, backend=backend, on_result=on_result)
    summary = write_summary(ResultStore(folder).table(), folder, title=f"rczone fit-many {manifest.name}")
    out_console = Console()
    out_console.print(
        f"{run.computed} computed ({run.failed} failed), {run.skipped} resumed, in {run.seconds:.1f} s;"
        f" {summary['ok']}/{summary['tasks']} ok in total"
    )
    for f in summary["failures"][:10]:
        out_console.print(f"[red]failed[/] {f['zone']} ({f['method']}): {f['error']}")
    if summary["failed"] > 10:
        out_console.print(f"... and {summary['failed'] - 10} more (see {folder / 'summary.json'})")
    out_console.print(f"results: {run.results}; report: {folder / 'report.html'}")
