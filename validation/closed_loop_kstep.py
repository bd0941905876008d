"""Closed loop: the MPC with a k-step fit against the MPC with the ML fit of the same model (issue 36).

Usage::

    python validation/closed_loop_kstep.py [--seeds 31,32,33,34] [--seasons summer,winter] [--days 1]
                                           [--horizons 1,10,60,360] [--no-oracle] [--out validation-output]
                                           [--page docs/validation.md]

The paper's 2-state model (``second-order-paper``, free ``Cr`` and ``Rw``) is fitted on the
virtual building's forced night C, as the paper study fits its Q2 model
(:func:`rczone.control.study.fitted`: ML, one start from the construction values), once by maximum
likelihood and once by the k-step criterion from that same ML fit (``method="kstep"``,
:mod:`rczone.estimation.methods.kstep`). Night C is sampled every minute and the reference MPC
plans over 36 steps of 10 min, so the default horizons are 1 step (the filter's own step, keeps
the one-step fit), 10 steps (10 min, the MPC's interval: the prediction its applied move rests
on), 60 steps (1 h) and 360 steps (6 h, the MPC's whole horizon).

Both models then drive the reference MPC in one :func:`rczone.control.comparison.compare` per
season: the same seeds, plant, limits, forecasts and observer settings; the only difference is the
model (its R, C and noise levels, hence also its observer's gains). The k-step entry is paired
against the ML entry seed by seed; the oracle (the MPC with the 2-state model of the zone's true
construction, its true state, the perfect forecast and the true gains) runs beside them as the
limit. The two fits are also scored on the closed-loop night A (data neither fit saw): k-step RMSE
at 10 min, 1 h and 6 h, the first hour skipped.

Prints two Markdown tables and pastes them between the ``<!-- table:kstep-closed-loop -->`` and
``<!-- table:kstep-closed-loop-fits -->`` markers of ``--page`` (``kstep-closed-loop-tight`` with ``--band tight``, the occupied band
narrowed to 0.8 K as ``control-test --band tight``; with the command, the date and the
load) after the fits and again after each season, so that a run stopped early leaves what it
finished; writes ``<out>/closed_loop_kstep.json`` likewise. The fits take some 2 minutes of CPU,
each one-day MPC run some 10-40 s; the defaults make 48 runs.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from rczone import datasets
from rczone.calibration import calibrate
from rczone.calibration.dataset import prepare
from rczone.control.comparison import Comparison, Entry, Scenario, compare, verdict
from rczone.estimation.forecast import k_step_bands
from rczone.estimation.kstep import kstep_cost
from rczone.files.atomic import write_json_atomic, write_text_atomic
from rczone.models.zone import ZoneModel

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from control_doc import block, paste  # noqa: E402

PAGE = HERE.parent / "docs" / "validation.md"
MODEL = "second-order-paper"
#: Steps of night C (60 s): one step, the MPC's 10-min interval, 1 h, its 6-h horizon.
HORIZONS = (1, 10, 60, 360)
#: Seeds 31-34 are docs/control.md's (no test names them), 35-38 four more.
SEEDS = tuple(range(31, 39))
ML, KSTEP, ORACLE = "MPC, ML fit on C", "MPC, k-step fit on C", "oracle"
#: KPIs of the table (lower is better for each).
TABLE_KPIS = ("comfort_Kh", "energy_kWh", "peak_flow_kg_s")
#: Steps ahead (of night A, sampled every A_DT s) the fits are scored at.
SCORE_STEPS, A_DT = (10, 60, 360), 60.0


def fits(horizons: tuple[int, ...]) -> dict[str, ZoneModel]:
    """The ML and the k-step fit of :data:`MODEL` on night C, with the same settings otherwise."""
    c = datasets.load("C")
    out = {}
    for label, method, options in ((ML, "ml", None), (KSTEP, "kstep", {"horizons": horizons})):
        t0 = time.process_time()
        out[label] = calibrate(
            MODEL, c, method=method, options=options, n_starts=1, uncertainty=False, analyses=False
        ).model
        print(f"{label}: {time.process_time() - t0:.0f} s CPU", flush=True)
    return out


def held_out_rmse(zm: ZoneModel, night: str = "A", steps: tuple[int, ...] = SCORE_STEPS) -> dict[int, float]:
    """RMSE (K) of the model's k-step predictions on ``night``, the first hour of targets skipped."""
    data = prepare(zm, datasets.load(night)).dataset
    if not np.allclose(np.diff(data.t), A_DT):
        raise ValueError(f"night {night} is not sampled every {A_DT:g} s")
    bands = k_step_bands(zm.network, {**zm.theta, **zm.noise}, data, steps)
    skip = int(np.searchsorted(data.t, data.t[0] + 3600.0))
    out = {}
    for k in steps:
        e = (data.y - bands[k].y_hat)[max(skip, k) :, 0]
        out[k] = float(np.sqrt(np.nanmean(e**2)))
    return out


