"""Paired comparisons of controllers (and models) over seeds: differences, their spread, a verdict.

One closed-loop run answers little: weather, thermostat settings, AHU drift and sensor noise
differ from seed to seed, and so do the scores. :func:`compare` runs every entry (a controller,
with a model where it needs one) on the same seeds, so that each seed gives a *paired*
difference of every KPI against the first entry (the reference); the differences' mean, standard
deviation and a verdict per KPI summarize them. The runs of one seed are checked to be
comparable (:func:`~rczone.control.closedloop.check_comparable`: the same test and the same
limits).

**Verdict.** For a KPI where lower is better (all of :data:`KPIS`), an entry is ``better`` or
``worse`` than the reference when the mean paired difference is more than two standard errors
(``2 sd / sqrt(n)``) from zero and more than :data:`NEGLIGIBLE` of the reference's mean, and
``no difference`` otherwise; with one seed there is no spread and the verdict is ``one seed``.
Two standard errors is the usual approximate 95 % bound of a paired comparison (a paired
t-test with few seeds is wider; Montgomery [1]_, section 2.5.3, the paired comparison design).

References
----------
.. [1] D. C. Montgomery, *Design and Analysis of Experiments*, 8th ed., Wiley, 2013.
"""

from __future__ import annotations

import html
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rczone.control.closedloop import ClosedLoopResult, check_comparable, closed_loop_test
from rczone.control.mpc import MPCSettings
from rczone.control.virtualplant import VirtualPlant
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel

#: The KPIs compared (lower is better for each).
KPIS = ("comfort_Kh", "energy_kWh", "cost", "peak_flow_kg_s")
#: A difference smaller than this share of the reference's mean is no difference.
NEGLIGIBLE = 0.01


@dataclass(frozen=True)
class Entry:
    """One compared variant: a label, a controller name and the model it uses (if any).

    Parameters
    ----------
    label : str
    controller : str
        A name of :mod:`rczone.control.registry`.
    model : ZoneModel, optional
    disturbance : bool
        For an MPC: its observer estimates an unmeasured heat input.
    reference : str, optional
        The label of the entry this one is paired against (default the first entry).
    """

    label: str
    controller: str
    model: ZoneModel | None = None
    disturbance: bool = True
    reference: str | None = None


@dataclass(frozen=True)
class Scenario:
    """The closed-loop test every entry runs (the :class:`VirtualPlant`'s settings but the seed)."""

    season: str = "summer"
    days: float = 1.0
    price: str = "flat"
    comfort_band: str = "normal"
    forecast: str = "measured"

    def plant(self, seed: int) -> VirtualPlant:
        """The plant of this test for ``seed``."""
        return VirtualPlant(
            self.season,
            days=self.days,
            seed=seed,
            price=self.price,
            comfort_band=self.comfort_band,
            forecast=self.forecast,
        )


