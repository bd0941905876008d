"""The paper's Q2 on EnergyPlus: normal-operation data against a forced-response test (issue 35).

Usage::

    python validation/energyplus_q2.py [--out validation-output] [--climates usa_il_chicago,usa_az_phoenix]
        [--seasons winter,summer] [--starts auto] [--replicates 1]

For each climate and season, on one perimeter zone of the medium office (:data:`ZONE`, the zone of
the closed-loop section), ``rczone emulate`` writes three trends (:data:`PERIODS`): ``calibration``,
five weekdays of the building's own control; ``forced``, a 3-day forced-response test of the zone
(``--test forced``, the thermostat schedule ``rczone design`` makes); ``heldout``, five later days of
normal operation (a Sunday, which only warms the filter up, then four weekdays). ``rczone fit`` (ML,
``--starts``, the zone's floor area from ``building.toml``) identifies the paper's second-order model
once from ``calibration`` and once from ``forced``; :func:`rczone.score_horizons` scores each fit on
``heldout`` at 15 min, 1 h, 6 h and open loop with the persistence and ARX baselines, and
:func:`rczone.postfit.evidence.held_out_evidence` gives its held-out checks. Every fit is appended to
``<out>/energyplus_q2.json`` as it finishes. ``--replicates N`` repeats every case with the sensor noise
drawn from other seeds (:data:`REPLICATE_SEED`; EnergyPlus itself is deterministic, so a replicate
changes only what the sensors add); the detailed tables show the first, :func:`spread` the range over
all. The tables (:func:`table`) go to
``<out>/energyplus_q2.md``. The runs of docs/energyplus.md are ``validation/energyplus_q2.json``; a
test keeps the page's tables equal to :func:`table` of them.

References
----------
.. [1] S. F. Fux, A. Ashouri, M. J. Benz, L. Guzzella, "EKF based self-adaptive thermal model for a
   passive house", Energy and Buildings 68, 2014 (closed-loop data and identifiability).
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   sections 13.4 (identification in closed loop) and 16.6 (model validation).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
import tomllib
from pathlib import Path

from rczone.cli.main import main as rczone
from rczone.files.atomic import write_text_atomic

BUILDING, ZONE = "office_medium", "Perimeter_mid_ZN_1"
CLIMATES = ("usa_il_chicago", "usa_az_phoenix")
#: Season -> first day (MM-DD of 2017, whose typical year starts on a Sunday) of each period.
SEASONS = {
    "winter": {"calibration": "01-09", "forced": "01-16", "heldout": "01-22"},
    "summer": {"calibration": "07-10", "forced": "07-17", "heldout": "07-23"},
}
#: Period -> (days, test, sensor seed).
PERIODS = {"calibration": (5, "normal", 1), "forced": (3, "forced", 2), "heldout": (5, "normal", 3)}
STEP_MIN, WARMUP, HORIZONS = 15, "1d", "1,4,24,open"
#: Replicate r draws the sensor noise of each period with its seed + r times this.
REPLICATE_SEED = 10
#: Horizon labels of the tables, by steps ahead (None: open loop).
LABELS = {1: "15 min", 4: "1 h", 24: "6 h", None: "open"}
PARAMS = ("Cr", "Cw", "Rwin", "R1", "R2")
#: The lines of docs/energyplus.md between which ``--doc`` writes :func:`table`.
BEGIN, END = "<!-- energyplus_q2.py: begin -->", "<!-- energyplus_q2.py: end -->"
#: A robust relative standard error at or above this leaves an estimate undetermined (the verdict's).
SE_MAX = 1.0


def _clock() -> tuple[float, float]:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return time.perf_counter(), r.ru_utime + r.ru_stime


def _since(t0: tuple[float, float]) -> dict:
    wall, cpu = _clock()
    return {"wall_s": round(wall - t0[0], 1), "cpu_s": round(cpu - t0[1], 1), "load": os.getloadavg()[0]}


def _emulate(folder: Path, weather: str, season: str, period: str, replicate: int) -> dict | None:
    """Run one period in EnergyPlus unless its trend exists; its times, or None when reused."""
    if (folder / "trend.csv").exists():
        return None
    days, test, seed = PERIODS[period]
    seed += REPLICATE_SEED * replicate
    args = ["emulate", "--building", BUILDING, "--weather", weather, "--start", SEASONS[season][period]]
    args += ["--days", str(days), "--step", str(STEP_MIN), "--test", test, "--seed", str(seed), "-q"]
    args += ["--zones", ZONE] if test == "forced" else []
    t0 = _clock()
    if rczone([*args, "-o", str(folder)]) != 0:
        raise SystemExit(f"rczone emulate failed: {weather} {season} {period}")
    return {
        "climate": weather, "season": season, "period": period, "days": days, "seed": seed, **_since(t0)
    }  # fmt: skip


def reference(building: dict) -> dict:
    """What EnergyPlus's constructions say of the zone's R and C (``building.toml`` of the emulation).

    ``Rwin`` is one over the zone's exterior ``U x A`` (walls and windows, with film coefficients;
    without infiltration, which adds a conductance to outdoors), ``R1 + R2`` one over the ``U x A`` it
    shares with the neighbours that make its ``Tsd``, ``Cr_air`` the heat capacity of its air
    (1.2 kg/m3, 1005 J/(kg K); the furnishings EnergyPlus does not lump into the air are not in it).
    """
    zone = next(z for z in building["zones"] if z["name"] == ZONE)
    shared = sum(a["ua"] for a in building["adjacency"] if ZONE in (a["a"], a["b"]))
    return {
        "floor_area_m2": zone["floor_area"],
        "Rwin": 1 / zone["exterior_ua"],
        "R1+R2": 1 / shared,
        "Cr_air": 1.2 * 1005 * zone["volume"],
    }


def _fit(
    folder: Path, out: Path, starts: str, *, model_name: str = "second-order"
) -> tuple[dict, Path, dict]:
    """``rczone fit`` of the zone on one trend: its JSON, the saved model and the times."""
    area = reference(tomllib.loads((folder / "building.toml").read_text()))["floor_area_m2"]
    model, report = out / "model.json", out / "fit.json"
    args = ["fit", str(folder / "trend.csv"), "--columns", str(folder / f"{ZONE}.columns.toml")]
    args += ["--model", model_name, "--starts", starts, "--floor-area", str(area), "--no-profiles"]
    t0 = _clock()
    code = rczone([*args, "--save-model", str(model), "--json", str(report)])
    if code not in (0, 3):
        raise SystemExit(f"rczone fit failed on {folder} (exit {code})")
    return json.loads(report.read_text()), model, _since(t0)


def _estimates(fit: dict) -> dict:
    """Each R and C: estimate, the Hessian's and the robust standard error, at a bound."""
    rows = {}
    for name in PARAMS:
        p, rob = fit["parameters"][name], fit["robust_std_errors"].get(name, {})
        rows[name] = {
            "estimate": p["estimate"],
            "std_error": p["std_error"],
            "robust_std_error": rob.get("robust"),
            "at_bound": bool(p["at_bound"]),
        }
    return rows


