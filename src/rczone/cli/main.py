"""Entry point of the ``rczone`` command: the Typer app and its error boundary.

Every command module registers its commands on :data:`app`. A user's mistake (any
:class:`~rczone.errors.RczoneError`, or a missing file) becomes one line on stderr and
exit code 2, never a traceback.
"""

from __future__ import annotations

import sys
import warnings

import typer

from rczone.errors import RczoneError

app = typer.Typer(
    name="rczone",
    help="Grey-box RC thermal models of building zones: simulate, compare, identify, diagnose.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)


def _version(value: bool) -> None:
    if value:
        from rczone import __version__

        typer.echo(__version__)
        raise typer.Exit()


def _plain_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line for a person, without the Python source line they came from."""
    typer.echo(f"warning: {message}", err=True)


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the rczone version and exit."
    ),
) -> None:
    """Grey-box RC thermal models of building zones."""
    warnings.showwarning = _plain_warning


@app.command()
def version() -> None:
    """Print the rczone version."""
    from rczone import __version__

    typer.echo(__version__)


# Command modules register themselves on `app` when imported.
from rczone.cli import (  # noqa: E402, F401
    commands_batch,
    commands_demo,
    commands_diagnose,
    commands_fit,
    commands_models,
    commands_select,
    commands_validate,
)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (also used by the console script)."""
    try:
        app(args=argv, standalone_mode=False)
    except RczoneError as exc:
        typer.echo(f"error: {exc}", err=True)
        return 2
    except FileNotFoundError as exc:
        typer.echo(f"error: file not found: {exc.filename or exc}", err=True)
        return 2
    except (typer.Abort, KeyboardInterrupt):
        typer.echo("aborted", err=True)
        return 130
    except typer.Exit as exc:
        return exc.exit_code
    except Exception as exc:  # usage errors (typer's vendored click) carry their own exit code
        if hasattr(exc, "show") and isinstance(getattr(exc, "exit_code", None), int):
            exc.show()
            return exc.exit_code
        raise
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
