"""The EnergyPlus closed loop with the k-step fit against the ML fit of the same model (issue 36).

Usage::

    python validation/energyplus_kstep.py [--out validation-output] [--seasons winter,summer]
        [--seeds 3] [--days 2] [--margins 0.1] [--horizons 1,4,48] [--no-baseline]

The set-up of ``validation/energyplus_closed_loop.py`` (medium office, ``Perimeter_mid_ZN_1``, the
paper's second-order model, a 3-day forced test, then 2 days under a time-of-use price with
BOPTEST's medium forecast error), with the same forced-test trend fitted twice: by maximum
likelihood (that script's fit, reused) and by the k-step criterion (``rczone fit --method kstep``,
which starts from the ML fit of the same settings). The trend and the plant step are 15 minutes
and the supervisory MPC plans every step over 48 steps, so the default horizons are 1 step (the
filter's step and the MPC's, keeps the one-step fit), 4 steps (1 h) and 48 steps (12 h, the MPC's
whole horizon).

Both models drive ``rczone control-test --emulator energyplus --controller mpc`` over seeds 0, 1,
... with the same seed (sensor noise and forecast error) and margin: the runs differ only in the
model. Per season and margin the k-step run is paired with the ML run of the same seed; the table (:func:`table`)
gives the mean of each, the paired difference k-step − ML (mean ± standard error) and the verdict of
:func:`rczone.control.comparison.verdict` (a difference beyond two standard errors and 1 % of the ML
mean, as docs/control.md defines it), with the building's own control (``baseline``, one run: it
reads neither rczone's sensors nor its forecasts) beside. Every run is appended to
``<out>/energyplus_kstep.json`` as it finishes, with its wall and CPU time and the load, beside the
two fits' estimates and errors (:func:`fit_summary`) and their k-step criterion on the trend
(:func:`criterion`); the tables are written to
``<out>/energyplus_kstep.md``. The runs of docs/energyplus.md are
``validation/energyplus_kstep.json``; a test keeps the page's table equal to :func:`table` of them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from rczone.calibration.dataset import prepare
from rczone.cli.main import main as rczone
from rczone.control.comparison import verdict
from rczone.estimation.kstep import kstep_cost
from rczone.models.zone import ZoneModel
from rczone.workflow.datasource import data_source

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import energyplus_closed_loop as ecl  # noqa: E402

#: Steps of the 15-minute trend: the filter's and the MPC's step, 1 h, the MPC's 12-h horizon.
HORIZONS = (1, 4, 48)
ML, KSTEP = "ml", "kstep"
#: (row key, label, per zone-day): the KPIs of the table, lower is better for each.
KPIS = (("cost", "HVAC cost", False), ("comfort_Kh", "comfort K h per zone-day", True))
KPIS += (("energy_kWh", "HVAC kWh", False), ("prediction_rmse_K", "1-step RMSE K", False))
KPIS += (("prediction_1h_rmse_K", "1-h RMSE K", False), ("open_loop_rmse_K", "open-loop RMSE K", False))
#: Prediction errors of the run's model, kept beside the KPIs of ``energyplus_closed_loop._run``.
PREDICTION = ("prediction_1h_rmse_K", "open_loop_rmse_K")


def _cpu() -> float:
    """CPU seconds of this process and its finished children (EnergyPlus may run as one)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def kstep_model(out: Path, season: str, horizons: tuple[int, ...]) -> Path:
    """The k-step fit of the season's forced-test trend (the trend and the ML fit made first, reused)."""
    ecl._model(out, season)
    model = out / f"zone_{season}_kstep.json"
    if model.exists():
        return model
    folder = out / f"forced_{season}"
    args = ["fit", str(folder / "trend.csv"), "--columns", str(folder / f"{ecl.ZONE}.columns.toml")]
    args += [
        "--model",
        "second-order",
        "--method",
        "kstep",
        "--option",
        "horizons=" + ",".join(map(str, horizons)),
    ]
    args += ["--starts", "1", "--no-profiles", "--save-model", str(model)]
    if rczone([*args, "--json", str(out / f"fit_{season}_kstep.json")]) not in (0, 3):
        raise SystemExit(f"the k-step fit of {season} failed")
    return model


