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
    held_out : mapping or None
        The held-out checks (``coverage``, ``baselines``, ``innovations``: outcome and detail),
        ``failed`` and the thresholds; None without ``--holdout``.
    standard_errors : {"hessian", "robust"}
        Which standard errors the verdict read (robust when the innovations are not white).
    """

    trustworthy: bool
    reasons: tuple[str, ...]
    suspect: tuple[str, ...]
    checked: tuple[str, ...]
    notes: tuple[str, ...] = ()
    held_out: Mapping[str, Any] | None = None
    standard_errors: str = "hessian"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields."""
        return {
            "trustworthy": self.trustworthy,
            "reasons": list(self.reasons),
            "suspect": list(self.suspect),
            "checked": list(self.checked),
            "notes": list(self.notes),
            "held_out": dict(self.held_out) if self.held_out is not None else None,
            "standard_errors": self.standard_errors,
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


#: A robust relative standard error (of log theta) at or above this leaves an R, C or gain
#: undetermined: the data cannot tell it from a value e times smaller or larger (the threshold of
#: "not identifiable" of :mod:`rczone.diagnostics.identifiability`, ``SE_NOT_IDENTIFIABLE``).
ROBUST_REL_SE_MAX = 1.0
#: Kinds whose robust errors the verdict judges (noise levels and initial states are nuisances).
JUDGED_KINDS = ("resistance", "capacitance", "gain")


def robust_findings(result, robust, white: bool | None) -> tuple[list[str], list[str], list[str]]:
    """``(reasons, suspect, notes)`` from the sandwich standard errors when the innovations are not white.

    Parameters
    ----------
    result : FitResult
        The fit.
    robust : RobustErrors or None
        Its sandwich standard errors (:mod:`rczone.postfit.robust`).
    white : bool or None
        Whether the innovations are white (None: no innovations). Only ``False`` makes the verdict
        read the robust errors: for a model that is right the two agree.
    """
    if robust is None or white is not False:
        return [], [], []
    reasons, suspect = [], []
    widened = []
    for n, e in result.parameters.items():
        se = robust.std_errors.get(n, float("nan"))
        if e.kind not in JUDGED_KINDS or not se == se or not e.value > 0:
            continue
        rel, rel_h = se / e.value, e.std_error / e.value
        widened.append(f"{n} ±{rel_h:.1%} -> ±{rel:.1%}")
        if rel >= ROBUST_REL_SE_MAX:
            reasons.append(
                f"{n}: its robust standard error is {rel:.0%} of the estimate (the Hessian's {rel_h:.1%}):"
                " with innovations that are not white, these data do not determine it"
            )
            suspect.append(n)
    note = (
        "the innovations are not white, so the Hessian's standard errors are too small; the verdict reads"
        " the robust (sandwich) ones"
    )
    return reasons, suspect, [note + (": " + ", ".join(widened) if widened else "")]


def verdict_of(
    result,
    identifiability=None,
    checks: Mapping[str, Any] | None = None,
    *,
    data: Sequence[str] = (),
    data_used: Mapping[str, Any] | None = None,
    notes: Sequence[str] = (),
    robust=None,
    white: bool | None = None,
    evidence=None,
    excitation=None,
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
    robust : RobustErrors, optional
        The sandwich standard errors; read instead of the Hessian's when ``white`` is False
        (:func:`robust_findings`).
    white : bool, optional
        Whether the fit's innovations are white.
    evidence : HeldOutEvidence, optional
        The held-out checks (:mod:`rczone.postfit.evidence`): coverage per horizon, the
        baselines, the innovations; each failed one is a reason.
    excitation : Excitation, optional
        Whether the inputs were excited apart (:mod:`rczone.data.excitation`): each group of
        collinear inputs is a note, named as the likely cause of estimates at a bound.

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
    exc = excitation if excitation is not None else getattr(identifiability, "excitation", None)
    if exc is not None and exc.collinear:
        cause = (
            " (the likely cause of the estimates at a bound)"
            if any(e.at_bound for e in result.parameters.values())
            else ""
        )
        notes += [f"{f}{cause}" for f in exc.findings()]
    more, names, robust_notes = robust_findings(result, robust, white)
    reasons += more
    suspect += names
    notes += robust_notes
    held_out = None
    if evidence is not None:
        checked.append("held-out data")
        reasons += evidence.reasons
        notes += evidence.notes
        held_out = evidence.to_dict()
    return Verdict(
        not reasons,
        tuple(reasons),
        tuple(dict.fromkeys(suspect)),
        tuple(checked),
        tuple(notes),
        held_out,
        "robust" if robust_notes else "hessian",
    )
