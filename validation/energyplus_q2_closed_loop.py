"""The paper's Q2 on EnergyPlus in closed loop: the MPC with the normal-operation fit against the forced-test fit (issue 35).

Usage::

    python validation/energyplus_q2_closed_loop.py [--out validation-output] [--q2-out DIR]
        [--climates usa_il_chicago,usa_az_phoenix] [--seasons winter,summer] [--seeds 5] [--days 2]
        [--margins 0] [--doc PAGE] [--trace CLIMATE,SEASON,SEED,MARGIN]

For each climate and season of ``validation/energyplus_q2.py`` the two second-order models of
:data:`ZONE` that script fits, on its first sensor replicate (replicate 0): the one fitted on the
five normal-operation weekdays (``calibration``) and the one fitted on the 3-day forced test
(``forced``). They are read from ``<q2-out>/<climate>_<season>/fit_<training>/model.json``, where
``energyplus_q2.py --out <q2-out>`` saved them; when they are not there, :func:`energyplus_q2.run_case`
makes them (same trends, seeds and settings). Each model's estimates are checked against the row
of ``validation/energyplus_q2.json`` (``--q2-json``) of the same case, so that the closed loop runs
the models of the Q2 tables, or the script stops.

Each model then drives ``rczone control-test --emulator energyplus --controller mpc --price tou
--forecast medium`` for ``--days`` from the closed-loop start of ``energyplus_closed_loop.SEASONS``
(:func:`energyplus_q1.run_loop`), seeds 0, 1, ... (sensor noise and forecast error), at ``--margins``,
both models on the same seeds; the building's own control (``baseline``) runs once per case. Per KPI
the table pairs the two MPCs by seed (:func:`energyplus_q1.loop_table` with :data:`FITS`): the
difference normal-fit − forced-fit (mean ± standard error) and the verdict of
:func:`rczone.control.comparison.verdict` (beyond two standard errors and 1 % of the forced fit's
mean; lower is better for every KPI, so "better" means the normal fit's MPC did better); under it
each MPC against the baseline by the closed-loop section's test.

Every run is appended to ``<out>/energyplus_q2_closed_loop.json`` as it finishes, written atomically
(kept when the script is stopped; a second start skips what is there); the tables go to
``<out>/energyplus_q2_closed_loop.md``, and ``--doc PAGE`` writes them between the page's markers
(:data:`BEGIN`, :data:`END`). The runs of docs/energyplus.md are
``validation/energyplus_q2_closed_loop.json``; a test keeps the page's tables equal to :func:`table`.
``--trace`` runs one seed of a case again (baseline and both MPCs) and prints :func:`outside_band`
of each: which side of the band the room left, and the cooling set point the controller held.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, sections IV (Q2: calibration on
   closed-loop data of normal operation against a forced-response test) and V (such a model "is
   unlikely to be useful in predictive control").
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   sections 13.4 (identification in closed loop) and 16.6 (model validation).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from rczone.files.atomic import write_text_atomic
from rczone.models.zone import ZoneModel

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import energyplus_q1 as eq1  # noqa: E402
import energyplus_q2 as eq2  # noqa: E402

ZONE = eq2.ZONE
#: The two fits of Q2 paired, normal-operation minus forced test (the values of ``training`` there).
FITS = ("calibration", "forced")
SHORT = ("normal-fit", "forced-fit")
NAMES = {"calibration": "normal-fit MPC", "forced": "forced-fit MPC"}
MARGINS = (0.0,)
#: The lines of docs/energyplus.md between which ``--doc`` writes :func:`table`.
BEGIN = "<!-- energyplus_q2_closed_loop.py: begin -->"
END = "<!-- energyplus_q2_closed_loop.py: end -->"
#: Relative difference within which a saved model's estimate is the one of Q2's JSON (a refit on
#: another machine may differ in the last digits; the tables give three).
SAME = 1e-3


def model_path(q2_out: Path, weather: str, season: str, training: str) -> Path:
    """Where ``energyplus_q2.py --out q2_out`` saved the replicate-0 fit of ``training``."""
    return q2_out / f"{weather}_{season}" / f"fit_{training}" / "model.json"


def q2_row(q2_rows: list[dict], weather: str, season: str, training: str) -> dict:
    """The replicate-0 row of Q2's JSON for one case and training period."""
    for r in q2_rows:
        if (r["climate"], r["season"], r["training"], r.get("replicate", 0)) == (
            weather,
            season,
            training,
            0,
        ):
            return r
    raise SystemExit(f"energyplus_q2.json has no fit of {weather}, {season}, {training} (replicate 0)")


def check_model(theta: dict[str, float], row: dict) -> dict[str, float]:
    """The R and C of Q2's ``row``; stops when ``theta`` (a saved model's) differs from them."""
    est = {p: row["estimates"][p]["estimate"] for p in eq2.PARAMS}
    off = [p for p in eq2.PARAMS if not math.isclose(theta[p], est[p], rel_tol=SAME)]
    if off:
        raise SystemExit(
            f"the saved model of {row['climate']}, {row['season']}, {row['training']} is not Q2's: "
            f"{', '.join(off)} differ (refit with energyplus_q2.py, or pass its --out as --q2-out)"
        )
    return est


