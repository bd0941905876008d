"""The multi-zone question on EnergyPlus in closed loop: one floor MPC or one MPC per zone (issue 35).

Usage::

    python validation/energyplus_floor_closed_loop.py [--out validation-output] [--climates usa_il_chicago]
        [--seasons winter,summer] [--seeds 3] [--days 2] [--fits floor,zones,floor_prior] [--doc PAGE]

On the small office's floor (``validation/energyplus_multizone.py``: five zones, the models it fits
by ``rczone fit`` on its two calibration weekdays of normal operation, reused from ``--out`` when
there), ``rczone control-test --emulator energyplus --price tou --forecast medium --step 15
--margin 0`` runs the five zones for ``--days`` from :data:`START` (a Tuesday after the
calibration days) under

* ``floor``: one centralized floor MPC (``--zones Z1,...,Z5 --model floor.json``,
  :class:`rczone.emulators.floormpc.FloorMPC`) on the fitted joint model of the floor;
* ``zones``: one supervisory MPC per zone (``--zones Z1=m1.json,...``,
  :class:`rczone.emulators.supervisory.ZoneMPCs`) on the fitted second-order models, each with its
  neighbours' measured temperatures as ``Tsd`` held over the horizon;
* ``floor_prior``: the floor MPC on the joint model at its construction values
  (``rczone models generate``'s file, not fitted);

seeds 0, 1, ... (sensor noise and forecast error), and the building's own control once. The floor
MPCs are paired with the zone MPCs by seed (:func:`energyplus_q1.paired`: mean ± standard error of
the difference and :func:`rczone.control.comparison.verdict`), each against the baseline by the
closed-loop section's test (:func:`energyplus_q1.against_baseline`). Comfort is K h per zone-day:
the run's ``comfort_Kh`` (the five zones' sum) over the zones and days.

Every run is appended to ``<out>/energyplus_floor_closed_loop.json`` as it finishes (a second start
skips what is there); ``--doc PAGE`` writes :func:`table` of them between :data:`BEGIN` and
:data:`END`, and a test keeps docs/energyplus.md's equal to :func:`table` of
``validation/energyplus_floor_closed_loop.json``.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012 (a zone's neighbours as inputs).
.. [2] J. B. Rawlings, D. Q. Mayne, M. M. Diehl, *Model Predictive Control: Theory, Computation,
   and Design*, 2nd ed., Nob Hill 2017, section 6.1 (centralized against decentralized MPC).
"""

from __future__ import annotations

import json
import os
import sys
import time
import tomllib
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from rczone.cli.main import main as rczone
from rczone.files.atomic import write_text_atomic

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import energyplus_kstep as eks  # noqa: E402
import energyplus_multizone as emz  # noqa: E402
import energyplus_q1 as eq1  # noqa: E402

BUILDING, FLOOR, STEP_MIN = emz.BUILDING, emz.FLOOR, 15
#: Season -> first day of the loop (MM-DD of 2017): the Tuesday after the calibration days.
START = {"winter": "01-24", "summer": "07-25"}
FITS = ("floor", "zones", "floor_prior")
NAMES = {
    "floor": "floor MPC, joint model fitted",
    "zones": "zone MPCs, single-zone models fitted",
    "floor_prior": "floor MPC, joint model at construction values (not fitted)",
}
#: (key, label, per zone-day) of the paired KPIs.
KPIS = (("cost", "HVAC cost", False), ("comfort_Kh", "comfort K h per zone-day", True))
KPIS += (("energy_kWh", "HVAC kWh", False),)
NAME = "energyplus_floor_closed_loop.json"
#: The lines of docs/energyplus.md between which ``--doc`` writes :func:`table`.
BEGIN, END = (
    "<!-- energyplus_floor_closed_loop.py: begin -->",
    "<!-- energyplus_floor_closed_loop.py: end -->",
)


