"""Printing to the terminal through rich without letting user text become markup.

Zone ids, column names, file names and error messages come from files a user hands in; rich
would read ``[vav-3]`` or ``[/]`` in them as markup, silently dropping text or raising
``MarkupError`` after the work is done. Every user string printed through rich goes through
:func:`escape`, and consoles are made by :func:`console` (no emoji codes, no highlighting of
numbers inside user text).
"""

from __future__ import annotations

import os

from rich.console import Console
from rich.markup import escape as _rich_escape


def escape(text: object) -> str:
    """``text`` as rich markup that prints literally (``[vav-3]`` stays ``[vav-3]``)."""
    return _rich_escape(str(text))


#: Width of a console that writes to a file or a pipe: wider than any line of rczone's, so nothing wraps.
UNWRAPPED_WIDTH = 100_000


def unwrapped(out: Console) -> Console:
    """``out``, made as wide as :data:`UNWRAPPED_WIDTH` when it does not write to a terminal.

    rich wraps at 80 columns when it cannot ask a terminal its width, so ``rczone fit C > out``
    split ``4.499e+05`` and a table's header words across lines; a file or a pipe has no width,
    and a script reading it wants each line whole. A terminal keeps its own width, and so does a
    width asked for with the ``COLUMNS`` environment variable.
    """
    if not out.is_terminal and not os.environ.get("COLUMNS"):  # an explicit width is the user's
        out.width = UNWRAPPED_WIDTH
    return out


def console(stderr: bool = False) -> Console:
    """A rich console for rczone's output (``stderr=True`` for progress and notes).

    Lines are not wrapped, so a long path or message stays one line (and one copy-paste); nothing
    wraps at all where the output is not a terminal (:func:`unwrapped`).
    """
    return unwrapped(Console(stderr=stderr, emoji=False, highlight=False, soft_wrap=True))
