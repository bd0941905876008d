"""The protocol every result follows: ``summary``, ``to_dict``, ``to_frame``, ``_repr_html_``, ``repr``.

A result class derives from :class:`Result` and defines :meth:`Result.summary_lines` (the rich
renderables the command line prints, in order), ``to_dict`` and ``to_frame``; :meth:`Result.summary`
renders the same lines as plain text, so the console and the Python API cannot drift apart
(python-control keeps computing apart from plotting in the same way; statsmodels'
``MLEResults.summary`` is the model for a result that prints itself). Dataclass results pass
``repr=False`` so that the short :meth:`Result.__repr__` is kept: a result can hold megabytes of
arrays, and its ``repr`` must stay one line.
"""

from __future__ import annotations

import html
import io
import math
from typing import Any

#: Width of :meth:`Result.summary` when none is given (characters).
SUMMARY_WIDTH = 100


def json_number(v: Any) -> float | None:
    """A float for JSON: NaN and infinities (which JSON has not) become ``None``.

    Parameters
    ----------
    v : float-like or None
        The number.

    Returns
    -------
    float or None
    """
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def render_plain(renderables: list, width: int = SUMMARY_WIDTH) -> str:
    """Rich renderables (markup strings, tables) as the plain text a console without colour shows.

    Parameters
    ----------
    renderables : list
        Strings with rich markup, or rich renderables (tables).
    width : int
        Console width, characters.

    Returns
    -------
    str
        One line (or table) per renderable, ending in a newline.
    """
    from rich.console import Console

    buf = io.StringIO()
    console = Console(
        file=buf, width=width, color_system=None, force_terminal=False, highlight=False, soft_wrap=False
    )
    print_lines(console, renderables)
    return buf.getvalue()


def print_lines(console, renderables: list) -> None:
    """Print summary lines on a rich console; a :class:`rich.text.Text` (a command to paste) is never wrapped.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    renderables : list
        Strings with rich markup, tables, or ``Text`` lines printed whole.
    """
    from rich.text import Text

    for r in renderables:
        console.print(r, soft_wrap=isinstance(r, Text))


class Result:
    """Mixin of the result protocol.

    Subclasses define :meth:`summary_lines`, :meth:`to_dict`, :meth:`to_frame` and
    :meth:`_repr_line`.
    """

    def summary_lines(self) -> list:
        """The rich renderables the command line prints for this result, in order."""
        raise NotImplementedError

    def summary(self, width: int = SUMMARY_WIDTH) -> str:
        """What the command line prints for this result, as plain text.

        Parameters
        ----------
        width : int
            Console width, characters (the command line uses the terminal's).

        Returns
        -------
        str
        """
        return render_plain(self.summary_lines(), width)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready content: exactly what the command's ``--json`` writes."""
        raise NotImplementedError

    def to_frame(self):
        """The result's main table as a pandas DataFrame."""
        raise NotImplementedError

    def _repr_line(self) -> str:
        """The few words after the class name in :meth:`__repr__`."""
        return ""

    def __repr__(self) -> str:
        line = self._repr_line()
        return f"<{type(self).__name__}{': ' + line if line else ''}>"

    def _repr_html_(self) -> str:
        """The summary and the table, for notebooks."""
        text = f"<pre>{html.escape(self.summary())}</pre>"
        try:
            frame = self.to_frame()
        except NotImplementedError:
            return text
        return text + frame.to_html(max_rows=60)
