"""The report of ``rczone fit``: fit against the data, residuals, parameters, verdicts."""

from __future__ import annotations

import html
import math

import pandas as pd

from rczone.calibrate import Calibration
from rczone.diagnostics import IdentifiabilityReport
from rczone.report import figures as figs
from rczone.report.diagnose import add_verdicts
from rczone.report.html import Report


def parameter_rows(cal: Calibration) -> list[dict[str, object]]:
    """One row per free parameter: estimate, standard error, construction value, ratio, flags."""
    r = cal.result
    rows = []
    for n in r.names:
        se = r.std_errors[n]
        rows.append(
            {
                "parameter": n,
                "estimate": r.estimates[n],
                "std. error": se if math.isfinite(se) else None,
                "construction": r.construction[n] if math.isfinite(r.construction[n]) else None,
                "estimate / construction": r.ratio_to_construction(n)
                if math.isfinite(r.construction[n])
                else None,
                "at bound": "yes" if r.at_bound[n] else "",
            }
        )
    return rows


def fit_report(
    cal: Calibration, frame: pd.DataFrame, data_name: str, model_name: str, diag: IdentifiabilityReport | None
) -> Report:
    """A full report for one fit."""
    r = cal.result
    rep = Report(f"Fit of {model_name} to {data_name} ({r.method.upper()})")
    rep.paragraph(
        f"Method {html.escape(r.method.upper())}, optimizer {html.escape(r.optimizer)}, {len(r.starts)} start(s),"
        f" {r.n_evals} cost evaluations; {'converged' if r.converged else 'did NOT converge'}."
    )
    if r.flags:
        rep.paragraph("Warnings: " + html.escape("; ".join(r.flags)), "warn")
    rep.heading("Data")
    rep.figure("data_overview", figs.data_overview(frame), f"{data_name}: temperatures and supply flow")
    rep.heading("Fit")
    ol = cal.open_loop
    rep.figure(
        "fit",
        figs.fit_overview(ol.t, frame["Ti"].to_numpy(float), ol.y_hat[:, 0]),
        "Open-loop simulation of the fitted model",
    )
    rep.paragraph(f"Open-loop RMSE {ol.rmse_K:.3f} K, largest error {ol.max_abs_K:.3f} K.")
    rep.table(parameter_rows(cal), "Estimates beside their construction (ASHRAE) values", digits=4)
    res = cal.residuals
    rep.heading("Residuals")
    rep.figure(
        "residual_acf",
        figs.residual_acf(res.lags, res.acf, len(ol.t)),
        "Autocorrelation of the open-loop error",
    )
    rep.paragraph(
        f"Ljung-Box Q = {res.q_statistic:.1f}, p = {res.p_value:.3g}: the residuals are "
        + (
            "consistent with white noise."
            if res.white_at_5pct
            else "<b>not</b> white; the model misses some dynamics or inputs."
        )
    )
    if diag is not None:
        rep.heading("Can these data identify the parameters?")
        add_verdicts(rep, diag)
        bad = [n for n, v in diag.parameters.items() if v.verdict != "identifiable" and n in r.names]
        if bad:
            rep.paragraph(
                "Do not trust the estimate(s) of "
                + html.escape(", ".join(bad))
                + " from these data, however well the"
                " model fits: a grossly different value would fit about as well.",
                "warn",
            )
    return rep
