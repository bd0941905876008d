"""The paper's Q1 on EnergyPlus: is the 2-state zone model enough for MPC, against the 1-state one (issue 35).

Usage::

    python validation/energyplus_q1.py [--out validation-output] [--climates usa_il_chicago,usa_az_phoenix]
        [--seasons winter,summer] [--seeds 3] [--days 2] [--starts auto]

For each climate and season, on one perimeter zone of the medium office (:data:`ZONE`, the zone of the
closed-loop and Q2 sections), the 3-day forced test of ``validation/energyplus_closed_loop.py``
(:func:`energyplus_closed_loop.forced_trend`: the thermostat schedule ``rczone design`` makes, the
same days and sensor seed, in the case's climate) is fitted twice by ``rczone fit`` (ML,
``--starts``, the zone's floor area): with the paper's first-order model (:data:`ONE`, M(1, 5, 3):
one capacitance, ``Rwin`` to outdoors, ``Rw`` to the surroundings' ``Tsd``) and with its
second-order model (:data:`TWO`, M(2, 5, 5)). Each fit is scored in prediction on the held-out
normal-operation days of ``validation/energyplus_q2.py`` (its ``heldout`` period and scoring: 1 h,
6 h and open loop, persistence beside) and in closed loop: ``rczone control-test --emulator
energyplus --controller mpc --price tou --forecast medium`` for ``--days`` from the closed-loop
start of ``energyplus_closed_loop.SEASONS``, seeds 0, 1, ... (sensor noise and forecast error), at
``--margins`` (default 0: aiming at the band's edge), both models on the same seeds; the building's own
control (``baseline``) once per case.
Per KPI the table (:func:`table`) pairs the two MPCs by seed: the difference 1-state − 2-state
(mean ± standard error) and the verdict of :func:`rczone.control.comparison.verdict` (beyond two
standard errors and 1 % of the 2-state mean; lower is better for every KPI, so "better" means the
1-state MPC did better).

Every fit and run is appended to ``<out>/energyplus_q1.json`` as it finishes (kept when the script
is stopped; a second start skips what is there); the tables go to ``<out>/energyplus_q1.md``, and
``--doc PAGE`` writes them between the page's markers (:data:`BEGIN`, :data:`END`). The runs of
docs/energyplus.md are ``validation/energyplus_q1.json``; a test keeps the page's tables equal to
:func:`table` of them. The paper's third candidate, the joint model of the floor in closed loop,
needs a centralized MPC of the floor, which rczone does not have yet; it is not measured here.
The pairing (:func:`paired`), the closed-loop table, the run loop (:func:`run_loop`) and the options
(:func:`loop_parser`) take the two fits to compare, and serve ``energyplus_q2_closed_loop.py`` too.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, section III (which model order is
   enough: the first- and second-order models against the full-scale one).
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 16.6 (model validation on fresh data).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rczone.control.comparison import verdict
from rczone.files.atomic import write_text_atomic

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import energyplus_closed_loop as ecl  # noqa: E402
import energyplus_kstep as eks  # noqa: E402
import energyplus_q2 as eq2  # noqa: E402

ZONE = ecl.ZONE
ONE, TWO = "first-order", "second-order"
MODELS = (ONE, TWO)
CLIMATES, SEASONS = eq2.CLIMATES, tuple(ecl.SEASONS)
#: How far inside the band the MPC aims, K, by default: the band's edge (the closed-loop section's runs
#: that beat the baseline in winter).
MARGINS = (0.0,)
#: The closed-loop section's test of the MPC against the baseline: at most this much more discomfort, K h per zone-day.
COMFORT_SLACK = 0.5
#: The lines of docs/energyplus.md between which ``--doc`` writes :func:`table`.
BEGIN, END = "<!-- energyplus_q1.py: begin -->", "<!-- energyplus_q1.py: end -->"


def _case(out: Path, weather: str) -> Path:
    return out / f"q1_{weather}"


def fit_and_score(out: Path, weather: str, season: str, model: str, starts: str) -> dict:
    """Fit ``model`` on the season's forced test and score it on the held-out normal days: the fit's row."""
    case = _case(out, weather)
    forced = ecl.forced_trend(case / f"forced_{season}", season, weather=weather).parent
    eq2._emulate(case / f"heldout_{season}", weather, season, "heldout", 0)
    fit, path, fit_time = eq2._fit(forced, case / f"fit_{season}_{model}", starts, model_name=model)
    scores, failed, score_time = eq2._scores(path, case / f"heldout_{season}")
    estimates = {
        name: {
            "estimate": p["estimate"],
            "std_error": p["std_error"],
            "robust_std_error": fit["robust_std_errors"].get(name, {}).get("robust"),
            "at_bound": bool(p["at_bound"]),
        }
        for name, p in fit["parameters"].items()
        if not name.startswith("sigma")
    }
    return {
        "climate": weather, "season": season, "model": model, "starts": starts,
        "exit_code": fit["exit_code"], "reasons": fit["verdict"]["reasons"],
        "one_step_rmse_K": fit["rmse_K"], "open_loop_rmse_K": fit["open_loop_rmse_K"],
        "estimates": estimates, "heldout": scores, "heldout_failed": failed,
        "fit_time": fit_time, "score_time": score_time,
    }  # fmt: skip


def model_path(out: Path, weather: str, season: str, model: str) -> Path:
    """Where :func:`fit_and_score` saved the fitted ``model``."""
    return _case(out, weather) / f"fit_{season}_{model}" / "model.json"


def paired(
    runs: list[dict],
    case: tuple[str, str],
    margin: float,
    kpi: str,
    per_day: bool,
    *,
    fits: tuple[str, str] = MODELS,
) -> dict | None:
    """Per seed the MPC of ``fits[0]``'s ``kpi`` minus that of ``fits[1]`` in ``case`` (climate, season) at ``margin``.

    By default the 1-state MPC minus the 2-state one; ``one`` and ``two`` are the means of ``fits[0]``
    and ``fits[1]``, the verdict is for ``fits[0]`` against 1 % of ``fits[1]``'s mean.
    """
    first, second = fits
    by = {
        (r["fit"], r["seed"]): r
        for r in runs
        if (r["climate"], r["season"]) == case and r["fit"] and r["margin"] == margin
    }
    seeds = sorted(s for f, s in by if f == first and (second, s) in by)
    if not seeds:
        return None

    def value(r: dict) -> float:
        return r[kpi] / r["days"] if per_day else r[kpi]

    two = np.array([value(by[second, s]) for s in seeds])
    d = np.array([value(by[first, s]) for s in seeds]) - two
    se = float(d.std(ddof=1)) / math.sqrt(d.size) if d.size > 1 else math.nan
    return {
        "seeds": seeds,
        "one": float((two + d).mean()),
        "two": float(two.mean()),
        "mean": float(d.mean()),
        "se": se,
        "verdict": verdict(d, float(two.mean())),
    }


def _order(r: dict) -> tuple:
    climate = CLIMATES.index(r["climate"]) if r["climate"] in CLIMATES else len(CLIMATES)
    season = SEASONS.index(r["season"]) if r["season"] in SEASONS else len(SEASONS)
    return climate, season, MODELS.index(r["model"]) if "model" in r else 0


def _verdict(r: dict) -> str:
    """``rczone fit``'s verdict: its exit code and how many reasons it gave."""
    return (
        "trustworthy (0)"
        if r["exit_code"] == 0
        else f"flagged ({r['exit_code']}), {len(r['reasons'])} reasons"
    )


