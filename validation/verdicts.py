"""The verdict rczone gives a fit, as one cell of the validation tables (docs/validation.md).

Every table of docs/validation.md that lists fits carries the verdict rczone itself gives each of
them (issue 38): ``trustworthy``, or ``flagged:`` and the checks that failed, each named in a few
words (the full sentences are in the fit's JSON, ``verdict.reasons``). The names are read off the
reasons :func:`rczone.results.verdict.verdict_of` writes: a fit's own flags
(:mod:`rczone.estimation.minimize`), the held-out checks (:mod:`rczone.postfit.evidence`), the
robust standard errors, flat profiles, fits to other data that disagree, implausible or dropped
data. A reason of another form is kept, cut to its first words, never dropped.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent

#: (pattern over one reason, the check's name; ``{0}`` is the parameter the pattern captured).
PATTERNS: tuple[tuple[str, str], ...] = (
    (r"^held out, (\w+) failed", "held-out {0}"),
    (r"^(\w+) is at a bound", "{0} at a bound"),
    (r"^Hessian not positive definite", "Hessian not positive definite"),
    (r"^no standard error for (.+)$", "no standard error ({0})"),
    (r"^not converged", "not converged"),
    (r"^starts that reach the same cost disagree on (\w+)", "starts disagree on {0}"),
    (r"^a value of (\w+) ten times", "{0} flat profile"),
    (r"^(\w+): its robust standard error", "{0} robust SE >= 100 %"),
    (r"^(\w+) fitted to .* disagree beyond", "{0} disagrees on other data"),
    (r"^implausible data", "implausible data"),
    (r"^fitted on \d+ of \d+ samples", "inputs missing"),
    (r"^the posterior of (\w+) piles up at a bound", "{0} posterior at a bound"),
)
#: Words kept of a reason no pattern names.
UNNAMED_WORDS = 6


def check_name(reason: str) -> str:
    """The failed check a verdict's reason names, in a few words.

    Parameters
    ----------
    reason : str
        One of :attr:`rczone.results.verdict.Verdict.reasons`.

    Returns
    -------
    str
    """
    for pattern, name in PATTERNS:
        m = re.search(pattern, reason)
        if m:
            return name.format(*m.groups())
    words = reason.split()
    return " ".join(words[:UNNAMED_WORDS]) + (" …" if len(words) > UNNAMED_WORDS else "")


def verdict_cell(verdict: Any) -> str:
    """``trustworthy``, or ``flagged: `` and the failed checks, for a Markdown table.

    Parameters
    ----------
    verdict : Verdict or mapping
        The fit's :class:`~rczone.results.verdict.Verdict`, or its JSON form (``trustworthy`` and
        ``reasons``), as ``rczone fit --json`` writes it under ``verdict``.

    Returns
    -------
    str
    """
    if isinstance(verdict, Mapping):
        trustworthy, reasons = verdict["trustworthy"], verdict.get("reasons") or ()
    else:
        trustworthy, reasons = verdict.trustworthy, verdict.reasons
    if trustworthy:
        return "trustworthy"
    names = list(dict.fromkeys(check_name(r) for r in reasons))
    return "flagged: " + ", ".join(names).replace("|", "/") if names else "flagged"


def flags_cell(flags: Iterable[str], trustworthy: bool) -> str:
    """:func:`verdict_cell` from a candidate's JSON (``rczone select --json``: ``trustworthy`` and ``flags``)."""
    return verdict_cell({"trustworthy": trustworthy, "reasons": list(flags)})
