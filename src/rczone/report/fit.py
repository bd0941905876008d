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
    cal: Calibration,
    frame: pd.DataFrame,
    data_name: str,
    model_name: str,
    diag: IdentifiabilityReport | None,
    checks: dict | None = None,
) -> Report:
    """A full report for one fit (``checks``: the JSON-ready post-fit checks of ``rczone fit``)."""
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
    if checks:
        add_checks(rep, cal, checks)
    return rep


def add_checks(rep: Report, cal: Calibration, checks: dict) -> None:
    """The section "Can the estimates be trusted?" from the post-fit checks."""
    r = cal.result
    rep.heading("After the fit: can the estimates be trusted?")
    rows = []
    for n in r.names:
        ratio = r.ratio_to_construction(n)
        prof = checks["profiles"].get(n)
        if prof:
            lo, hi = prof["interval"]
            shape = (
                "flat: a value ten times smaller fits as well"
                if prof["flat_low"]
                else "flat: a value ten times larger fits as well"
                if prof["flat_high"]
                else "curved"
            )
            interval = f"{_fmt(lo)} to {_fmt(hi)}"
        else:
            shape = interval = ""
        rows.append(
            {
                "parameter": n,
                "estimate": r.estimates[n],
                "estimate / construction": ratio if math.isfinite(ratio) else None,
                "far from construction": "yes" if n in checks["far_from_construction"] else "",
                "at bound": "yes" if n in checks["at_bound"] else "",
                "profile": shape,
                "95% profile interval": interval,
            }
        )
    rep.table(rows, "Checks per parameter (profiles counted per 30 min of correlated error)", digits=3)
    if checks["disagreements"]:
        rep.table(
            [
                {
                    "parameter": d["name"],
                    "data": f"{d['data_a']} vs {d['data_b']}",
                    "estimates": f"{d['estimate_a']:.3g} vs {d['estimate_b']:.3g}",
                    "z": d["z"],
                    "verdict": "DISAGREE" if d["disagree"] else "agree",
                }
                for d in checks["disagreements"]
            ],
            "The same model fitted to other data sets",
            digits=2,
        )
    if checks["validation"]:
        rep.table(
            [
                {"data": k, "RMSE (K)": v["rmse_K"], "max error (K)": v["max_error_K"]}
                for k, v in checks["validation"].items()
            ],
            "This fit predicting the other data sets open loop",
            digits=3,
        )
    worry = sorted(
        {d["name"] for d in checks["disagreements"] if d["disagree"]}
        | set(checks["far_from_construction"])
        | set(checks["at_bound"])
        | {n for n, p in checks["profiles"].items() if p["flat_low"] or p["flat_high"]}
    )
    if worry:
        rep.paragraph(
            "Treat "
            + html.escape(", ".join(worry))
            + " with suspicion: a parameter the data pin down is not at"
            " a bound, not far from what the construction suggests without a reason, has a curved profile, and"
            " comes out the same on other data.",
            "warn",
        )


def _fmt(x: float) -> str:
    return "open" if not math.isfinite(x) else f"{x:.3g}"
