"""A small builder for self-contained HTML reports (figures embedded as PNG data URIs)."""

from __future__ import annotations

import base64
import html
import io
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from matplotlib.figure import Figure

from rczone.files.atomic import write_bytes_in, write_text_in

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1050px;margin:2em auto;
padding:0 1em;color:#1b1f24;line-height:1.5}
h1{border-bottom:2px solid #2b6cb0;padding-bottom:.2em}h2{margin-top:2em;color:#2b6cb0}
table{border-collapse:collapse;margin:1em 0;font-size:.92em}
th,td{border:1px solid #ccd;padding:.3em .7em;text-align:right}th{background:#eef2f8}
td:first-child,th:first-child{text-align:left}
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #dde}
figcaption{font-size:.9em;color:#555}.note{background:#f6f8fa;border-left:4px solid #2b6cb0;padding:.6em 1em}
.warn{background:#fff8e6;border-left:4px solid #d69e2e;padding:.6em 1em}
.bad{color:#c53030;font-weight:600}.good{color:#2f855a;font-weight:600}
"""


def literal(text: object) -> str:
    """``text`` as a figure label that matplotlib prints as written: each ``$`` escaped.

    A user's zone, file, model, node or column name may hold ``$`` (``a$\\frac{$b``); unescaped,
    matplotlib would read it as mathtext and fail to parse or print a formula. Escaping the user's
    strings where they are drawn keeps mathtext on for matplotlib's own labels (the log axes'
    ``10^{-5}`` tick labels are mathtext), the figures' counterpart of the escaping of user strings
    for rich (:func:`rczone.cli.console.escape`) and for HTML (``html.escape``).

    Parameters
    ----------
    text : object
        A name or label (converted with ``str``).

    Returns
    -------
    str
        The label with every ``$`` written ``\\$``.

    References
    ----------
    The matplotlib developers, "Writing mathematical expressions" (matplotlib 3.8 user guide): an
    escaped dollar sign ``\\$`` prints a literal ``$``.
    """
    return str(text).replace("$", r"\$")


def file_stem(name: str) -> str:
    """A figure's file name from a name that may hold a user's string (an output ``../x``): one
    plain file inside the report folder."""
    stem = re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_")[:100]
    return stem or "figure"


def fmt(v: object, digits: int = 4) -> str:
    """Format a table cell: numbers with ``digits`` significant digits."""
    if isinstance(v, bool) or v is None:
        return "" if v is None else str(v)
    if isinstance(v, (int, float)):
        return f"{v:.{digits}g}"
    return str(v)


@dataclass
class Report:
    """Collects sections, then writes ``report.html`` (self-contained) and the figures as PNG.

    Building a report is the only mutable step; it happens once, at the end of a command.
    """

    title: str
    parts: list[str] = field(default_factory=list)
    figures: dict[str, bytes] = field(default_factory=dict)

    def heading(self, text: str, level: int = 2) -> None:
        self.parts.append(f"<h{level}>{html.escape(text)}</h{level}>")

    def paragraph(self, text: str, css: str | None = None) -> None:
        """A paragraph; ``text`` may contain simple inline HTML written by rczone itself."""
        cls = f' class="{css}"' if css else ""
        self.parts.append(f"<p{cls}>{text}</p>")

    def bullets(self, items: Sequence[str]) -> None:
        """A bulleted list; each item may contain simple inline HTML written by rczone itself."""
        if items:
            self.parts.append("<ul>" + "".join(f"<li>{item}</li>" for item in items) + "</ul>")

    def extend(self, other: Report) -> None:
        """Append ``other``'s sections and figures (a summary written last can then come first)."""
        self.parts.extend(other.parts)
        self.figures.update(other.figures)

    def table(self, rows: Sequence[Mapping[str, object]], caption: str = "", digits: int = 4) -> None:
        """A table from a list of dicts sharing keys (first key is the row label)."""
        if not rows:
            return
        cols = list(rows[0])
        head = "".join(f"<th>{html.escape(str(c))}</th>" for c in cols)
        body = "".join(
            "<tr>" + "".join(f"<td>{html.escape(fmt(r.get(c), digits))}</td>" for c in cols) + "</tr>"
            for r in rows
        )
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        self.parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")

    def figure(self, name: str, fig: Figure, caption: str = "") -> None:
        """Embed a matplotlib figure; it is also written as ``<name>.png``."""
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
        png = buf.getvalue()
        self.figures[file_stem(name)] = png
        b64 = base64.b64encode(png).decode("ascii")
        self.parts.append(
            f'<figure><img alt="{html.escape(caption or name)}" src="data:image/png;base64,{b64}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>"
        )

    def render(self) -> str:
        """The whole page."""
        return (
            '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head><body>"
            f"<h1>{html.escape(self.title)}</h1>" + "\n".join(self.parts) + "</body></html>\n"
        )

    def write(self, folder: str | os.PathLike, *, under: str | None = None) -> Path:
        """Write ``report.html`` and every figure's PNG into ``folder`` (atomically each, never outside it).

        Parameters
        ----------
        folder : str or path
            The user's folder (it may be a link).
        under : str, optional
            A subfolder rczone names itself (``"holdout"``): opened like the files, so a symbolic
            link planted at its name is refused, never followed.
        """
        folder = Path(folder)
        prefix = f"{under}/" if under else ""
        for name, png in self.figures.items():
            write_bytes_in(folder, f"{prefix}{name}.png", png)
        return write_text_in(folder, f"{prefix}report.html", self.render())