@dataclass(frozen=True, eq=False)
class Comparison:
    """Runs of several entries on the same seeds, and their paired differences (see the module notes).

    Attributes
    ----------
    labels : tuple of str
        The entries, the reference first.
    seeds : tuple of int
    scores : mapping of str to mapping of str to ndarray
        ``scores[label][kpi]``, one value per seed.
    setup : mapping
        The test's settings, and under ``constraints`` the limits of each seed (the schedule is
        seeded; every entry of a seed ran under the same).
    references : mapping of str to str
        Entry label -> the label it is paired against (entries not named: the first).
    """

    labels: tuple[str, ...]
    seeds: tuple[int, ...]
    scores: Mapping[str, Mapping[str, np.ndarray]]
    setup: Mapping[str, Any]
    references: Mapping[str, str] = field(default_factory=dict)

    def reference(self, label: str) -> str:
        """The label ``label`` is paired against."""
        return self.references.get(label, self.labels[0])

    def rows(self) -> list[dict[str, Any]]:
        """One row per entry and KPI: mean, paired difference to its reference (mean, sd), verdict."""
        out = []
        for label in self.labels:
            ref = self.reference(label)
            for k in KPIS:
                v = self.scores[label][k]
                d = v - self.scores[ref][k]
                out.append(
                    {
                        "entry": label,
                        "against": None if label == ref else ref,
                        "kpi": k,
                        "mean": float(v.mean()),
                        "diff_mean": float(d.mean()),
                        "diff_sd": float(d.std(ddof=1)) if d.size > 1 else None,
                        "verdict": "reference"
                        if label == ref
                        else verdict(d, float(self.scores[ref][k].mean())),
                    }
                )
        return out

    def markdown(self) -> str:
        """The table of :meth:`rows` in Markdown, one row per entry, one column per KPI."""
        head = "| entry | against | " + " | ".join(KPIS) + " |"
        lines = [head, "|" + " --- |" * (len(KPIS) + 2)]
        rows = self.rows()
        for label in self.labels:
            cells = []
            for r in (r for r in rows if r["entry"] == label):
                if r["verdict"] == "reference":
                    cells.append(f"{r['mean']:.3g}")
                else:
                    sd = "" if r["diff_sd"] is None else f" ± {r['diff_sd']:.2g}"
                    cells.append(f"{r['mean']:.3g} ({r['diff_mean']:+.2g}{sd}, {r['verdict']})")
            against = self.reference(label) if self.reference(label) != label else ""
            lines.append(f"| {label} | {against} | " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """:meth:`rows` as a table."""
        return pd.DataFrame(self.rows())

    def to_dict(self) -> dict[str, Any]:
        """The runs' scores, the rows and the setup (what ``--json`` writes)."""
        return {
            "seeds": list(self.seeds),
            "scores": {lab: {k: v.tolist() for k, v in s.items()} for lab, s in self.scores.items()},
            "rows": self.rows(),
            "references": {lab: self.reference(lab) for lab in self.labels},
            "setup": dict(self.setup),
        }

    def summary(self) -> str:
        """The table of paired differences against the reference (what the CLI prints)."""
        st = self.setup
        lines = [
            f"paired comparison on the {st['scenario']} scenario, {st['days']} day(s), seeds "
            f"{', '.join(map(str, self.seeds))}, price {st['price']}, band {st['band']}, "
            f"{st['forecast']} forecast; reference: {self.labels[0]}"
            + "".join(
                f"; {lab} against {ref}" for lab, ref in self.references.items() if ref != self.labels[0]
            ),
            f"  {'entry':28s} {'KPI':15s} {'mean':>9s} {'diff':>9s} {'sd':>8s}  verdict",
        ]
        for r in self.rows():
            sd = "" if r["diff_sd"] is None else f"{r['diff_sd']:8.3f}"
            lines.append(
                f"  {r['entry'][:28]:28s} {r['kpi']:15s} {r['mean']:9.3f} {r['diff_mean']:+9.3f} {sd:>8s}  {r['verdict']}"
            )
        return "\n".join(lines)


def verdict(diff: np.ndarray, reference_mean: float) -> str:
    """``better``, ``worse``, ``no difference`` or ``one seed`` for paired differences ``diff`` (lower is better)."""
    if diff.size < 2:
        return "one seed"
    mean, se = float(diff.mean()), float(diff.std(ddof=1)) / math.sqrt(diff.size)
    if abs(mean) <= 2 * se or abs(mean) <= NEGLIGIBLE * abs(reference_mean):
        return "no difference"
    return "better" if mean < 0 else "worse"


def compare(
    entries: Sequence[Entry],
    seeds: Sequence[int],
    *,
    scenario: Scenario | None = None,
    settings: MPCSettings | None = None,
    progress: Any = None,
) -> Comparison:
    """Run every entry on every seed of ``test``, and pair the runs by seed.

    Parameters
    ----------
    entries : sequence of Entry
        The first is the reference; labels must differ.
    seeds : sequence of int
    scenario : Scenario, optional
    settings : MPCSettings, optional
        For the entries that are MPCs.
    progress : callable, optional
        Called with ``"<label>, seed <s>"`` before each run, and told its simulated hours
        (``progress.advance``, :func:`rczone.control.closedloop.closed_loop_test`); None: nothing.

    Returns
    -------
    Comparison
    """
    scenario = scenario or Scenario()
    labels = [e.label for e in entries]
    if len(entries) < 2 or len(set(labels)) != len(labels):
        raise ParameterError(f"a comparison needs two or more entries with distinct labels, got {labels}")
    for e in entries:
        if e.reference is not None and e.reference not in labels:
            raise ParameterError(
                f"entry {e.label!r} is paired against {e.reference!r}, which is not an entry"
            )
    if not seeds or len(set(seeds)) != len(seeds):
        raise ParameterError(f"a comparison needs distinct seeds, got {list(seeds)}")
    scores: dict[str, dict[str, list[float]]] = {lab: {k: [] for k in KPIS} for lab in labels}
    setup: Mapping[str, Any] = {}
    limits: dict[int, Any] = {}
    for seed in seeds:
        runs: list[ClosedLoopResult] = []
        for e in entries:
            if progress is not None:
                progress(f"{e.label}, seed {seed}")
            r = closed_loop_test(
                scenario.plant(seed),
                e.controller,
                model=e.model,
                settings=settings,
                disturbance=e.disturbance,
                progress=progress,
            )
            if runs:
                check_comparable(runs[0], r)
            runs.append(r)
            for k in KPIS:
                scores[e.label][k].append(float(r.scores[k]))
        setup = {
            k: v for k, v in runs[0].setup.items() if k not in ("controller", "model", "seed", "constraints")
        }
        limits[seed] = runs[0].setup["constraints"]
    setup = {**setup, "disturbance_estimate": None, "constraints": limits}
    arrays = {lab: {k: np.array(v) for k, v in s.items()} for lab, s in scores.items()}
    refs = {e.label: e.reference for e in entries if e.reference is not None}
    return Comparison(tuple(labels), tuple(int(s) for s in seeds), arrays, setup, refs)


def compare_entries(
    text: str, model: ZoneModel, load: Callable[[str], ZoneModel], *, disturbance: bool = True
) -> list[Entry]:
    """Entries from ``"CONTROLLER[:MODEL],..."`` (``--compare``); ``model`` for entries without one.

    ``load`` turns a model specification into a model (the CLI's reader of names and files).
    """
    entries = []
    for item in (x.strip() for x in text.split(",")):
        if not item:
            raise ParameterError(f"--compare has an empty entry in {text!r}; give CONTROLLER[:MODEL],...")
        name, _, spec = item.partition(":")
        entries.append(Entry(item, name, load(spec) if spec else model, disturbance))
    return entries


def comparison_report(cmp: Comparison, folder: str | os.PathLike) -> Path:
    """Write ``report.html`` into ``folder``: the setup, the paired table and the verdicts (escaped)."""
    from rczone.files.atomic import ensure_folder, write_text_atomic

    st = cmp.setup
    title = f"Paired closed-loop comparison: {st['scenario']}, seeds {', '.join(map(str, cmp.seeds))}"
    table = cmp.to_frame().to_html(index=False, escape=True, float_format=lambda v: f"{v:.4g}", na_rep="")
    body = (
        f"<h1>{html.escape(title)}</h1>\n<pre>{html.escape(cmp.summary())}</pre>\n{table}\n"
        "<p>Each entry's paired difference is to the entry in its <i>against</i> column (seed by seed);"
        " the verdict needs the mean difference beyond two standard errors and 1 % of the reference."
        " Every run of a seed was held to the same limits (recorded in the JSON).</p>"
    )
    page = f"<!doctype html>\n<html><head><meta charset='utf-8'><title>{html.escape(title)}</title></head>\n<body>{body}</body></html>\n"
    return write_text_atomic(ensure_folder(folder) / "report.html", page)
