"""The report of ``rczone diagnose``: data overview, indicators and the verdict per parameter."""

from __future__ import annotations

import html

import pandas as pd

from rczone.diagnostics import IdentifiabilityReport
from rczone.report import figures as figs
from rczone.report.html import Report

_CSS = {"identifiable": "good", "weak": "", "not identifiable": "bad"}


def add_verdicts(report: Report, rep: IdentifiabilityReport) -> None:
    """The verdict table and the reasons, in plain words."""
    rows = [
        {
            "parameter": n,
            "construction value": v.construction,
            "expected ± (relative)": f"{v.expected_rel_se:.0%}" if v.expected_rel_se < 10 else "> 1000%",
            "change if /10 (K RMS)": v.rms_change_tenth_K,
            "change if x10 (K RMS)": v.rms_change_tenfold_K,
            "verdict": v.verdict,
        }
        for n, v in rep.parameters.items()
    ]
    report.table(rows, "Identifiability of each free parameter", digits=3)
    for n, v in rep.parameters.items():
        css = _CSS[v.verdict]
        text = f'<b>{html.escape(n)}</b>: <span class="{css}">{html.escape(v.verdict)}</span> because {html.escape(v.reason)}.'
        if v.advice:
            text += f" <i>What to do:</i> {html.escape(v.advice)}."
        report.paragraph(text, "note" if v.verdict == "identifiable" else "warn")


def diagnose_report(
    rep: IdentifiabilityReport, frame: pd.DataFrame, data_name: str, model_name: str
) -> Report:
    """A full report for one diagnose run."""
    r = Report(f"Can {data_name} identify the {model_name} model?")
    r.paragraph(
        "rczone checks, before any fit, whether the data carry enough information to pin down each "
        "parameter. It measures how far the room moved from each neighbouring space (a wall's "
        "resistance only shows when heat actually flows through it), computes how precisely a fit "
        "could determine each parameter from the exact sensitivities of the room temperature, and "
        "tries a value ten times smaller and larger to see whether the data could tell the difference "
        f"once the unknown initial state and heat gain are allowed for. Error level assumed: {rep.sigma_K:g} K."
    )
    r.heading("Data")
    r.figure("data_overview", figs.data_overview(frame), f"{data_name}: temperatures and supply flow")
    sur = [
        {
            "surrounding": s.name,
            "max |Ti - Tj| (K)": s.max_abs_diff_K,
            "median |Ti - Tj| (K)": s.median_abs_diff_K,
            "correlation with Ti": s.correlation,
        }
        for s in rep.indicators.surroundings
    ]
    r.table(sur, "How far the room moved from each surrounding space", digits=3)
    r.heading("Verdicts")
    add_verdicts(r, rep)
    return r
