"""The report of ``rczone control-test``: the scores and a figure of the run."""

from __future__ import annotations

import html

import numpy as np
from matplotlib.figure import Figure

from rczone.control.closedloop import ClosedLoopResult
from rczone.report.html import Report, literal


def closed_loop_figure(result: ClosedLoopResult) -> Figure:
    """Room temperature with the band (occupied hours shaded), flow, and cumulative energy."""
    s = result.series
    h = result.t / 3600.0
    fig = Figure(figsize=(9.0, 7.5))
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True)
    ax1.fill_between(h, s["lower"], s["upper"], color="#c6f6d5", step="post", label="band")
    occ = s["occupied"].astype(float)
    ax1.fill_between(h, 0, 1, where=occ > 0, transform=ax1.get_xaxis_transform(), color="0.9", zorder=0)
    ax1.plot(h, s["Ti"], color="black", lw=1.0, label="Ti (true)")
    ax1.set_ylabel("Ti (°C)")
    ax1.legend(fontsize=8, loc="best")
    ax2.step(h, s["m"], where="post", color="#2b6cb0", lw=1.0)
    ax2.set_ylabel("flow (kg/s)")
    ax2b = ax2.twinx()
    ax2b.step(h, s["Ts"], where="post", color="#dd6b20", lw=0.8)
    ax2b.set_ylabel("Ts (°C)", color="#dd6b20")
    ax3.plot(h, np.cumsum(s["power_W"]) * (h[1] - h[0]) / 1e3, color="#38a169")
    ax3.set_ylabel("energy (kWh)")
    ax3.set_xlabel("hours from the first 6 pm (grey: occupied)")
    for ax in (ax1, ax2, ax3):
        ax.grid(alpha=0.3)
    st = result.setup
    fig.suptitle(
        literal(
            f"{st['controller']} on the {st['scenario']} scenario (model {st['model']}, seed {st['seed']})"
        )
    )
    fig.tight_layout()
    return fig


def closed_loop_report(result: ClosedLoopResult) -> Report:
    """The scores as a table and :func:`closed_loop_figure`."""
    st, sc = result.setup, result.scores
    rep = Report(f"Closed-loop test: {st['controller']}, {st['scenario']}")
    rep.paragraph(
        "The plant is the full virtual building (152 states, neighbours under their thermostats,"
        " unmeasured daytime gains); energy is reheat + cooling-coil load + fan (SFP 1500 W per m3/s);"
        f" comfort counts K h outside the band in occupied hours. Model: {html.escape(str(st['model']))};"
        f" forecast: {html.escape(str(st.get('forecast')))}. Every controller is held to the zone's limits"
        " (ventilation minimum 0.05 kg/s occupied, 0.02 kg/s unoccupied; steps outside them:"
        f" {html.escape(str(sc.get('constraint_violations')))})."
    )
    rows = [{"score": k, "value": v} for k, v in sc.items() if k != "solve_time_s" and v is not None]
    if sc.get("solve_time_s"):
        rows += [{"score": f"QP time {k} (s)", "value": v} for k, v in sc["solve_time_s"].items()]
    rep.table(rows, "Scores of the run", digits=4)
    rep.figure(
        "closed_loop",
        closed_loop_figure(result),
        "Room temperature and band, flow and discharge temperature, energy",
    )
    return rep