def _scores(model: Path, heldout: Path) -> tuple[dict, list[str], dict]:
    """Held-out RMSE per horizon and predictor, the model's coverage, the failed checks, the times."""
    import rczone as rz
    from rczone.postfit.evidence import held_out_evidence

    t0 = _clock()
    s = rz.score_horizons(
        str(model),
        heldout / "trend.csv",
        columns=heldout / f"{ZONE}.columns.toml",
        horizons=HORIZONS,
        baselines=True,
        warmup=WARMUP,
    )
    evidence = held_out_evidence(s)
    rows = {}
    for r in s.table.itertuples():
        h = LABELS[None if r.steps != r.steps else int(r.steps)]
        stable = bool(r.stable) and r.predictor not in s.unstable
        rows.setdefault(h, {})[r.predictor] = float(r.rmse_K) if stable else None
        if r.predictor == "model":
            rows[h]["coverage"] = float(r.coverage_2sigma)
    return rows, list(evidence.failed), _since(t0)


def run_case(
    out: Path, weather: str, season: str, starts: str, replicate: int = 0
) -> tuple[list[dict], list[dict]]:
    """Emulate one climate and season, fit on calibration and forced, score both on heldout."""
    case = out / (f"{weather}_{season}" + (f"_r{replicate}" if replicate else ""))
    emulations = [_emulate(case / p, weather, season, p, replicate) for p in PERIODS]
    rows = []
    for training in ("calibration", "forced"):
        fit, model, fit_time = _fit(case / training, case / f"fit_{training}", starts)
        scores, failed, score_time = _scores(model, case / "heldout")
        on_forced = _scores(model, case / "forced")[0]  # the paper's check; in sample for the forced fit
        rows.append(
            {
                "climate": weather,
                "season": season,
                "training": training,
                "replicate": replicate,
                "days": PERIODS[training][0],
                "starts": starts,
                "exit_code": fit["exit_code"],
                "trustworthy": fit["trustworthy"],
                "reasons": fit["verdict"]["reasons"],
                "one_step_rmse_K": fit["rmse_K"],
                "open_loop_rmse_K": fit["open_loop_rmse_K"],
                "estimates": _estimates(fit),
                "heldout": scores,
                "heldout_failed": failed,
                "on_forced": {h: on_forced[h]["model"] for h in ("6 h", "open")},
                "fit_time": fit_time,
                "score_time": score_time,
                "ua_W_per_K": fit["plausibility"]["ua_W_per_K"],
                "reference": reference(tomllib.loads((case / training / "building.toml").read_text())),
            }
        )
    return rows, [e for e in emulations if e is not None]


