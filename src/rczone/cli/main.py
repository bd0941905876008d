"""Entry point of the ``rczone`` command: the Typer app and its error boundary.

Every command module registers its commands on :data:`app`. A user's mistake (any
:class:`~rczone.errors.RczoneError`, or a missing file) becomes one line on stderr and
exit code 2, never a traceback.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from contextlib import nullcontext

import typer
from typer.core import TyperGroup

from rczone.cli.interrupt import noting_ctrl_c
from rczone.errors import RczoneError

#: The commands in the order of the work (``rczone --help`` lists them so): look at the models,
#: ask what the data can identify (or design a test that can), fit, predict, choose among models,
#: fit many zones, control; then the paper's demo, the reference checks and the version.
WORKFLOW_ORDER = (
    "models",
    "methods",
    "diagnose",
    "design",
    "fit",
    "predict",
    "select",
    "fit-many",
    "emulate",
    "control-test",
    "demo",
    "validate",
    "version",
)


class _WorkflowGroup(TyperGroup):
    """The command group that lists its commands in :data:`WORKFLOW_ORDER` (others last, by name)."""

    def list_commands(self, ctx) -> list[str]:
        names = super().list_commands(ctx)
        rank = {n: i for i, n in enumerate(WORKFLOW_ORDER)}
        return sorted(names, key=lambda n: (rank.get(n, len(rank)), n))

    def get_command(self, ctx, cmd_name: str):
        cmd = super().get_command(ctx, cmd_name)
        if cmd is not None:
            _untyped_flags(cmd, ctx)
        return cmd

    def get_params(self, ctx):
        params = super().get_params(ctx)
        _untyped_flags(self, ctx, params)
        return params


def _untyped_flags(cmd, ctx, params=None) -> None:
    """No ``<bool>`` beside a flag in the help: a flag takes no value, so it has no type to show."""
    for p in cmd.get_params(ctx) if params is None else params:
        if getattr(p, "is_flag", False) and p.metavar is None:
            p.metavar = ""


app = typer.Typer(
    name="rczone",
    cls=_WorkflowGroup,
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


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the rczone version and exit."
    ),
) -> None:
    """Grey-box RC thermal models of building zones."""


@app.command()
def version() -> None:
    """Print the rczone version."""
    from rczone import __version__

    typer.echo(__version__)


# Command modules register themselves on `app` when imported.
from rczone.cli import (  # noqa: E402, F401
    commands_batch,
    commands_control,
    commands_demo,
    commands_diagnose,
    commands_emulate,
    commands_fit,
    commands_methods,
    commands_models,
    commands_select,
    commands_validate,
)


def one_line(text: object) -> str:
    """``text`` on one line: newlines and other control characters become spaces."""
    return " ".join("".join(c if c.isprintable() else " " for c in str(text)).split())


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning for the user as one line on stderr (no source line, no file of rczone's)."""
    typer.echo(f"warning: {one_line(message)}", err=True)


def _writes_outputs(exc: BaseException) -> bool:
    """An exit that ends a command with its outputs written (see the exit codes of :func:`main`)."""
    return isinstance(exc, typer.Exit) and exc.exit_code in (0, 3, 4, 5)


def _error(message: object) -> int:
    typer.echo(f"error: {one_line(message)}", err=True)
    return 2


#: Commands that run compiled kernels: they announce a first compilation (rczone.cli.compile_notice).
COMPUTING = frozenset({"demo", "diagnose", "design", "fit", "predict", "select", "fit-many", "validate"})


def _notice_for(argv: list[str]):
    """The compile notice for a computing command (which imports numba anyway), else nothing."""
    if not argv or argv[0] not in COMPUTING or "--help" in argv:
        return nullcontext()
    from rczone.cli.compile_notice import compile_notice

    return compile_notice()


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (also used by the console script).

    Exit codes: 0 success, 1 a validation check failed, 2 a user's mistake (one line on stderr,
    no traceback), 3 a fit flagged untrustworthy, 4 ``fit-many`` stored failed zones, 5
    ``fit-many`` could not run some tasks (retried by the next run), 130 interrupted (Ctrl-C).
    """
    argv = sys.argv[1:] if argv is None else list(argv)
    with noting_ctrl_c() as ctrl_c:
        return _run(argv, ctrl_c)


def _run(argv: list[str], ctrl_c: Callable[[], bool]) -> int:
    from rczone.files.atomic import all_or_nothing

    try:
        # every output of a command appears only if it succeeds (exit 0, or 3..5 that still write
        # them): a failing --report leaves no --json behind (fit-many keeps its results as they come)
        with warnings.catch_warnings(), _notice_for(argv), all_or_nothing(_writes_outputs):
            warnings.showwarning = _show_warning
            code = app(args=argv, standalone_mode=False)  # returns typer.Exit's code in this mode
            if ctrl_c():  # a Ctrl-C that Python dropped on the way: the command was interrupted
                raise KeyboardInterrupt
    except RczoneError as exc:
        return _error(exc)
    except FileNotFoundError as exc:
        return _error(f"file not found: {exc.filename or exc}")
    except OSError as exc:  # a path the user gave cannot be read or written
        where = f"{exc.filename}: " if exc.filename else ""
        return _error(f"{where}{exc.strerror or exc}")
    except typer.Abort as exc:
        # click turns an EOFError from anywhere into Abort; only Ctrl-C is an interruption
        if isinstance(exc.__cause__, EOFError):
            return _error("unexpected end of input (a truncated or damaged file?)")
        typer.echo("aborted", err=True)
        return 130
    except KeyboardInterrupt:
        typer.echo("aborted", err=True)
        return 130
    except MemoryError:
        return _error(
            "out of memory: the input is too large for the memory this process may use"
            " (see the size limits in docs/data.md); use a shorter record or a coarser log"
        )
    except typer.Exit as exc:
        return exc.exit_code
    except Exception as exc:  # usage errors (typer's vendored click) carry their own exit code
        if hasattr(exc, "show") and isinstance(getattr(exc, "exit_code", None), int):
            exc.show()
            return exc.exit_code
        if _interrupted(exc) or ctrl_c():
            typer.echo("aborted", err=True)
            return 130
        raise
    return code if isinstance(code, int) else 0


def _interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` was caused by Ctrl-C: libraries (numba loading its cache, for one) wrap it."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