def models(q2_out: Path, q2_rows: list[dict], weather: str, season: str, starts: str) -> dict[str, dict]:
    """Per fit of :data:`FITS` the saved model's path and what Q2 recorded of it (fitted first if missing)."""
    if not all(model_path(q2_out, weather, season, t).exists() for t in FITS):
        eq2.run_case(q2_out, weather, season, starts, 0)
    found = {}
    for training in FITS:
        path, row = model_path(q2_out, weather, season, training), q2_row(q2_rows, weather, season, training)
        est = check_model(ZoneModel.load(path).theta, row)
        h = row["heldout"]
        found[training] = {
            "path": path,
            "row": {
                "climate": weather, "season": season, "fit": training, "exit_code": row["exit_code"],
                "estimates": est, "heldout": {k: h[k]["model"] for k in ("1 h", "6 h", "open")},
            },
        }  # fmt: skip
    return found


def models_table(fits: list[dict]) -> str:
    """Markdown: per case and fit its ``rczone fit`` exit code, R and C and held-out RMSE (Q2's)."""
    lines = [
        "| climate | season | fitted on | fit exit | Cr J/K | Cw J/K | Rwin K/W | R1 K/W | R2 K/W | "
        "held-out RMSE K 1 h / 6 h / open loop (Q2) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(fits, key=lambda r: (eq1._order(r), FITS.index(r["fit"]))):
        cells = [
            r["climate"],
            r["season"],
            dict(zip(FITS, SHORT, strict=True))[r["fit"]],
            str(r["exit_code"]),
        ]
        cells += [f"{r['estimates'][p]:.3g}" for p in eq2.PARAMS]
        cells.append(" / ".join(eq2._f(r["heldout"][k]) for k in ("1 h", "6 h", "open")))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def outside_band(frame, step_h: float) -> dict:
    """Where a run's room left the band over the occupied steps, from its series (``to_frame()`` of
    :func:`rczone.emulators.control.energyplus_test`): K h above and below, and the hours the cooling
    set point in effect lay above the band's top, with its mean and largest value then, degC."""
    occ = frame["occupied"].astype(bool)
    ti, up, lo, cool = frame["Ti"][occ], frame["upper"][occ], frame["lower"][occ], frame["cooling_sp"][occ]
    raised = cool > up + 1e-6
    return {
        "above_Kh": float((ti - up).clip(lower=0).sum() * step_h),
        "below_Kh": float((lo - ti).clip(lower=0).sum() * step_h),
        "cooling_sp_above_band_h": float(raised.sum() * step_h),
        "cooling_sp_mean_degC": float(cool.mean()),
        "cooling_sp_max_degC": float(cool.max()),
    }


def trace(q2_out: Path, case: tuple[str, str], seed: int, margin: float) -> dict[str, dict]:
    """The baseline and both fits' MPCs of ``case`` run again through the API: :func:`outside_band` of each."""
    from rczone.emulators.control import energyplus_test
    from rczone.emulators.plant import EnergyPlusPlant

    weather, season = case
    found = {None: model_path(q2_out, weather, season, FITS[1])} | {
        f: model_path(q2_out, weather, season, f) for f in FITS
    }
    rows = {}
    for fit, path in found.items():
        plant = EnergyPlusPlant(
            eq2.BUILDING, weather, zones=[ZONE], start=eq1.ecl.SEASONS[season][1], days=2,
            step_minutes=eq1.ecl.STEP_MIN, seed=seed, price="tou", forecast="medium",
        )  # fmt: skip
        res = energyplus_test(
            plant, "mpc" if fit else "baseline", model=ZoneModel.load(path), margin_K=margin
        )
        rows[fit or "baseline"] = outside_band(res.to_frame(), eq1.ecl.STEP_MIN / 60)
    return rows


def table(store: dict) -> str:
    """The page's tables: the two models, then the closed loop paired by seed."""
    loop = eq1.loop_table(store["runs"], fits=FITS, short=SHORT, names=NAMES)
    return models_table(store["fits"]) + "\n" + loop


def _save(out: Path, store: dict) -> None:
    write_text_atomic(out / "energyplus_q2_closed_loop.json", json.dumps(store, indent=1))
    write_text_atomic(out / "energyplus_q2_closed_loop.md", table(store))


def run_case(
    out: Path, store: dict, case: tuple[str, str], a: argparse.Namespace, q2_rows: list[dict]
) -> None:
    """Run the baseline and both fits' MPCs of one (climate, season), saving after each run."""
    weather, season = case
    found = models(a.q2_out, q2_rows, weather, season, a.starts)
    for training, m in found.items():
        if not any((f["climate"], f["season"], f["fit"]) == (*case, training) for f in store["fits"]):
            store["fits"].append(m["row"])
            _save(out, store)
    paths = {t: m["path"] for t, m in found.items()}
    eq1.run_loop(out / f"q2cl_{weather}", store, case, a, paths, lambda: _save(out, store))


def main(argv: list[str] | None = None) -> int:
    ap = eq1.loop_parser(__doc__.splitlines()[0], seeds=5)
    ap.add_argument(
        "--q2-out", type=Path, help="energyplus_q2.py's --out, where its models are (default: --out)"
    )
    ap.add_argument("--q2-json", type=Path, default=HERE / "energyplus_q2.json", help="Q2's recorded fits")
    ap.add_argument(
        "--trace", help="CLIMATE,SEASON,SEED,MARGIN: where the room left the band, per controller"
    )
    a = ap.parse_args(argv)
    a.q2_out = a.q2_out or a.out
    if a.trace:
        weather, season, seed, margin = a.trace.split(",")
        rows = trace(a.q2_out, (weather, season), int(seed), float(margin))
        print(json.dumps(rows, indent=1))
        return 0
    store = eq1.open_store(a, "energyplus_q2_closed_loop.json", table, (BEGIN, END))
    if store is None:
        return 0
    q2_rows = json.loads(a.q2_json.read_text())
    for weather in a.climates.split(","):
        for season in a.seasons.split(","):
            run_case(a.out, store, (weather, season), a, q2_rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
