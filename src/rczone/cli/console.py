"""Printing to the terminal through rich without letting user text become markup.

Zone ids, column names, file names and error messages come from files a user hands in; rich
would read ``[vav-3]`` or ``[/]`` in them as markup, silently dropping text or raising
``MarkupError`` after the work is done. Every user string printed through rich goes through
:func:`escape`, and consoles are made by :func:`console` (no emoji codes, no highlighting of
numbers inside user text).
"""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape as _rich_escape


def escape(text: object) -> str:
    """``text`` as rich markup that prints literally (``[vav-3]`` stays ``[vav-3]``)."""
    return _rich_escape(str(text))


def console(stderr: bool = False) -> Console:
    """A rich console for rczone's output (``stderr=True`` for progress and notes).

    Lines are not wrapped, so a long path or message stays one line (and one copy-paste).
    """
    return Console(stderr=stderr, emoji=False, highlight=False, soft_wrap=True)
