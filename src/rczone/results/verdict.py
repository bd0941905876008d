"""One verdict on a fit, computed once, shown the same in the console, the JSON and the report.

A fit can be untrustworthy for reasons of its own (an estimate at a bound, no standard error, an
indefinite Hessian, a search that has not settled) and for reasons the checks after it find on
the estimates themselves: a profile flat over a factor of ten, or fits to other data that
disagree beyond their standard errors. The identifiability analysis at the estimates adds notes.
Before, the report said "do not trust" from the analysis while the command exited 0; here one
:class:`Verdict` decides the exit code, the console's last lines, the JSON's ``trustworthy`` and
``verdict`` and the report's warnings.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

#: Exit code of a command whose result is flagged untrustworthy.
EXIT_UNTRUSTED = 3


class Verdict(NamedTuple):
    """Whether a fit's estimates can be used, and why not.

    Attributes
    ----------
    trustworthy : bool
        No reason below.
    reasons : tuple of str
        Each reason, one sentence.
    suspect : tuple of str
        Parameters not to trust (empty when only the search itself is flagged).
    checked : tuple of str
        What the verdict rests on: ``"fit"`` always; ``"identifiability"``, ``"profiles"``,
        ``"other data"`` when those checks ran.
    notes : tuple of str
        Findings that do not make the fit untrustworthy (a parameter identified only weakly).
    """

    trustworthy: bool
    reasons: tuple[str, ...]
    suspect: tuple[str, ...]
    checked: tuple[str, ...]
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields."""
        return {
            "trustworthy": self.trustworthy,
            "reasons": list(self.reasons),
            "suspect": list(self.suspect),
            "checked": list(self.checked),
            "notes": list(self.notes),
        }


#: A fit on less than this fraction of the samples (the rest dropped for missing inputs) is flagged.
FLAGGED_USED_FRACTION = 0.9


def dropped_samples(data_used: Mapping[str, Any] | None) -> str | None:
    """The reason a fit on part of its data is flagged, naming the inputs and the times; None if it is not.

    Parameters
    ----------
    data_used : mapping, optional
        The fitted model's ``provenance["stretch"]``: ``samples``, ``of``, ``fraction`` and ``missing``
        (:func:`rczone.calibration.dataset.missing_inputs`).
    """
    if not data_used or data_used.get("fraction", 1.0) >= FLAGGED_USED_FRACTION:
        return None
    where = "; ".join(
        f"{m['channel']} is missing at {m['samples']} sample(s) between t = {m['first_s']:.10g} s and"
        f" {m['last_s']:.10g} s"
        for m in data_used.get("missing") or ()
    )
    return (
        f"fitted on {data_used['samples']} of {data_used['of']} samples ({data_used['fraction']:.0%}), the"
        f" longest stretch where every input is known{': ' + where if where else ''}; fill the gaps or select"
        " the stretch with the column map's [time] start and end"
    )


def verdict_of(
    result,
    identifiability=None,
    checks: Mapping[str, Any] | None = None,
    *,
    data: Sequence[str] = (),
    data_used: Mapping[str, Any] | None = None,
    notes: Sequence[str] = (),
) -> Verdict:
    """The one verdict on a fit from its own flags and the checks made after it.

    Parameters
    ----------
    result : FitResult
        The fit (its ``flags`` and ``parameters``).
    identifiability : IdentifiabilityReport, optional
        The identifiability analysis at the estimates. What it calls ``"weak"`` or
        ``"not identifiable"`` is a note, not a flag: it allows for a worst-case model error
        (0.2 K by default) and calls parameters not identifiable that the fit recovers to a few
        per cent (a two-zone forced test of the virtual building, every one of ten parameters;
        a heated zone simulated from the model itself), so it asks for the check that decides,
        the same fit on other data (Lin et al. 2012, sec. V: closed-loop data give grossly wrong
        R and C that still fit).
    checks : mapping, optional
        The JSON-ready post-fit checks (``profiles``, ``disagreements``): a profile flat over a
        factor of ten, or fits to other data that disagree, make the estimate untrustworthy.
    data : sequence of str
        The data's signals outside their plausible range (:attr:`rczone.estimation.Dataset.warnings`):
        temperatures in degF read as degC fit as well as any, so each is a reason not to trust the fit.
    data_used : mapping, optional
        The samples the fit used (:func:`dropped_samples`): fewer than
        :data:`FLAGGED_USED_FRACTION` of the record flag the fit.
    notes : sequence of str
        Notes the caller adds (a fit that held every R and C is an evaluation).

    Returns
    -------
    Verdict
    """
    reasons = list(result.flags) + [f"implausible data: {line}" for line in data]
    dropped = dropped_samples(data_used)
    if dropped:
        reasons.append(dropped)
    suspect = [n for n, e in result.parameters.items() if e.at_bound and result.issues]
    checked = ["fit"]
    notes = list(notes)
    if checks:
        if checks.get("other_fits"):
            checked.append("other data")
        for d in checks.get("disagreements") or ():
            if d["disagree"]:
                reasons.append(
                    f"{d['name']} fitted to {d['data_a']} ({d['estimate_a']:.3g}) and to {d['data_b']}"
                    f" ({d['estimate_b']:.3g}) disagree beyond their standard errors"
                )
                suspect.append(d["name"])
        if checks.get("profiles"):
            checked.append("profiles")
        for name, p in (checks.get("profiles") or {}).items():
            if p["flat_low"] or p["flat_high"]:
                side = "ten times smaller" if p["flat_low"] else "ten times larger"
                reasons.append(f"a value of {name} {side} fits these data about as well")
                suspect.append(name)
    if identifiability is not None:
        checked.append("identifiability")
        verdicts = {n: v.verdict for n, v in identifiability.parameters.items() if n in result.parameters}
        error_K = (getattr(identifiability, "settings", None) or {}).get("model_error_K", 0.2)
        for word in ("not identifiable", "weak"):
            names = [n for n, v in verdicts.items() if v == word]
            if names:
                notes.append(
                    f"the identifiability analysis at the estimates calls {', '.join(names)} {word}"
                    f" (allowing {error_K:g} K of model error):"
                    f" confirm {'it' if len(names) == 1 else 'them'} on other data (--check-on) before relying on"
                    f" {'it' if len(names) == 1 else 'them'}"
                )
    return Verdict(not reasons, tuple(reasons), tuple(dict.fromkeys(suspect)), tuple(checked), tuple(notes))