def criterion(zm: ZoneModel, horizons: tuple[int, ...], night: str = "C") -> float:
    """The k-step criterion (K^2) of the model's values on ``night`` at ``horizons``."""
    data = prepare(zm, datasets.load(night)).dataset
    values = {**zm.theta, **zm.noise, **zm.provenance.get("initial_state", {})}
    return float(kstep_cost(zm.network, values, data, horizons).value)


def paired(cmp: Comparison, kpi: str, label: str = KSTEP, against: str = ML) -> dict[str, float]:
    """Mean, standard error and verdict of ``label - against`` for ``kpi``, seed by seed."""
    d = cmp.scores[label][kpi] - cmp.scores[against][kpi]
    se = float(d.std(ddof=1)) / math.sqrt(d.size) if d.size > 1 else math.nan
    ref = float(cmp.scores[against][kpi].mean())
    return {"mean": float(d.mean()), "se": se, "verdict": verdict(d, ref), "per_seed": d.tolist()}


def kpi_table(results: dict[str, Comparison]) -> str:
    """Markdown: per season and KPI, both MPCs' means, the paired difference, the oracle."""
    oracle = any(ORACLE in c.labels for c in results.values())
    lines = [
        "| season | KPI | MPC, ML fit | MPC, k-step fit | k-step − ML (mean ± s.e.) | verdict"
        + (" | oracle |" if oracle else " |"),
        "|---|---|---|---|---|---|" + ("---|" if oracle else ""),
    ]
    for season, cmp in results.items():
        for kpi in TABLE_KPIS:
            p = paired(cmp, kpi)
            cells = [
                season,
                kpi,
                f"{cmp.scores[ML][kpi].mean():.3g}",
                f"{cmp.scores[KSTEP][kpi].mean():.3g}",
                f"{p['mean']:+.2g} ± {p['se']:.2g}",
                p["verdict"],
            ]
            if oracle:
                cells.append(f"{cmp.scores[ORACLE][kpi].mean():.3g}" if ORACLE in cmp.labels else "-")
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def fits_table(models: dict[str, ZoneModel], rmse: dict, crit: dict[str, float]) -> str:
    """Markdown: the two fits' estimates, noise levels, k-step criterion on C and k-step RMSE on night A."""
    names = sorted({k for zm in models.values() for k in zm.theta if k in ("Cr", "Rw")})
    noise = sorted({k for zm in models.values() for k, v in zm.noise.items() if v > 0 and "x0" not in k})
    steps = sorted({k for r in rmse.values() for k in r})
    head = (
        names
        + noise
        + ["k-step criterion on C (K²)"]
        + [f"RMSE {k * A_DT / 60:g} min on A (K)" for k in steps]
    )
    lines = ["| fit | " + " | ".join(head) + " |", "|---|" + "---|" * len(head)]
    for label, zm in models.items():
        cells = [f"{zm.theta[n]:.4g}" for n in names] + [f"{zm.noise.get(n, math.nan):.3g}" for n in noise]
        cells += [f"{crit[label]:.4g}"] + [f"{rmse[label][k]:.3f}" for k in steps]
        lines.append(f"| {label.removeprefix('MPC, ')} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def stamp(argv: list[str], cpu_s: float) -> str:
    """The command, the date and the load, for the page."""
    load = os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3
    cmd = " ".join(["python validation/closed_loop_kstep.py", *argv])
    day = datetime.now(UTC).strftime("%Y-%m-%d")
    return f"`{cmd}` (run {day}; {cpu_s / 60:.0f} min of CPU, load averages {load[0]:.1f} / {load[2]:.1f} (1 / 15 min) on {os.cpu_count()} cores at the end)"


def run(seeds, seasons, days: float, horizons, oracle: bool, save, band: str = "normal") -> dict:
    """The fits, their criterion and held-out RMSE, and one comparison per season.

    ``save`` is called with what is done so far after the fits and after every season.
    """
    models = fits(horizons)
    rmse = {label: held_out_rmse(zm) for label, zm in models.items()}
    crit = {label: criterion(zm, horizons) for label, zm in models.items()}
    out = {"models": models, "rmse": rmse, "criterion": crit, "results": {}}
    save(out)
    entries = [Entry(ML, "mpc", models[ML]), Entry(KSTEP, "mpc", models[KSTEP])]
    entries += [Entry(ORACLE, "oracle")] if oracle else []
    for season in seasons:
        t0 = time.process_time()
        out["results"][season] = cmp = compare(
            entries, seeds, scenario=Scenario(season, days=days, comfort_band=band)
        )
        print(f"{season}: {time.process_time() - t0:.0f} s CPU\n{cmp.summary()}", flush=True)
        save(out)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default=",".join(map(str, SEEDS)))
    ap.add_argument("--seasons", default="summer,winter")
    ap.add_argument("--band", choices=("normal", "tight"), default="normal", help="tight: 0.8 K occupied")
    ap.add_argument("--days", type=float, default=1.0)
    ap.add_argument("--horizons", default=",".join(map(str, HORIZONS)))
    ap.add_argument("--no-oracle", action="store_true", help="leave the oracle out")
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--page", type=Path, default=PAGE, help="the page to paste into; 'none': no page")
    a = ap.parse_args(argv)
    seeds = [int(s) for s in a.seeds.split(",")]
    horizons = tuple(int(h) for h in a.horizons.split(","))
    t0 = time.process_time()
    table_name = "kstep-closed-loop" + ("-tight" if a.band == "tight" else "")

    def save(out: dict) -> None:
        models, rmse, crit, results = out["models"], out["rmse"], out["criterion"], out["results"]
        tables = {
            table_name: f"{stamp(argv, time.process_time() - t0)}\n\n{kpi_table(results)}",
            "kstep-closed-loop-fits": fits_table(models, rmse, crit),
        }
        for name, text in tables.items():
            print(f"\n{block(name, text)}", flush=True)
        write_json_atomic(
            a.out / "closed_loop_kstep.json",
            {
                "horizons": list(horizons),
                "fits": {lab: {"theta": dict(zm.theta), "noise": dict(zm.noise), "criterion_C_K2": crit[lab], "rmse_A_K": rmse[lab]} for lab, zm in models.items()},
                "paired": {s: {k: paired(c, k) for k in TABLE_KPIS} for s, c in results.items()},
                "comparisons": {s: c.to_dict() for s, c in results.items()},
            },
        )  # fmt: skip
        if str(a.page) != "none":  # the page's comfort table stays until a season is done
            keep = {} if results else {table_name}
            new = {k: v for k, v in tables.items() if k not in keep}
            write_text_atomic(a.page, paste(a.page.read_text(), new))

    run(seeds, a.seasons.split(","), a.days, horizons, not a.no_oracle, save, a.band)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