def run(
    out: Path,
    season: str,
    fit: str | None,
    seed: int,
    days: int,
    model: Path,
    margin: float,
    *,
    weather: str = ecl.WEATHER,
) -> dict:
    """One closed-loop run (``fit`` None: the baseline) with its wall and CPU time and the load."""
    folder = out / f"kstep_runs_{fit or 'baseline'}"
    folder.mkdir(parents=True, exist_ok=True)
    wall, cpu = time.perf_counter(), _cpu()
    controller = "baseline" if fit is None else "mpc"
    row = ecl._run(folder, season, controller, seed, days, model, margin, weather=weather)
    row["fit"] = fit
    row |= {**_prediction(out, row), "wall_s": time.perf_counter() - wall, "cpu_s": _cpu() - cpu}
    return row | {"load_1min": os.getloadavg()[0], "date": datetime.now(UTC).strftime("%Y-%m-%d")}


def fit_summary(path: Path) -> dict:
    """The estimates, one-step and open-loop RMSE on the trend, criterion and exit code of ``rczone fit --json``."""
    d = json.loads(path.read_text())
    est = {k: v["estimate"] for k, v in d["parameters"].items() if not k.startswith("sigma")}
    at_bound = sorted(k for k, v in d["parameters"].items() if v.get("at_bound"))
    keep = {
        "one_step_rmse_K": d["rmse_K"],
        "open_loop_rmse_K": d["open_loop_rmse_K"],
        "exit_code": d["exit_code"],
    }
    return {
        "estimates": est,
        "at_bound": at_bound,
        "objective": d["objective"],
        "objective_value": d["objective_value"],
        **keep,
    }


def criterion(out: Path, season: str, model: Path, horizons: tuple[int, ...]) -> float:
    """The k-step criterion (K²) of the saved ``model`` on the season's forced-test trend at ``horizons``."""
    zm, folder = ZoneModel.load(model), out / f"forced_{season}"
    frame = data_source(folder / "trend.csv", folder / f"{ecl.ZONE}.columns.toml").frame(zm)
    values = {**zm.theta, **zm.noise, **zm.provenance.get("initial_state", {})}
    return float(kstep_cost(zm.network, values, prepare(zm, frame).dataset, horizons).value)


def _prediction(out: Path, row: dict) -> dict:
    """The 1-h and open-loop prediction RMSE of a run, from the file ``energyplus_closed_loop._run`` wrote."""
    margin = 0.0 if row["margin"] is None else row["margin"]
    path = (
        out
        / f"kstep_runs_{row['fit'] or 'baseline'}"
        / f"run_{row['season']}_{row['controller']}_{row['seed']}_{margin:g}.json"
    )
    r = json.loads(path.read_text())
    return {k: r[k] for k in PREDICTION}


def paired(results: list[dict], season: str, margin: float, kpi: str, per_day: bool) -> dict | None:
    """Per seed the k-step run's ``kpi`` minus the ML run's at ``margin``; mean, standard error, verdict."""
    runs = {
        (r["fit"], r["seed"]): r
        for r in results
        if r["season"] == season and r["fit"] and r["margin"] == margin
    }
    seeds = sorted(s for f, s in runs if f == KSTEP and (ML, s) in runs)
    if not seeds:
        return None

    def value(r: dict) -> float:
        return r[kpi] / r["days"] if per_day else r[kpi]

    ml = np.array([value(runs[ML, s]) for s in seeds])
    d = np.array([value(runs[KSTEP, s]) for s in seeds]) - ml
    se = float(d.std(ddof=1)) / math.sqrt(d.size) if d.size > 1 else math.nan
    mean_ml, mean_k = float(ml.mean()), float((ml + d).mean())
    return {
        "seeds": seeds,
        "ml": mean_ml,
        "kstep": mean_k,
        "mean": float(d.mean()),
        "se": se,
        "verdict": verdict(d, mean_ml),
    }