def fits_table(fits: list[dict]) -> str:
    """Markdown: per case and model the fit's verdict, estimates and its held-out prediction errors."""
    lines = [
        "| climate | season | model | fit verdict | R and C (robust relative s.e.) | determined | RMSE K on the "
        "forced test: 1 step / open loop | held-out RMSE K 1 h: model / persistence | 6 h | open loop | "
        "2σ coverage open loop | held-out checks failed |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(fits, key=_order):
        h, rc = r["heldout"], {n: e for n, e in r["estimates"].items() if n[0] in "CR"}
        cells = [r["climate"], r["season"], r["model"], _verdict(r)]
        cells.append(", ".join(f"{n} {eq2._rc(e)}" for n, e in rc.items()))
        cells.append(f"{sum(eq2.determined(e) for e in rc.values())} of {len(rc)}")
        cells.append(f"{r['one_step_rmse_K']:.2f} / {r['open_loop_rmse_K']:.2f}")
        cells += [
            " / ".join(eq2._f(h[k].get(p)) for p in ("model", "persistence")) for k in ("1 h", "6 h", "open")
        ]
        cells += [f"{100 * h['open']['coverage']:.0f} %", ", ".join(r["heldout_failed"]) or "none"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _cases(runs: list[dict]) -> list[tuple[str, str]]:
    cases = {(r["climate"], r["season"]) for r in runs}
    return sorted(cases, key=lambda c: _order({"climate": c[0], "season": c[1]}))


def loop_table(
    runs: list[dict],
    *,
    fits: tuple[str, str] = MODELS,
    short: tuple[str, str] = ("1-state", "2-state"),
    names: dict[str, str] | None = None,
) -> str:
    """Markdown: per case, margin and KPI the baseline, both MPCs' means, the paired difference and its verdict.

    ``fits`` are the two values of the runs' ``fit`` paired (the first minus the second), ``short``
    their names in the table's head, ``names`` theirs in :func:`against_baseline`'s lines.
    """
    a, b = short
    lines = [
        f"| climate | season | margin K | KPI | baseline | MPC, {a} | MPC, {b} | {a} − {b} "
        f"(mean ± s.e.) | verdict for the {a} MPC | seeds |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case in _cases(runs):
        base = [r for r in runs if (r["climate"], r["season"]) == case and r["fit"] is None]
        margins = sorted({r["margin"] for r in runs if (r["climate"], r["season"]) == case and r["fit"]})
        for margin, (kpi, label, per_day) in ((m, k) for m in margins for k in eks.KPIS):
            p = paired(runs, case, margin, kpi, per_day, fits=fits)
            if p is None:
                continue
            base_cell = (
                ""
                if not base or "rmse" in kpi
                else f"{base[0][kpi] / (base[0]['days'] if per_day else 1):.3f}"
            )
            cells = [*case, f"{margin:g}", label, base_cell, f"{p['one']:.3f}", f"{p['two']:.3f}"]
            cells += [f"{p['mean']:+.3f} ± {p['se']:.3f}", p["verdict"], str(len(p["seeds"]))]
            lines.append("| " + " | ".join(cells) + " |")
    mpc = [r for r in runs if r["fit"]]
    if not mpc:
        return "\n".join(lines) + "\n"
    wall, cpu = np.array([r["wall_s"] for r in mpc]), np.array([r["cpu_s"] for r in mpc])
    load, dates = [r["load_1min"] for r in runs], sorted({r["date"] for r in runs})
    note = (
        f"Runs of {' to '.join(dates[:: max(1, len(dates) - 1)])}: {len(mpc)} MPC runs of {mpc[0]['days']} days, "
        f"wall {wall.mean():.0f} s ({wall.min():.0f} to {wall.max():.0f}) and CPU {cpu.mean():.0f} s per run; "
        f"load average (1 min) {min(load):.1f} to {max(load):.1f} at the runs' ends on a 2-core machine shared "
        "with other jobs."
    )
    checks = against_baseline(runs, fits=fits, names=names)
    return "\n".join(lines) + "\n\n" + "\n".join(checks) + "\n\n" + note + "\n"


def against_baseline(
    runs: list[dict], *, fits: tuple[str, ...] = MODELS, names: dict[str, str] | None = None
) -> list[str]:
    """A line per case, margin and fit: its MPC's cost and comfort against the building's own control,
    and whether it cost less with at most :data:`COMFORT_SLACK` more discomfort on every seed.

    ``names`` maps a fit to what the line calls its MPC (by default "<fit> MPC")."""
    lines = []
    for case in _cases(runs):
        here = [r for r in runs if (r["climate"], r["season"]) == case]
        base = [r for r in here if r["fit"] is None]
        for margin, model in ((m, f) for m in sorted({r["margin"] for r in here if r["fit"]}) for f in fits):
            mpc = [r for r in here if r["fit"] == model and r["margin"] == margin]
            if not base or not mpc:
                continue
            b = base[0]
            cost = np.array([r["cost"] for r in mpc])
            dcomfort = np.array([(r["comfort_Kh"] - b["comfort_Kh"]) / r["days"] for r in mpc])
            holds = bool(np.all(cost < b["cost"]) and np.all(dcomfort <= COMFORT_SLACK))
            lines.append(
                f"- {case[0]}, {case[1]}, margin {margin:g} K, {(names or {}).get(model, f'{model} MPC')}: cost {cost.mean():.2f} against the "
                f"baseline's {b['cost']:.2f} ({100 * (cost.mean() / b['cost'] - 1):+.1f} %), comfort "
                f"{dcomfort.mean():+.2f} K h per zone-day against the baseline; lower cost with at most "
                f"+{COMFORT_SLACK:g} K h per zone-day on every seed: {'yes' if holds else 'no'}"
            )
    return lines


def table(store: dict) -> str:
    """The page's tables: the fits in prediction, then the closed loop."""
    return fits_table(store["fits"]) + "\n" + loop_table(store["runs"])


def _save(out: Path, store: dict) -> None:
    write_text_atomic(out / "energyplus_q1.json", json.dumps(store, indent=1))
    write_text_atomic(out / "energyplus_q1.md", table(store))


def run_case(out: Path, store: dict, case: tuple[str, str], a: argparse.Namespace) -> None:
    """Fit both models of one (climate, season) and run them and the baseline in closed loop, saving each."""
    weather, season = case
    for model in MODELS:
        if not any((f["climate"], f["season"], f["model"]) == (*case, model) for f in store["fits"]):
            store["fits"].append(fit_and_score(out, weather, season, model, a.starts))
            _save(out, store)
            print(
                json.dumps({k: store["fits"][-1][k] for k in ("climate", "season", "model", "exit_code")}),
                flush=True,
            )
    models = {m: model_path(out, weather, season, m) for m in MODELS}
    run_loop(_case(out, weather), store, case, a, models, lambda: _save(out, store))


def run_loop(
    folder: Path,
    store: dict,
    case: tuple[str, str],
    a: argparse.Namespace,
    models: dict[str, Path],
    save: Callable[[], None],
) -> None:
    """Run one (climate, season): the baseline once, then per margin and seed the MPC of each fit in
    ``models`` (fit -> saved model, in the order given); what ``store`` holds is skipped, ``save``
    is called after each run. The runs' files go under ``folder``."""
    weather, season = case
    done = {(r["climate"], r["season"], r["fit"], r["seed"], r["days"], r["margin"]) for r in store["runs"]}
    margins = [float(m) for m in a.margins.split(",")]
    plan = [(None, 0, None)] + [(f, s, m) for m in margins for s in range(a.seeds) for f in models]
    for fit, seed, margin in plan:
        if (weather, season, fit, seed, a.days, margin) in done:
            continue
        model = models[fit] if fit else list(models.values())[-1]  # the baseline reads no model
        row = eks.run(folder, season, fit, seed, a.days, model, margin or 0.0, weather=weather)
        store["runs"].append({"climate": weather, **row})
        save()
        print(json.dumps(store["runs"][-1]), flush=True)


def loop_parser(description: str, *, seeds: int) -> argparse.ArgumentParser:
    """The options of a closed-loop comparison script: cases, seeds, days, margins, fit starts, ``--doc``."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--climates", default=",".join(CLIMATES))
    ap.add_argument("--seasons", default=",".join(SEASONS))
    ap.add_argument("--seeds", type=int, default=seeds)
    ap.add_argument("--days", type=int, default=2)
    ap.add_argument(
        "--margins",
        default=",".join(f"{m:g}" for m in MARGINS),
        help="how far inside the band the MPC aims, K",
    )
    ap.add_argument("--starts", default="auto", help="rczone fit --starts")
    ap.add_argument("--doc", type=Path, help="write the tables of <out>'s runs into this page and stop")
    return ap


def open_store(
    a: argparse.Namespace, name: str, tables: Callable[[dict], str], markers: tuple[str, str]
) -> dict | None:
    """The runs recorded in ``<a.out>/name`` (none yet: empty); None once ``a.doc`` is given and its
    page's part between ``markers`` is written from them by ``tables``."""
    path = a.out / name
    store = json.loads(path.read_text()) if path.exists() else {"fits": [], "runs": []}
    if a.doc:
        eq2.write_doc(a.doc, tables(store), markers=markers)
        return None
    a.out.mkdir(parents=True, exist_ok=True)
    return store


def main(argv: list[str] | None = None) -> int:
    a = loop_parser(__doc__.splitlines()[0], seeds=3).parse_args(argv)
    store = open_store(a, "energyplus_q1.json", table, (BEGIN, END))
    if store is None:
        return 0
    for weather in a.climates.split(","):
        for season in a.seasons.split(","):
            run_case(a.out, store, (weather, season), a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