def models(out: Path, weather: str, season: str) -> tuple[list[str], dict[str, Path | dict[str, Path]]]:
    """The floor's zones and, per fit, its model(s): fitted by ``energyplus_multizone.py`` unless done."""
    case = out / f"{weather}_{season}"
    rooms = [z["name"] for z in _rooms(case)] if (case / "calibration" / "building.toml").exists() else []
    if not rooms or not all((case / z / "model.json").exists() for z in ["joint", *rooms]):
        emz.run_case(out, weather, season)
        rooms = [z["name"] for z in _rooms(case)]
    return rooms, {
        "floor": case / "joint" / "model.json",
        "zones": {z: case / z / "model.json" for z in rooms},
        "floor_prior": case / "joint" / f"floor{FLOOR}.toml",
    }


def _rooms(case: Path) -> list[dict]:
    return emz.floor_zones(tomllib.loads((case / "calibration" / "building.toml").read_text()))


def command(
    weather: str, season: str, fit: str | None, seed: int, days: int, rooms: list[str], model
) -> list[str]:
    """The ``rczone control-test`` arguments of one run (``fit`` None: the baseline)."""
    args = ["control-test", "--emulator", "energyplus", "--building", BUILDING, "--weather", weather]
    args += ["--start", START[season], "--days", str(days), "--step", str(STEP_MIN), "--price", "tou"]
    args += ["--forecast", "medium", "--seed", str(seed)]
    if fit is None:
        return [*args, "--zones", ",".join(rooms), "--controller", "baseline"]
    if fit == "zones":
        zones = ",".join(f"{z}={model[z]}" for z in rooms)
        return [*args, "--zones", zones, "--controller", "mpc", "--margin", "0"]
    return [*args, "--zones", ",".join(rooms), "--model", str(model), "--controller", "mpc", "--margin", "0"]


def run(folder: Path, case: tuple[str, str], fit: str | None, seed: int, days: int, rooms, model) -> dict:
    """One closed-loop run of the floor: its row (comfort per zone; the five zones' totals otherwise)."""
    weather, season = case
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"run_{season}_{fit or 'baseline'}_{seed}.json"
    wall, cpu = time.perf_counter(), eks._cpu()
    if rczone([*command(weather, season, fit, seed, days, rooms, model), "-q", "--json", str(path)]) != 0:
        raise SystemExit(f"the {fit or 'baseline'} run of {weather} {season} (seed {seed}) failed")
    r = json.loads(path.read_text())
    return {
        "climate": weather, "season": season, "start": START[season], "fit": fit, "seed": seed, "days": days,
        "margin": None if fit is None else 0.0, "zones": rooms, "cost": r["cost"], "energy_kWh": r["energy_kWh"],
        "comfort_Kh": r["comfort_Kh"] / len(rooms), "comfort_Kh_total": r["comfort_Kh"],
        "comfort_Kh_zone": {z: r[f"comfort_Kh_{z}"] for z in rooms}, "peak_power_kW": r["peak_power_kW"],
        "constraint_violations": r["constraint_violations"],
        "solve_ms": 1e3 * r["solve_time_s"]["mean"] if r.get("solve_time_s") else None,
        "wall_s": time.perf_counter() - wall, "cpu_s": eks._cpu() - cpu, "load_1min": os.getloadavg()[0],
        "date": datetime.now(UTC).strftime("%Y-%m-%d"),
    }  # fmt: skip


