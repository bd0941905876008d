"""The summary of a batch: what was done, what failed, how the estimates are distributed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rczone.files.atomic import write_json_in
from rczone.network.stochastic import is_reserved
from rczone.report import Report
from rczone.report.html import ReportFigure as Figure

VERDICTS = ("identifiable", "weak", "not identifiable")


def parameter_names(df: pd.DataFrame) -> list[str]:
    """Estimated parameters: columns with a matching ``_se`` column."""
    return [c for c in df.columns if f"{c}_se" in df.columns]


def summarize(df: pd.DataFrame) -> dict:
    """Counts, failures, estimate quantiles per method and verdict counts, JSON-ready."""
    ok = df[df["status"] == "ok"] if len(df) else df
    out: dict = {
        "tasks": len(df),
        "zones": int(df["zone"].nunique()) if len(df) else 0,
        "ok": int((df["status"] == "ok").sum()) if len(df) else 0,
        "failed": int((df["status"] != "ok").sum()) if len(df) else 0,
        # finished, but flagged (an estimate at a bound, no standard error, starts that disagree)
        "flagged": int((ok["trustworthy"] == False).sum()) if "trustworthy" in ok else 0,  # noqa: E712
        "failures": [
            {"zone": r.zone, "method": r.method, "error": r.error}
            for r in df[df["status"] != "ok"].itertuples()
        ]
        if len(df)
        else [],
        "estimates": {},
        "verdicts": {},
    }
    for method, g in ok.groupby("method") if len(ok) else []:
        est = {}
        for p in parameter_names(g):
            v = g[p].dropna().to_numpy(float)
            if v.size:
                q = np.quantile(v, [0.05, 0.25, 0.5, 0.75, 0.95])
                at_b = g.get(f"{p}_at_bound")
                est[p] = {
                    "n": int(v.size),
                    "q05": q[0],
                    "q25": q[1],
                    "median": q[2],
                    "q75": q[3],
                    "q95": q[4],
                    "at_bound": int(at_b.fillna(False).astype(bool).sum()) if at_b is not None else 0,
                }
        out["estimates"][method] = est
    for c in [c for c in df.columns if c.endswith("_verdict")]:
        counts = ok.drop_duplicates("zone")[c].value_counts()
        out["verdicts"][c.removesuffix("_verdict")] = {v: int(counts.get(v, 0)) for v in VERDICTS}
    return out


def _histograms(df: pd.DataFrame, params: list[str]) -> Figure:
    fig = Figure(figsize=(4.0 * max(1, len(params)), 3.2), layout="constrained")
    axes = fig.subplots(1, max(1, len(params)), squeeze=False)[0]
    ok = df[df["status"] == "ok"]
    for ax, p in zip(axes, params):
        vals = ok[p].dropna()
        vals = vals[vals > 0]
        if vals.empty:
            continue
        bins = np.logspace(np.log10(vals.min()) - 0.05, np.log10(vals.max()) + 0.05, 30)
        for method, g in ok.groupby("method"):
            v = g[p].dropna()
            ax.hist(v[v > 0], bins=bins, alpha=0.55, label=method.upper())
        cons = ok.get(f"{p}_construction")
        if cons is not None and cons.notna().any():
            ax.axvline(float(cons.dropna().iloc[0]), color="k", ls="--", lw=1, label="construction")
        ax.set_xscale("log")
        ax.set_xlabel(p)
        ax.set_ylabel("zones")
        ax.legend(fontsize=8)
    return fig


def write_summary(df: pd.DataFrame, folder: str | Path, title: str = "rczone batch") -> dict:
    """Write ``summary.json`` and ``report.html`` (+ PNG) into ``folder``; return the summary."""
    folder = Path(folder)
    s = summarize(df)
    write_json_in(folder, "summary.json", s)
    rep = Report(f"{title}: {s['tasks']} calibrations of {s['zones']} zones")
    rep.paragraph(f"{s['ok']} succeeded, {s['failed']} failed.", "warn" if s["failed"] else "")
    params = [p for p in parameter_names(df) if not is_reserved(p)]
    if params and s["ok"]:
        rep.heading("Distribution of the estimates")
        rep.figure("estimates", _histograms(df, params), "Estimates across zones (log scale), per method")
        rows = []
        for method, est in s["estimates"].items():
            for p, q in est.items():
                if p in params:
                    rows.append(
                        {
                            "method": method.upper(),
                            "parameter": p,
                            "zones": q["n"],
                            "5%": q["q05"],
                            "median": q["median"],
                            "95%": q["q95"],
                            "at bound": q["at_bound"],
                        }
                    )
        rep.table(rows, "Quantiles of the estimates", digits=3)
    if s["verdicts"]:
        rep.heading("Can the data identify the parameters?")
        rep.table(
            [{"parameter": p, **c} for p, c in s["verdicts"].items()],
            "Identifiability verdicts across zones (rczone diagnose, before fitting)",
        )
    if s["failures"]:
        rep.heading("Failures")
        rep.table(
            s["failures"][:200],
            f"Failed calibrations ({s['failed']}; first 200 shown)",
        )
    rep.write(folder)
    return s
