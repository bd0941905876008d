"""The report of ``rczone fit``: fit against the data, residuals, parameters, verdicts."""

from __future__ import annotations

import html
import math

import pandas as pd

from rczone.calibration import Calibration
from rczone.diagnostics import IdentifiabilityReport
from rczone.report import figures as figs
from rczone.report.diagnose import add_verdicts, signal_panels
from rczone.report.html import Report


def parameter_rows(cal: Calibration) -> list[dict[str, object]]:
    """One row per free parameter: estimate, unit, standard error, construction value, ratio, flags.

    A built-in model of the Bacher & Madsen family starts from generic values, not construction
    data: its column says "generic start" and no ratio is given.
    """
    from rczone.models.library import is_family_name

    r = cal.result
    generic = is_family_name(cal.model_label)
    rows = []
    for n, e in r.parameters.items():
        before = e.construction if math.isfinite(e.construction) else None
        row = {
            "parameter": n,
            "estimate": e.value,
            "unit": e.unit,
            "std. error": e.std_error if math.isfinite(e.std_error) else None,
        }
        if generic:
            row["generic start"] = before
        else:
            row["construction"] = before
            row["estimate / construction"] = e.ratio_to_construction if before is not None else None
        row["at bound"] = "yes" if e.at_bound else ""
        rows.append(row)
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
    verdict = cal.verdict
    if not verdict.trustworthy:
        rep.paragraph(
            f"Result flagged (exit code {cal.exit_code}): " + html.escape("; ".join(verdict.reasons)),
            "warn",
        )
    rep.heading("Data")
    rep.figure(
        "data_overview",
        figs.signals_overview(frame, signal_panels(cal.model)),
        f"{data_name}: the model's signals",
    )
    rep.heading("Fit")
    ol = cal.open_loop
    for j, (o, rmse, worst) in enumerate(cal.output_errors()):
        rep.figure(
            "fit" if j == 0 else f"fit_{o}",
            figs.fit_overview(ol.t, ol.y_hat[:, j] + ol.error[:, j], ol.y_hat[:, j], label=o),
            f"Open-loop simulation of the fitted model: {o}",
        )
        rep.paragraph(f"{html.escape(o)}: open-loop RMSE {rmse:.3f} K, largest error {worst:.3f} K.")
    rows = parameter_rows(cal)
    caption = (
        "Estimates beside the model's generic starting values"
        if rows and "generic start" in rows[0]
        else "Estimates beside their construction (ASHRAE) values"
    )
    rep.table(rows, caption, digits=4)
    if r.posterior is not None:
        from rczone.report.posterior import add_posterior

        add_posterior(rep, r.posterior)
    if cal.plausibility is not None:
        rep.paragraph(html.escape(cal.plausibility.line()) + ".")
        for w in cal.plausibility.warnings:
            rep.paragraph("Implausible: " + html.escape(w) + ".", "warn")
    add_residuals(rep, cal)
    if diag is not None:
        rep.heading("Can these data identify the parameters?")
        add_verdicts(rep, diag)
        for note in verdict.notes:
            rep.paragraph(html.escape(note[0].upper() + note[1:]) + ".", "warn")
    if checks:
        add_checks(rep, cal, checks)
    return rep


def add_residuals(rep: Report, cal: Calibration) -> None:
    """The innovations of an ML fit, or the open-loop error of an LS fit labelled as such."""
    inn, olr = cal.innovations, cal.open_loop_residuals
    if inn is not None:
        rep.heading("Innovations: is anything left to explain?")
        rep.paragraph(
            "The one-step-ahead prediction errors of the Kalman filter, each divided by its predicted"
            " standard deviation. For an adequate model they are white: no autocorrelation beyond the"
            " band, a cumulative periodogram inside its Kolmogorov-Smirnov band, and no correlation"
            " with past inputs."
        )
        for j, o in enumerate(inn.outputs):
            _residual_figure(rep, inn, j, "innovations", "Innovations")
            rep.paragraph(_verdict(inn, j), None if o.white else "warn")
        if olr is not None:
            rep.paragraph(
                f"For comparison, the open-loop error's Ljung-Box p = {olr.ljung_box_p:.3g}: open-loop"
                " errors accumulate the process noise and are not white even for the true model, so"
                " their whiteness says nothing about the structure.",
                "note",
            )
    elif olr is not None:
        rep.heading("Open-loop residuals (not innovations)")
        rep.paragraph(
            "A least-squares fit has no noise model, hence no innovations: these are the errors of the"
            " open-loop simulation. They accumulate every unmodelled disturbance and are <b>not expected"
            " to be white</b>, even for the right model; fit by ML (--method ml) to test the model"
            " structure on its innovations.",
            "note",
        )
        for j, o in enumerate(olr.outputs):
            _residual_figure(rep, olr, j, "open_loop_residuals", "Open-loop error")
            rep.paragraph(
                f"Ljung-Box p = {o.p_value:.3g} over {o.lb_lags} lags; autocorrelation at the first lag"
                f" {o.acf[1]:.2f}."
            )


def _residual_figure(rep: Report, an, j: int, name: str, what: str) -> None:
    o = an.outputs[j].output
    rep.figure(
        f"{name}_{o}" if j else name,
        figs.residual_panels(an, j),
        f"{what} of {o}: series, autocorrelation (lags in hours), cumulative periodogram (top axis:"
        " period) and cross-correlation with each input, 95 % bands",
    )


def _verdict(an, j: int) -> str:
    """One paragraph saying what the residual statistics of output ``j`` show."""
    o = an.outputs[j]
    lag1 = f"{an.lags_h[1] * 60:.0f} min" if an.lags_h[1] < 1 else f"{an.lags_h[1]:.2g} h"
    parts = [
        f"Ljung-Box Q = {o.q_statistic:.1f} over {o.lb_lags} lags, p = {o.p_value:.3g}: "
        + ("consistent with white noise" if o.white else "<b>not</b> white"),
        f"autocorrelation at {lag1}: {o.acf[1]:.2f} (band ±{o.band:.2f})",
        "cumulative periodogram "
        + ("inside" if o.periodogram.inside_band else "<b>outside</b>")
        + f" its band (largest deviation {o.periodogram.max_deviation:.2f}, band {o.periodogram.band:.2f})",
    ]
    worst = o.worst_input()
    if worst is not None:
        name, value, k = worst
        parts.append(
            f"largest cross-correlation with an input: {html.escape(name)} {value:.2f} at"
            f" {k * an.dt_s / 3600:.2g} h" + (" (outside the band)" if value > o.band else "")
        )
    text = "; ".join(parts) + "."
    if not o.white:
        text += " The model misses some dynamics or an input."
    return text


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
    shown = {n: p for n, p in checks["profiles"].items() if n in r.estimates and len(p.get("values", ())) > 1}
    if shown:
        rep.figure(
            "profiles",
            figs.profile_curves(shown, r.estimates, {n: e.unit for n, e in r.parameters.items()}),
            "Profile of each parameter: the cost re-minimized over the others, its rise above the"
            " minimum (per 30 min of correlated error); dashed: the 95 % threshold; shaded: the"
            " profile interval; vertical line: the estimate",
        )
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