def _kpi_rows(runs: list[dict], case: tuple[str, str], fit: str) -> list[str]:
    """The rows of one case and floor MPC: per KPI baseline, zone MPCs, floor MPC, the paired difference."""
    base = [r for r in runs if (r["climate"], r["season"]) == case and r["fit"] is None]
    lines = []
    for kpi, label, per_day in KPIS:
        p = eq1.paired(runs, case, 0.0, kpi, per_day, fits=(fit, "zones"))
        if p is None:
            continue
        b = f"{base[0][kpi] / (base[0]['days'] if per_day else 1):.3f}" if base else ""
        cells = [*case, NAMES[fit], label, b, f"{p['two']:.3f}", f"{p['one']:.3f}"]
        cells += [f"{p['mean']:+.3f} ± {p['se']:.3f}", p["verdict"], str(len(p["seeds"]))]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def zone_table(runs: list[dict]) -> str:
    """Markdown: per case and controller the comfort of each zone, K h per day (mean over the seeds)."""
    zones = next((r["zones"] for r in runs), [])
    lines = [
        "| climate | season | controller | " + " | ".join(zones) + " | peak kW | LP ms per step |",
        "|---|---|---|" + "---|" * (len(zones) + 2),
    ]
    for case in eq1._cases(runs):
        for fit in (None, *FITS):
            rs = [r for r in runs if (r["climate"], r["season"]) == case and r["fit"] == fit]
            if not rs:
                continue
            cells = [*case, "baseline" if fit is None else NAMES[fit]]
            cells += [f"{np.mean([r['comfort_Kh_zone'][z] / r['days'] for r in rs]):.2f}" for z in zones]
            ms = [r["solve_ms"] for r in rs if r["solve_ms"] is not None]
            cells += [f"{np.mean([r['peak_power_kW'] for r in rs]):.1f}", f"{np.mean(ms):.0f}" if ms else ""]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def table(store: dict) -> str:
    """The page's tables: each floor MPC paired with the zone MPCs, the lines against the baseline, per zone."""
    runs = store["runs"]
    head = (
        "| climate | season | floor MPC | KPI | baseline | zone MPCs | floor MPC | floor − zone MPCs "
        "(mean ± s.e.) | verdict for the floor MPC | seeds |\n|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = [x for case in eq1._cases(runs) for f in FITS if f != "zones" for x in _kpi_rows(runs, case, f)]
    checks = eq1.against_baseline(runs, fits=FITS, names=NAMES)
    mpc = [r for r in runs if r["fit"]]
    note = ""
    if mpc:
        wall, load = np.array([r["wall_s"] for r in mpc]), [r["load_1min"] for r in runs]
        dates = sorted({r["date"] for r in runs})
        note = (
            f"\nRuns of {' to '.join(dates[:: max(1, len(dates) - 1)])}: {len(mpc)} MPC runs of {mpc[0]['days']} "
            f"days, wall {wall.mean():.0f} s ({wall.min():.0f} to {wall.max():.0f}) per run; load average "
            f"(1 min) {min(load):.1f} to {max(load):.1f} at the runs' ends on a 2-core machine shared with other jobs.\n"
        )
    return head + "\n".join(rows) + "\n\n" + "\n".join(checks) + "\n\n" + zone_table(runs) + note


def run_case(a, store: dict, case: tuple[str, str], fits: list[str]) -> None:
    """The baseline once, then per seed each fit's MPC; what ``store`` holds is skipped, each run saved."""
    rooms, paths = models(a.out, *case)
    done = {(r["climate"], r["season"], r["fit"], r["seed"], r["days"]) for r in store["runs"]}
    for fit, seed in [(None, 0)] + [(f, s) for s in range(a.seeds) for f in fits]:
        if (*case, fit, seed, a.days) in done:
            continue
        folder = a.out / f"{case[0]}_{case[1]}" / "closed_loop"
        store["runs"].append(run(folder, case, fit, seed, a.days, rooms, paths.get(fit)))
        write_text_atomic(a.out / NAME, json.dumps(store, indent=1))
        write_text_atomic(a.out / NAME.replace(".json", ".md"), table(store))
        r = store["runs"][-1]
        print(
            json.dumps({k: r[k] for k in ("climate", "season", "fit", "seed", "cost", "comfort_Kh")}),
            flush=True,
        )


def main(argv: list[str] | None = None) -> int:
    ap = eq1.loop_parser(__doc__.splitlines()[0], seeds=3)
    ap.add_argument("--fits", default=",".join(FITS), help="which MPCs: floor, zones, floor_prior")
    a = ap.parse_args(argv)
    store = eq1.open_store(a, NAME, table, (BEGIN, END))
    if store is None:
        return 0
    for season in a.seasons.split(","):
        for weather in a.climates.split(","):
            run_case(a, store, (weather, season), a.fits.split(","))
    return 0


if __name__ == "__main__":
    sys.exit(main())