def _rc(e: dict) -> str:
    """An estimate with its robust relative standard error (the Hessian's when there is none)."""
    se = e["robust_std_error"] if e["robust_std_error"] is not None else e["std_error"]
    if e["at_bound"]:
        return f"{e['estimate']:.3g} (bound)"
    return (
        f"{e['estimate']:.3g} ±{100 * se / e['estimate']:.0f} %"
        if se is not None
        else f"{e['estimate']:.3g} (no SE)"
    )


def determined(e: dict) -> bool:
    """An estimate the data determine: off its bounds, robust relative standard error below 100 %."""
    se = e["robust_std_error"] if e["robust_std_error"] is not None else e["std_error"]
    return not e["at_bound"] and se is not None and se < SE_MAX * abs(e["estimate"])


def _f(x: float | None) -> str:
    return "unstable" if x is None else f"{x:.2f}"


def _prediction_row(r: dict) -> str:
    h = r["heldout"]
    verdict = (
        "trustworthy (0)"
        if r["exit_code"] == 0
        else f"flagged ({r['exit_code']}), {len(r['reasons'])} reasons"
    )
    cells = [
        " / ".join(_f(h[k].get(p)) for p in ("model", "persistence", "arx")) for k in ("1 h", "6 h", "open")
    ]
    cover = " / ".join(f"{100 * h[k]['coverage']:.0f} %" for k in ("1 h", "6 h", "open"))
    failed = ", ".join(r["heldout_failed"]) or "none"
    forced = _f(r["on_forced"]["open"]) + (" (own data)" if r["training"] == "forced" else "")
    return f"{_who(r)} {verdict} | {failed} | {' | '.join(cells)} | {cover} | {forced} |\n"


def _estimate_rows(r: dict) -> str:
    e, ref = r["estimates"], r["reference"]
    ok = ", ".join(p for p in PARAMS if determined(e[p])) or "none"
    row = f"{_who(r)} {' | '.join(_rc(e[p]) for p in PARAMS)} | {_sum_r(e):.3g} | {ok} |\n"
    if r["training"] != "calibration":
        return row
    cells = [f"{ref['Cr_air']:.3g} (air)", "", f"{ref['Rwin']:.3g}", "", "", f"{ref['R1+R2']:.3g}", ""]
    return f"| {r['climate']} | {r['season']} | EnergyPlus constructions | {' | '.join(cells)} |\n" + row


