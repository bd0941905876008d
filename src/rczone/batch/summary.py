"""The summary of a batch: what was done, what failed, how the estimates are distributed.

:class:`BatchRun` is the result of :func:`rczone.batch.run_batch` and follows the result protocol
(:mod:`rczone.results.protocol`): ``summary()`` is what ``rczone fit-many`` prints, ``to_dict()``
holds the run's figures and the contents of ``summary.json``, ``to_frame()`` is the results table.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from rczone.files.atomic import write_json_in
from rczone.network.stochastic import is_reserved
from rczone.results.protocol import Result, json_number

if TYPE_CHECKING:  # matplotlib loads only where a report is written, not in every worker process
    from matplotlib.figure import Figure

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
        "drifted": _drifted(ok),
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


def _drifted(ok: pd.DataFrame) -> list[dict]:
    """The calibrations whose own record shows drift (:func:`rczone.calibration.drift.record_drift`)."""
    if "drift" not in ok or not len(ok):
        return []
    hit = ok[ok["drift"].map(lambda v: v is True or v == 1.0)]  # None/NaN: not tested
    return [
        {"zone": r.zone, "method": r.method, "since_s": json_number(r.drift_since_s), "tests": r.drift_tests}
        for r in hit.itertuples()
    ]


def _histograms(df: pd.DataFrame, params: list[str]) -> Figure:
    from matplotlib.figure import Figure

    from rczone.report.html import literal

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
            ax.hist(v[v > 0], bins=bins, alpha=0.55, label=literal(method.upper()))
        cons = ok.get(f"{p}_construction")
        if cons is not None and cons.notna().any():
            ax.axvline(float(cons.dropna().iloc[0]), color="k", ls="--", lw=1, label="construction")
        ax.set_xscale("log")
        ax.set_xlabel(literal(p))
        ax.set_ylabel("zones")
        ax.legend(fontsize=8)
    return fig


def write_summary(df: pd.DataFrame, folder: str | Path, title: str = "rczone batch") -> dict:
    """Write ``summary.json`` and ``report.html`` (+ PNG) into ``folder``; return the summary."""
    from rczone.report import Report

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
    if s["drifted"]:
        rep.heading("Drift")
        rep.table(
            [
                {**d, "since (h)": d["since_s"] / 3600 if d["since_s"] is not None else None}
                for d in s["drifted"]
            ],
            "Zones whose errors left the range of their record's first half (CUSUM on the innovations)",
            digits=3,
        )
    if s["failures"]:
        rep.heading("Failures")
        rep.table(
            s["failures"][:200],
            f"Failed calibrations ({s['failed']}; first 200 shown)",
        )
    rep.write(folder)
    return s


#: Failures listed by :meth:`BatchRun.summary` (all are in ``summary.json``).
SHOWN_FAILURES = 10


@dataclass(frozen=True, repr=False)
class BatchRun(Result):
    """What one run of a batch did, and the batch's results so far.

    Attributes
    ----------
    total : int
        Calibrations (tasks) in the manifest.
    skipped : int
        Already done by an earlier run (resumed).
    computed : int
        Finished in this run (ok or failed with the zone's own error), and stored.
    failed : int
        Of the computed, how many failed.
    lost : int
        Could not be run (worker died, scheduler lost, no workers): not stored, and computed
        by the next run.
    lost_reasons : tuple of str
        Why, one entry per distinct reason.
    seconds : float
        Wall time of this run, s.
    results : Path
        The consolidated table (``results.parquet``).
    folder : Path
        The results folder.
    totals : dict
        The summary of every stored result of the manifest (:func:`summarize`; ``summary.json``).
    table : DataFrame
        The rows of ``results.parquet``.
    workers : int
        Worker processes the run asked for (local) or found (a cluster).
    compute_seconds : float
        Sum over the calibrations computed in this run of their own time in the workers, s.
    cpu_seconds : float
        The same in processor time, s: what the calibrations cost where other processes share
        the cores.
    submitted : int
        Units of work sent to the workers (a unit holds one or more zones).
    """

    total: int
    skipped: int
    computed: int
    failed: int
    lost: int
    lost_reasons: tuple[str, ...]
    seconds: float
    results: Path
    folder: Path
    totals: dict = field(default_factory=dict)
    table: pd.DataFrame = field(default_factory=pd.DataFrame)
    workers: int = 1
    compute_seconds: float = 0.0
    cpu_seconds: float = 0.0
    submitted: int = 0

    @property
    def overhead(self) -> float:
        """Share of the workers' time not spent calibrating: ``1 - compute / (wall x workers)``.

        Cluster start, scheduling, transfers and idle workers at the end; NaN when nothing ran.
        """
        capacity = self.seconds * self.workers
        return 1.0 - self.compute_seconds / capacity if self.computed and capacity > 0 else float("nan")

    def summary_lines(self, *, lost: bool = True) -> list:
        """What ``rczone fit-many`` prints (with ``lost=False``: its standard output only).

        Parameters
        ----------
        lost : bool
            Include :meth:`lost_lines` (the command prints them on its error stream).

        Returns
        -------
        list of str
            Lines with rich markup.
        """
        from rich.markup import escape

        s = self.totals
        lines = [
            f"{self.computed} computed ({self.failed} failed), {self.skipped} resumed, in {self.seconds:.1f} s;"
            f" {s.get('ok', 0)}/{self.total} ok in total"
        ]
        lines += [
            f"[red]failed[/] {escape(f['zone'])} ({escape(f['method'])}): {escape(f['error'])}"
            for f in s.get("failures", [])[:SHOWN_FAILURES]
        ]
        if s.get("failed", 0) > SHOWN_FAILURES:
            lines.append(
                f"... and {s['failed'] - SHOWN_FAILURES} more (see {escape(str(self.folder / 'summary.json'))})"
            )
        lines.append(
            f"results: {escape(str(self.results))}; report: {escape(str(self.folder / 'report.html'))}"
        )
        if s.get("flagged", 0) and not self.lost and not s.get("failed", 0):
            lines.append(
                f"[yellow]{s['flagged']} calibration(s) finished but are flagged untrustworthy[/]"
                " (column 'flags' of the results: an estimate at a bound, no standard error, or starts that"
                " disagree)"
            )
        if s.get("drifted"):
            zones = ", ".join(escape(d["zone"]) for d in s["drifted"][:SHOWN_FAILURES])
            more = len(s["drifted"]) - SHOWN_FAILURES
            lines.append(
                f"[yellow]{len(s['drifted'])} calibration(s) show drift[/] ({zones}{f' and {more} more' if more > 0 else ''}):"
                " the errors of the record's second half left the range of its first (columns 'drift', 'drift_since_s')"
            )
        return lines + (self.lost_lines() if lost else [])

    def lost_lines(self) -> list[str]:
        """The note on calibrations that could not run (none when every one ran)."""
        from rich.markup import escape

        if not self.lost:
            return []
        return [
            f"[yellow]{self.lost} calibration(s) could not run[/] ({escape('; '.join(self.lost_reasons[:3]))});"
            " nothing was stored for them: rerun the same command to compute them"
        ]

    def to_dict(self) -> dict:
        """The run's figures (``run``) and the contents of ``summary.json``."""
        run = {
            "total": self.total,
            "skipped": self.skipped,
            "computed": self.computed,
            "failed": self.failed,
            "lost": self.lost,
            "lost_reasons": list(self.lost_reasons),
            "seconds": self.seconds,
            "workers": self.workers,
            "compute_seconds": self.compute_seconds,
            "cpu_seconds": self.cpu_seconds,
            "submitted": self.submitted,
            "overhead": json_number(self.overhead),
        }
        return {"run": run, **self.totals}

    def to_frame(self) -> pd.DataFrame:
        """The results table, one row per calibration (as ``results.parquet``)."""
        return self.table

    def _repr_line(self) -> str:
        return f"{self.computed} computed, {self.skipped} resumed, {self.lost} lost of {self.total}"
