"""Exceptions raised by rczone, and the helper that suggests close names.

Every error a user can cause is a subclass of a built-in exception (so ``except
ValueError`` keeps working) and of :class:`RczoneError` (so the CLI can turn it into
one clear line instead of a traceback).
"""

from __future__ import annotations

import difflib
import os
import sys
from collections.abc import Iterable


class RczoneError(Exception):
    """Base class of every error rczone raises on purpose."""


class NetworkError(RczoneError, ValueError):
    """An RC network is malformed (undeclared node, floating node, duplicate name...)."""


class ParameterError(RczoneError, ValueError):
    """A parameter name is unknown, a value is out of range or an expression is invalid."""


class InputShapeError(RczoneError, ValueError):
    """An array passed to a simulation or cost has the wrong shape or content."""


class OutputError(RczoneError, OSError):
    """A result cannot be written where asked (a folder for a file, read-only, disk full...)."""


class DataError(RczoneError, ValueError):
    """Data or a file a user handed in cannot be used as given (missing column, bad unit, bad
    timestamps, a malformed column map or manifest...)."""


class EmulatorError(RczoneError, RuntimeError):
    """An emulator (EnergyPlus) cannot run as asked: a missing extra, an actuator it refuses, a
    failed simulation (its own severe errors quoted)."""


class ModelFileError(DataError):
    """A model file (TOML written by a person, or JSON saved by rczone) cannot be used as given."""


def printable(text: str) -> str:
    """``text`` with control and other unprintable characters escaped, so a message stays one line.

    Names come from user files (a CSV header can hold a newline); ``"a\\nb"`` is shown as ``a\\nb``.
    """
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)


def did_you_mean(name: str, candidates: Iterable[str], n: int = 3) -> str:
    """Return a hint naming the candidates closest to ``name``, or listing them all.

    Parameters
    ----------
    name : str
        The name the user wrote.
    candidates : iterable of str
        The names that would have been valid.
    n : int
        How many close matches to offer at most.

    Returns
    -------
    str
        ``"did you mean 'Rw'?"`` when close matches exist, else ``"known: a, b, c"``.
    """
    pool = sorted(set(candidates))
    close = difflib.get_close_matches(name, pool, n=n, cutoff=0.5)
    if not close:
        lowered = {c.lower(): c for c in pool}
        close = [lowered[c] for c in difflib.get_close_matches(name.lower(), lowered, n=n, cutoff=0.5)]
    if close:
        return "did you mean " + " or ".join(f"'{printable(c)}'" for c in close) + "?"
    shown = ", ".join(printable(c) for c in pool[:20]) + (" ..." if len(pool) > 20 else "")
    return f"known names: {shown}" if pool else "none are declared"


#: The package's folder: frames of files under it are rczone's own.
_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def user_stacklevel() -> int:
    """The ``stacklevel`` of :func:`warnings.warn` that points at the user's call, past rczone's frames.

    Called by the function that warns: ``warnings.warn(msg, RczoneWarning, stacklevel=user_stacklevel())``.
    The same warning is raised through the API's entry points at different depths (a frame, a
    file, a batch: all prepare the data set in one place); a fixed level points into rczone from
    most of them. (Python 3.12's ``skip_file_prefixes`` does this; rczone supports 3.11.)
    """
    frame = sys._getframe(1)  # the function that warns: stacklevel 1
    level = 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE):
        frame = frame.f_back
        level += 1
    return level