def _who(r: dict) -> str:
    return f"| {r['climate']} | {r['season']} | {r['training']} ({r['days']} d) |"


def _sum_r(e: dict) -> float:
    return e["R1"]["estimate"] + e["R2"]["estimate"]


def table(results: list[dict]) -> str:
    """The markdown tables of the fits (held-out prediction, estimates), a line per case, and the spread
    over the sensor-noise replicates when there are several."""
    pred = (
        "| climate | season | fitted on | fit verdict | held-out checks failed | RMSE K 1 h: model / persistence / ARX | "
        "6 h | open loop | 2σ coverage 1 h / 6 h / open | open loop on the forced test |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
    )
    est = "| climate | season | fitted on | Cr J/K | Cw J/K | Rwin K/W | R1 K/W | R2 K/W | R1 + R2 K/W | determined |\n"
    est += "|---|---|---|---|---|---|---|---|---|---|\n"
    results = sorted(results, key=_order)
    first = [r for r in results if r.get("replicate", 0) == 0]
    for r in first:
        pred += _prediction_row(r)
        est += _estimate_rows(r)
    lines = [compare(normal, forced) for normal, forced in _pairs(first)]
    text = pred + "\n" + est + "\n" + "\n".join(lines) + "\n"
    return text + (spread(results) if len(first) < len(results) else "")


def _order(r: dict) -> tuple:
    """Climates and seasons in the order of :data:`CLIMATES` and :data:`SEASONS`, then as recorded."""
    climate = CLIMATES.index(r["climate"]) if r["climate"] in CLIMATES else len(CLIMATES)
    season = list(SEASONS).index(r["season"]) if r["season"] in SEASONS else len(SEASONS)
    return climate, season, r.get("replicate", 0)


def spread(results: list[dict]) -> str:
    """Per case and training data, the range over the replicates of what the line per case compares."""
    head = (
        "\n| climate | season | fitted on | replicates | trustworthy | open-loop RMSE K | 6 h RMSE K | "
        "determined of 5 | Rwin / constructions | R1 + R2 / constructions |\n|---|---|---|---|---|---|---|---|---|---|\n"
    )
    groups: dict[tuple, list[dict]] = {}
    for r in results:
        groups.setdefault((r["climate"], r["season"], r["training"]), []).append(r)

    def span(values: list[float], fmt: str) -> str:
        lo, hi = min(values), max(values)
        return format(lo, fmt) if format(lo, fmt) == format(hi, fmt) else f"{lo:{fmt}} to {hi:{fmt}}"

    rows = []
    for (climate, season, training), rs in groups.items():
        ref = rs[0]["reference"]
        cells = [
            str(len(rs)),
            str(sum(r["exit_code"] == 0 for r in rs)),
            span([r["heldout"]["open"]["model"] for r in rs], ".2f"),
            span([r["heldout"]["6 h"]["model"] for r in rs], ".2f"),
            span([float(sum(determined(r["estimates"][p]) for p in PARAMS)) for r in rs], ".0f"),
            span([r["estimates"]["Rwin"]["estimate"] / ref["Rwin"] for r in rs], ".2g"),
            span([_sum_r(r["estimates"]) / ref["R1+R2"] for r in rs], ".2g"),
        ]
        rows.append(f"| {climate} | {season} | {training} | {' | '.join(cells)} |")
    return head + "\n".join(rows) + "\n"


def _pairs(results: list[dict]) -> list[tuple[dict, dict]]:
    by = {(r["climate"], r["season"], r["training"]): r for r in results}
    return [
        (r, by[k])
        for r in results
        if r["training"] == "calibration" and (k := (r["climate"], r["season"], "forced")) in by
    ]