def table(results: list[dict]) -> str:
    """Markdown: per season, margin and KPI the baseline, both MPCs' means, the paired difference, its verdict."""
    lines = [
        "| season | margin K | KPI | baseline | MPC, ML fit | MPC, k-step fit | k-step − ML (mean ± s.e.) | verdict | seeds |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for season in ecl.SEASONS:
        base = [r for r in results if r["season"] == season and r["fit"] is None]
        margins = sorted({r["margin"] for r in results if r["season"] == season and r["fit"]}, reverse=True)
        for margin, (kpi, label, per_day) in ((m, k) for m in margins for k in KPIS):
            p = paired(results, season, margin, kpi, per_day)
            if p is None:
                continue
            b = (
                ""
                if not base or "rmse" in kpi
                else f"{base[0][kpi] / (base[0]['days'] if per_day else 1):.3f}"
            )
            cells = [season, f"{margin:g}", label, b, f"{p['ml']:.3f}", f"{p['kstep']:.3f}"]
            cells += [f"{p['mean']:+.3f} ± {p['se']:.3f}", p["verdict"], str(len(p["seeds"]))]
            lines.append("| " + " | ".join(cells) + " |")
    mpc = [r for r in results if r["fit"]]
    if not mpc:
        return "\n".join(lines) + "\n"
    wall, cpu = np.array([r["wall_s"] for r in mpc]), np.array([r["cpu_s"] for r in mpc])
    load = [r["load_1min"] for r in results]
    dates = sorted({r["date"] for r in results})
    note = (
        f"Runs of {' to '.join(dates[:: max(1, len(dates) - 1)])}: {len(mpc)} MPC runs of {mpc[0]['days']} days, "
        f"wall {wall.mean():.0f} s ({wall.min():.0f} to {wall.max():.0f}) and CPU {cpu.mean():.0f} s per run; "
        f"load average (1 min) {min(load):.1f} to {max(load):.1f} at the runs' ends on a 2-core machine shared with other jobs."
    )
    return "\n".join(lines) + "\n\n" + note + "\n"


def fits_table(fits: dict) -> str:
    """Markdown: per season the two fits' estimates, their errors on the forced-test trend and exit codes."""
    names = ("Cr", "Cw", "Rwin", "R1", "R2")
    lines = [
        "| season | fit | " + " | ".join(names) + " | at a bound | 1-step RMSE K | open-loop RMSE K | "
        "k-step criterion K² | exit |",
        "|---|---|" + "---|" * (len(names) + 5),
    ]
    for season in (s for s in ecl.SEASONS if s in fits):
        for fit in (ML, KSTEP):
            f = fits[season][fit]
            cells = [
                season,
                fit,
                *(f"{f['estimates'][n]:.3g}" for n in names),
                ", ".join(f["at_bound"]) or "-",
            ]
            cells += [
                f"{f['one_step_rmse_K']:.3f}",
                f"{f['open_loop_rmse_K']:.3f}",
                f"{f['criterion_K2']:.1f}",
            ]
            cells.append(str(f["exit_code"]))
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _save(out: Path, store: dict) -> None:
    (out / "energyplus_kstep.json").write_text(json.dumps(store, indent=1))
    (out / "energyplus_kstep.md").write_text(table(store["runs"]) + "\n" + fits_table(store["fits"]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--seasons", default="winter,summer")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--days", type=int, default=2)
    ap.add_argument(
        "--margins", default="0.1", help="how far inside the band the MPC aims, K (comma-separated)"
    )
    ap.add_argument("--horizons", default=",".join(map(str, HORIZONS)))
    ap.add_argument("--no-baseline", action="store_true", help="leave the building's own control out")
    a = ap.parse_args(argv)
    horizons = tuple(int(h) for h in a.horizons.split(","))
    a.out.mkdir(parents=True, exist_ok=True)
    path = a.out / "energyplus_kstep.json"
    store = (
        json.loads(path.read_text())
        if path.exists()
        else {"horizons": list(horizons), "fits": {}, "runs": []}
    )
    store["runs"] = [
        r if all(k in r for k in PREDICTION) else r | _prediction(a.out, r) for r in store["runs"]
    ]
    done = {(r["season"], r["fit"], r["seed"], r["days"], r["margin"]) for r in store["runs"]}
    for season in a.seasons.split(","):
        t0, c0 = time.perf_counter(), _cpu()
        models = {KSTEP: kstep_model(a.out, season, horizons), ML: a.out / f"zone_{season}.json"}
        print(f"{season}: fits in {time.perf_counter() - t0:.0f} s wall, {_cpu() - c0:.0f} s CPU", flush=True)
        fits = {ML: a.out / f"fit_{season}.json", KSTEP: a.out / f"fit_{season}_kstep.json"}
        store["fits"][season] = {
            fit: fit_summary(p) | {"criterion_K2": criterion(a.out, season, models[fit], horizons)}
            for fit, p in fits.items()
        }
        plan = [
            (fit, s, float(m)) for m in a.margins.split(",") for s in range(a.seeds) for fit in (ML, KSTEP)
        ]
        for fit, seed, margin in plan + ([] if a.no_baseline else [(None, 0, None)]):
            if (season, fit, seed, a.days, margin) in done:
                continue
            store["runs"].append(run(a.out, season, fit, seed, a.days, models[fit or ML], margin or 0.0))
            _save(a.out, store)
            print(json.dumps(store["runs"][-1]), flush=True)
        _save(a.out, store)
    return 0


if __name__ == "__main__":
    sys.exit(main())
