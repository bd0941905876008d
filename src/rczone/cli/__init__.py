"""The ``rczone`` command-line interface."""

from __future__ import annotations


def run() -> int:
    """The console script: :func:`rczone.cli.main.main`, with Ctrl-C during start-up giving 130 too.

    Importing the command modules (typer, rich, and the numerical stack they pull in) takes a
    moment; an interrupt then would otherwise end in a traceback or a signal exit instead of the
    documented 130.
    """
    try:
        from rczone.cli.main import main
    except KeyboardInterrupt:
        return 130
    return main()
