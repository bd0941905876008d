"""``rczone methods``: the estimation methods, built in and plug-ins, with their own options."""

from __future__ import annotations

from rczone.cli.common import esc
from rczone.cli.main import app


@app.command("methods")
def methods() -> None:
    """List the estimation methods (`--method NAME`) and each one's options (`--option NAME=VALUE`)."""
    import dataclasses

    from rich.console import Console
    from rich.table import Table

    from rczone.estimation.methods import method_names, method_of

    table = Table(title="Estimation methods (`rczone fit --method NAME --option NAME=VALUE`)")
    table.add_column("name", no_wrap=True)
    table.add_column("what", overflow="fold")
    table.add_column("options (default)", overflow="fold")
    for name in method_names():
        m = method_of(name)
        opts = ", ".join(f"{f.name}={f.default!r}" for f in dataclasses.fields(m.options)) or "none"
        table.add_row(esc(m.name), esc(m.title), esc(opts))
    Console().print(table)
