"""``rczone validate``: run rczone against independent reference cases."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from rczone.cli.console import unwrapped
from rczone.cli.main import app

validate_app = typer.Typer(help="Check rczone against independent references.", no_args_is_help=True)
app.add_typer(validate_app, name="validate")


@validate_app.command("vdi6007")
def vdi6007(
    case: Annotated[
        list[str] | None, typer.Option("--case", help="Test case(s) to run, e.g. TC1 (default: all).")
    ] = None,
    json_out: Annotated[Path | None, typer.Option("--json", help="Write the deviations as JSON.")] = None,
) -> None:
    """VDI 6007-1 test cases: hourly mean air temperatures against the VDI and Dymola references."""
    from rczone.files.atomic import write_json_atomic
    from rczone.reference.vdi6007 import CASES, TOL_DYMOLA_K, TOL_VDI_K, run_case

    names = case or list(CASES)
    for n in names:  # check all names before the (seconds-long) work
        if n not in CASES:
            run_case(n)  # raises the one-line error with a suggestion
    results = {}
    with Console(stderr=True).status("running") as status:
        for n in names:
            status.update(f"VDI 6007 {n}")
            results[n] = run_case(n)
    table = Table(title=f"VDI 6007-1 (tolerances: {TOL_VDI_K} K vs VDI, {TOL_DYMOLA_K} K vs Dymola)")
    for col in ("case", "max dev. VDI (K)", "day 1", "day 10", "day 60", "max dev. Dymola (K)", ""):
        table.add_column(col)
    for n, r in results.items():
        table.add_row(
            n,
            f"{r.max_dev_vdi_K:.3f}",
            *(f"{v:.3f}" for v in r.per_day.values()),
            f"{r.max_dev_dymola_K:.2g}",
            "[green]pass[/]" if r.passed else "[red]FAIL[/]",
        )
    unwrapped(Console()).print(table)
    if json_out:
        write_json_atomic(json_out, {"cases": {n: r.to_dict() for n, r in results.items()}})
    if not all(r.passed for r in results.values()):
        raise typer.Exit(1)