def compare(normal: dict, forced: dict) -> str:
    """One line: which fit predicts the held-out days better, and how far their R and C lie apart."""
    o_n, o_f = normal["heldout"]["open"]["model"], forced["heldout"]["open"]["model"]
    s_n, s_f = normal["heldout"]["6 h"]["model"], forced["heldout"]["6 h"]["model"]
    best = "forced" if o_f < o_n else "normal"
    ratio = {p: forced["estimates"][p]["estimate"] / normal["estimates"][p]["estimate"] for p in PARAMS}
    apart = ", ".join(f"{p} x{v:.2g}" for p, v in ratio.items() if not 0.5 <= v <= 2) or "none"
    n_ok = sum(determined(normal["estimates"][p]) for p in PARAMS)
    f_ok = sum(determined(forced["estimates"][p]) for p in PARAMS)
    ref = normal["reference"]
    vs = "; ".join(
        f"{name} x{get(normal['estimates']) / ref[key]:.2g} vs x{get(forced['estimates']) / ref[key]:.2g}"
        for name, key, get in (
            ("Rwin", "Rwin", lambda e: e["Rwin"]["estimate"]),
            ("R1 + R2", "R1+R2", _sum_r),
        )
    )
    return (
        f"- {normal['climate']}, {normal['season']}: held-out open loop {o_n:.2f} K (normal-operation fit) vs "
        f"{o_f:.2f} K (forced-test fit), 6 h {s_n:.2f} vs {s_f:.2f} K: the {best} fit predicts better open loop; "
        f"R and C determined {n_ok} of {len(PARAMS)} vs {f_ok} of {len(PARAMS)}; "
        f"forced / normal estimate beyond a factor 2: {apart}; against EnergyPlus's constructions "
        f"(normal vs forced fit): {vs}; the normal fit on the forced test's last {PERIODS['forced'][0] - 1} days: "
        f"{normal['on_forced']['open']:.2f} K open loop (the forced fit on its own data: {forced['on_forced']['open']:.2f} K)"
    )


def in_doc(text: str, *, markers: tuple[str, str] = (BEGIN, END)) -> str:
    """The part of a page between the ``markers`` lines (default :data:`BEGIN`, :data:`END`: what ``--doc`` wrote)."""
    begin, end = markers
    if text.count(begin) != 1 or text.count(end) != 1:
        raise ValueError(f"the page needs one line {begin!r} and one line {end!r}")
    return text.split(begin + "\n", 1)[1].split(end, 1)[0]


def write_doc(page: Path, tables: str, *, markers: tuple[str, str] = (BEGIN, END)) -> None:
    """Replace what lies between the page's ``markers`` lines by ``tables``."""
    text, (begin, end) = page.read_text(), markers
    old = in_doc(text, markers=markers)
    write_text_atomic(page, text.replace(begin + "\n" + old + end, begin + "\n" + tables + end))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--climates", default=",".join(CLIMATES))
    ap.add_argument("--seasons", default=",".join(SEASONS))
    ap.add_argument("--starts", default="auto", help="rczone fit --starts")
    ap.add_argument("--replicates", type=int, default=1, help="sensor-noise replicates of every case")
    ap.add_argument("--doc", type=Path, help="write the tables of <out>'s runs into this page and stop")
    a = ap.parse_args(argv)
    if a.doc:
        write_doc(a.doc, table(json.loads((a.out / "energyplus_q2.json").read_text())))
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    store, times = a.out / "energyplus_q2.json", a.out / "energyplus_q2_emulate.json"
    results = json.loads(store.read_text()) if store.exists() else []
    emulations = json.loads(times.read_text()) if times.exists() else []
    plan = [
        (s, w, k) for k in range(a.replicates) for s in a.seasons.split(",") for w in a.climates.split(",")
    ]
    for season, weather, rep in plan:
        if any((r["climate"], r["season"], r.get("replicate", 0)) == (weather, season, rep) for r in results):
            continue
        rows, runs = run_case(a.out, weather, season, a.starts, rep)
        results = (json.loads(store.read_text()) if store.exists() else []) + rows  # another process may add
        emulations = (json.loads(times.read_text()) if times.exists() else []) + runs
        store.write_text(json.dumps(results, indent=1))
        times.write_text(json.dumps(emulations, indent=1))
        (a.out / "energyplus_q2.md").write_text(table(results))
        print(compare(*rows), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
