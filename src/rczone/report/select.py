"""The report of ``rczone select``: the candidates, the tests between nested ones, their innovations."""

from __future__ import annotations

import html
import math

from rczone.report import figures as figs
from rczone.report.html import Report
from rczone.selection.compare import Selection


def selection_report(sel: Selection, data_name: str) -> Report:
    """Table of candidates, likelihood-ratio tests, the forward path and the innovations compared."""
    how = (
        f"forward selection by likelihood-ratio tests at level {sel.alpha:g}"
        if sel.rule == "forward"
        else f"the smallest {sel.rule.upper()}"
    )
    rep = Report(f"Model selection on {data_name}")
    rep.paragraph(
        f"{len(sel.candidates)} candidate(s) fitted by maximum likelihood to the same"
        f" {sel.samples['n']} samples ({sel.samples['n_obs']} measured outputs). Selected:"
        f" <b>{html.escape(sel.selected)}</b>, by {html.escape(how)}."
    )
    inn = sel.best.calibration.innovations
    if inn is not None and not inn.white:
        rep.paragraph(
            f"The innovations of {html.escape(sel.selected)} are not white (Ljung-Box p ="
            f" {inn.ljung_box_p:.2g}): every candidate misses some dynamics or input.",
            "warn",
        )
    conditional = sel.basis is not None and sel.basis.conditional
    if conditional:
        rep.paragraph(
            "The candidates measure different outputs, so their own likelihoods are of different data."
            f" They are compared on one quantity both predict: the likelihood {html.escape(sel.basis.describe())},"
            " one step ahead (for a joint model by Gaussian conditioning of its innovations on the"
            " neighbours' innovations at the same time; for a model that takes the neighbours'"
            " measurements as inputs, its own likelihood).",
            "note",
        )
    rep.heading("Candidates")
    rep.table(
        sel.table(),
        ("log L: log-likelihood " + (sel.basis.describe() if conditional else "at the estimate"))
        + "; k: free parameters (noise levels included);"
        " AIC = 2k - 2 log L; BIC = k log n - 2 log L; Ljung-Box p of the standardized innovations",
        digits=5,
    )
    if sel.vuong:
        rep.heading("Vuong tests between non-nested candidates")
        rep.paragraph(
            "Vuong's (1989) test: the per-sample log-likelihood differences averaged and divided by"
            " their long-run (Newey-West) standard deviation; under equal closeness to the truth the"
            " statistic is standard normal. The Schwarz-corrected statistic charges the extra parameters."
        )
        rep.table(
            [
                {
                    "model a": v.a,
                    "model b": v.b,
                    "log L ratio": v.loglik_ratio,
                    "z": v.statistic,
                    "p": v.p_value,
                    "z (BIC)": v.statistic_bic,
                    "p (BIC)": v.p_value_bic,
                    f"closer at {sel.alpha:g}": v.closer(sel.alpha) or "neither",
                }
                for v in sel.vuong
            ],
            f"Each pair of non-nested candidates, {sel.basis.describe()}",
            digits=3,
        )
    if sel.tests or not sel.vuong:
        rep.heading("Likelihood-ratio tests")
    if sel.tests:
        rep.paragraph(
            "Nesting is detected from the networks: the simpler model is the richer one with the"
            " parameters of the restriction at a limit. p: chi2(df), conservative where a restriction"
            " is at the boundary of the parameter's domain; chi-bar²: the boundary mixture."
        )
        rep.table(
            [
                {
                    "simple": t.simple,
                    "rich": t.rich,
                    "restriction": t.nesting.describe(),
                    "LR": t.statistic,
                    "df": t.df,
                    "p": t.p_value,
                    "p (chi-bar²)": t.p_value_chi_bar,
                    f"rejects at {sel.alpha:g}": "yes" if t.rejects(sel.alpha) else "no",
                }
                for t in sel.tests
            ],
            "Each simpler model against each richer model it is nested in",
            digits=3,
        )
    elif not sel.vuong:
        rep.paragraph("No candidate is nested in another: the models are compared by AIC and BIC only.")
    if sel.steps:
        rep.heading("Forward selection")
        rep.table(
            [
                {
                    "from": s["from"],
                    "extensions fitted": ", ".join(s["tried"]),
                    "best": s["best"],
                    "LR": s["statistic"],
                    "df": s["df"],
                    "p": s["p_value"],
                    "step": "accepted" if s["accepted"] else "rejected: stop",
                }
                for s in sel.steps
            ],
            "Each step: the smallest extensions of the current model, the best of them and its test",
            digits=3,
        )
        if sel.not_fitted:
            rep.paragraph("Not reached: " + html.escape(", ".join(sel.not_fitted)) + ".")
    analyses = {
        n: c.calibration.innovations
        for n, c in sel.candidates.items()
        if c.calibration.innovations is not None
    }
    if analyses:
        rep.heading("Innovations of the candidates")
        rep.figure(
            "innovations_compared",
            figs.residual_comparison(analyses),
            "Autocorrelation of each candidate's standardized innovations (lags in hours) and their"
            " cumulative periodograms (top axis: period), 95 % bands of white noise",
        )
        best = sel.best.calibration.innovations
        if best is not None:
            rep.figure(
                "innovations_selected",
                figs.residual_panels(best),
                f"The selected model {sel.selected}: innovations, autocorrelation, cumulative periodogram"
                " and cross-correlation with each input",
            )
    rep.heading("Estimates of the selected model")
    r = sel.best.calibration.result
    rep.table(
        [
            {
                "parameter": n,
                "estimate": e.value,
                "unit": e.unit,
                "std. error": e.std_error if math.isfinite(e.std_error) else None,
                "at bound": "yes" if e.at_bound else "",
            }
            for n, e in r.parameters.items()
        ],
        f"{sel.selected} fitted by ML",
        digits=4,
    )
    return rep
