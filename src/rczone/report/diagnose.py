"""The report of ``rczone diagnose``: data overview, operating point, indicators and the verdict per parameter."""

from __future__ import annotations

import html

from rczone.diagnostics import IdentifiabilityReport
from rczone.models import ZoneModel
from rczone.report import figures as figs
from rczone.report.html import Report

_CSS = {"identifiable": "good", "weak": "", "not identifiable": "bad"}


def add_verdicts(report: Report, rep: IdentifiabilityReport) -> None:
    """The verdict table and the reasons, in plain words."""
    rows = [
        {
            "parameter": n,
            "value used": v.value,
            "construction value": v.construction,
            "unit": rep.units.get(n, ""),
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


def signal_panels(zm: ZoneModel) -> list[tuple[str, list[str]]]:
    """The model's signals grouped by quantity: temperatures around the zone, supply temperatures, flows, heat."""
    net = zm.network
    around = [*net.outputs, *net.boundaries]
    for b in net.boundaries:
        around += list(zm.inputs.mean_of.get(b, ()))
    supply = [s.temperature for s in net.supply_air if s.temperature not in net.boundaries]
    watts = [h.name for h in net.heat_inputs if h.unit == "W"]
    sun = [h.name for h in net.heat_inputs if h.unit != "W"]
    return [
        ("zone and surroundings (°C)", list(dict.fromkeys(around))),
        ("supply air (°C)", list(dict.fromkeys(supply))),
        ("flow (kg/s)", list(net.flow_names)),
        ("heat (W)", watts),
        ("irradiance (W/m²)", sun),
    ]


def diagnose_report(rep: IdentifiabilityReport, zm: ZoneModel, data_name: str) -> Report:
    """A full report for one diagnose run of model ``zm`` on the data called ``data_name``."""
    r = Report(f"Can {data_name} identify the {zm.label} model?")
    r.paragraph(
        "rczone checks whether the data carry enough information to pin down each parameter. It "
        "measures how far the zone moved from each surrounding temperature (a wall's resistance only "
        "shows when heat actually flows through it), computes how precisely a fit could determine each "
        "parameter from the exact sensitivities of every measured temperature, and tries a value ten "
        "times smaller and larger to see whether the data could tell the difference once the unknown "
        f"initial state and guessed heat gains are allowed for. Error level assumed: {rep.sigma_K:g} K; "
        f"model error allowed: {rep.settings.get('model_error_K', 0.0):g} K."
    )
    if rep.operating_point is not None:
        op = rep.operating_point
        r.paragraph(
            "Operating point: " + html.escape(op.reason) + ".",
            "note" if op.reproduces_data else "warn",
        )
    r.heading("Data")
    if rep.signals is not None:
        r.figure(
            "data_overview",
            figs.signals_overview(rep.signals, signal_panels(zm)),
            f"{data_name}: the model's signals over the samples analysed",
        )
    sur = [
        {
            "surrounding": s.name,
            f"max |{zm.network.outputs[0]} - Tj| (K)": s.max_abs_diff_K,
            f"median |{zm.network.outputs[0]} - Tj| (K)": s.median_abs_diff_K,
            f"correlation with {zm.network.outputs[0]}": s.correlation,
        }
        for s in rep.indicators.surroundings
    ]
    if sur:
        r.table(sur, "How far the zone moved from each surrounding temperature", digits=3)
    r.heading("Verdicts")
    add_verdicts(r, rep)
    return r
