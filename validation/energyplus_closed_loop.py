"""The supervisory MPC against the building's own control on the EnergyPlus medium office (issue 35).

Usage::

    python validation/energyplus_closed_loop.py [--out validation-output] [--seasons winter,summer]
        [--seeds 3] [--days 2]

For each season: ``rczone emulate --test forced`` drives one perimeter zone of the medium office
(:data:`ZONE`) for :data:`FORCED_DAYS` days (the set-point schedule ``rczone design`` makes), ``rczone
fit`` identifies the paper's second-order model from that trend, and ``rczone control-test
--emulator energyplus`` runs the zone for ``--days`` from a later weekday (:data:`SEASONS`) under a
time-of-use price with BOPTEST's medium forecast error: ``baseline`` once (the building's own
control does not read rczone's sensors or forecasts, so every seed gives the same run) and ``mpc``
with seeds 0, 1, ... (sensor noise and forecast error), aiming ``--margin`` K inside the band. Every run is appended to
``<out>/energyplus_closed_loop.json`` as it finishes (kept when the script is stopped); the table
(:func:`table`) is written to ``<out>/energyplus_closed_loop.md``. The runs of docs/energyplus.md
are ``validation/energyplus_closed_loop.json`` (the seasons, run as two processes with ``--seasons
winter`` and ``--seasons summer`` and ``--margin 0.1`` then ``--margin 0``, joined); a test keeps
the page's table equal to :func:`table` of them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rczone.cli.main import main as rczone

BUILDING, WEATHER, ZONE = "office_medium", "usa_il_chicago", "Perimeter_mid_ZN_1"
#: (forced test start, closed-loop start): weekdays of 2017 (the typical year starts on a Sunday).
SEASONS = {"winter": ("01-09", "01-17"), "summer": ("07-10", "07-18")}
FORCED_DAYS = 3
STEP_MIN = 15


def forced_trend(folder: Path, season: str, *, weather: str = WEATHER) -> Path:
    """The season's forced test of :data:`ZONE` in ``folder`` (run in EnergyPlus once, reused): its trend."""
    if not (folder / "trend.csv").exists():
        args = ["emulate", "--building", BUILDING, "--weather", weather, "--start", SEASONS[season][0]]
        args += ["--days", str(FORCED_DAYS), "--step", str(STEP_MIN), "--test", "forced", "--zones", ZONE]
        if rczone([*args, "--seed", "1", "-o", str(folder)]) != 0:
            raise SystemExit(f"the forced test of {weather}, {season} failed")
    return folder / "trend.csv"


def _model(out: Path, season: str) -> Path:
    """The zone model fitted from the season's forced test (made once, reused)."""
    model = out / f"zone_{season}.json"
    if model.exists():
        return model
    folder = forced_trend(out / f"forced_{season}", season).parent
    args = ["fit", str(folder / "trend.csv"), "--columns", str(folder / f"{ZONE}.columns.toml")]
    args += ["--model", "second-order", "--starts", "1", "--no-profiles", "--save-model", str(model)]
    if rczone([*args, "--json", str(out / f"fit_{season}.json")]) not in (0, 3):
        raise SystemExit(f"the fit of {season} failed")
    return model


def _run(
    out: Path,
    season: str,
    controller: str,
    seed: int,
    days: int,
    model: Path,
    margin: float,
    *,
    weather: str = WEATHER,
) -> dict:
    """One ``rczone control-test`` of :data:`ZONE` from the season's closed-loop start: the row of its KPIs."""
    path = out / f"run_{season}_{controller}_{seed}_{margin:g}.json"
    args = ["control-test", "--emulator", "energyplus", "--building", BUILDING, "--weather", weather]
    args += ["--zone", ZONE, "--start", SEASONS[season][1], "--days", str(days), "--step", str(STEP_MIN)]
    args += ["--price", "tou", "--forecast", "medium", "--seed", str(seed), "--controller", controller]
    args += ["--margin", str(margin)] if controller == "mpc" else []
    if rczone([*args, "--model", str(model), "--json", str(path)]) != 0:
        raise SystemExit(f"the {controller} run of {season} (seed {seed}) failed")
    r = json.loads(path.read_text())
    keep = ("cost", "energy_kWh", "comfort_Kh", "peak_power_kW", "prediction_rmse_K", "building_hvac_kWh")
    row = {k: r[k] for k in keep}
    row["solve_ms"] = 1e3 * r["solve_time_s"]["mean"] if r["solve_time_s"] else None
    m = margin if controller == "mpc" else None
    return {"season": season, "controller": controller, "seed": seed, "days": days, "margin": m, **row}


def table(results: list[dict]) -> str:
    """The markdown table of the runs, and per season the MPC's mean against the baseline."""
    head = (
        "| season | controller | margin K | seed | HVAC cost | HVAC kWh | comfort K h per day | peak kW | "
        "1-step RMSE K | LP ms |\n|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines, verdicts = [], []
    for season in SEASONS:
        rows = [r for r in results if r["season"] == season]
        for r in rows:
            ms = "" if r["solve_ms"] is None else f"{r['solve_ms']:.0f}"
            lines.append(
                f"| {season} | {r['controller']} | {'' if r['margin'] is None else r['margin']} | {r['seed']} | {r['cost']:.2f} | {r['energy_kWh']:.2f} | "
                f"{r['comfort_Kh'] / r['days']:.2f} | {r['peak_power_kW']:.2f} | {r['prediction_rmse_K']:.3f} | {ms} |"
            )
        base = [r for r in rows if r["controller"] == "baseline"]
        margins = sorted({r["margin"] for r in rows if r["controller"] == "mpc"})
        for margin in margins if base else ():
            mpc = [r for r in rows if r["controller"] == "mpc" and r["margin"] == margin]
            b, days = base[0], base[0]["days"]
            cost = np.array([r["cost"] for r in mpc])
            dcomfort = np.array([(r["comfort_Kh"] - b["comfort_Kh"]) / days for r in mpc])
            holds = bool(np.all(cost < b["cost"]) and np.all(dcomfort <= 0.5))
            verdicts.append(
                f"- {season}, margin {margin:g} K: MPC cost {np.mean(cost):.2f} vs baseline {b['cost']:.2f} "
                f"({100 * (np.mean(cost) / b['cost'] - 1):+.1f} %, seeds {cost.min():.2f} to {cost.max():.2f}); "
                f"comfort {np.mean(dcomfort):+.2f} K h per zone-day against the baseline; "
                f"lower cost with at most +0.5 K h per zone-day on every seed: {'yes' if holds else 'no'}"
            )
    return head + "\n".join(lines) + "\n\n" + "\n".join(verdicts) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--seasons", default="winter,summer")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--days", type=int, default=2)
    ap.add_argument("--margin", type=float, default=0.1, help="how far inside the band the MPC aims, K")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    store = a.out / "energyplus_closed_loop.json"
    results = json.loads(store.read_text()) if store.exists() else []
    done = {(r["season"], r["controller"], r["seed"], r["days"], r["margin"]) for r in results}
    for season in a.seasons.split(","):
        model = _model(a.out, season)
        plan = [("baseline", 0)] + [("mpc", s) for s in range(a.seeds)]
        for controller, seed in plan:
            if (season, controller, seed, a.days, a.margin if controller == "mpc" else None) in done:
                continue
            results.append(_run(a.out, season, controller, seed, a.days, model, a.margin))
            store.write_text(json.dumps(results, indent=1))
            (a.out / "energyplus_closed_loop.md").write_text(table(results))
            print(json.dumps(results[-1]), flush=True)
    (a.out / "energyplus_closed_loop.md").write_text(table(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
