"""The multi-zone question on EnergyPlus, in prediction: a joint floor model or single zones (issue 35).

Usage::

    python validation/energyplus_multizone.py [--out validation-output] [--climates usa_il_chicago,usa_az_phoenix]
        [--seasons winter,summer] [--doc docs/energyplus.md]

For each climate and season, on the single floor of the small office (:data:`BUILDING`, five zones),
``rczone emulate --test normal`` writes two trends (:data:`SEASONS`): ``calibration``, two weekdays of
the building's own control, and ``heldout``, Q2's five held-out days (``validation/energyplus_q2.py``:
a Sunday, which only warms the filters up, then four weekdays). On the calibration days ``rczone fit``
(ML, the default search) identifies

* ``joint``: the floor's joint model (``rczone models generate --from building.toml --floor``: every
  zone's air and mass, the walls between the zones, the attic and outdoors as measured boundaries),
  fitted on ``floor<N>.columns.toml``;
* ``single``: for each zone, the paper's second-order model with the conductance-weighted mean of its
  neighbours' *measured* air temperatures as ``Tsd`` (``<zone>.columns.toml``).

Each is scored on ``heldout`` by :func:`rczone.score_horizons` at 1 h, 6 h and open loop, per zone,
with persistence beside it. The joint model predicts all zones together from what is measured off
the floor (outdoors, the attic, each zone's supply air and metered power); each single-zone model is
given its neighbours' measured temperatures over the whole horizon, information a predictor of the
floor would not have (it would have to predict them). Every fit is appended to
``<out>/energyplus_multizone.json`` as it finishes; :func:`table` makes the page's tables from it,
and a test keeps docs/energyplus.md's equal to :func:`table` of ``validation/energyplus_multizone.json``.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012 (a zone's neighbours as inputs).
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 16.6 (model validation on fresh data).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import tomllib
from pathlib import Path

from rczone.cli.main import main as rczone
from rczone.files.atomic import write_json_atomic, write_text_atomic


def _q2():
    """``validation/energyplus_q2.py`` (the scripts live outside the package)."""
    spec = importlib.util.spec_from_file_location(
        "energyplus_q2", Path(__file__).with_name("energyplus_q2.py")
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


Q2 = _q2()
BUILDING, FLOOR = "office_small", 1
CLIMATES, STEP_MIN, WARMUP = Q2.CLIMATES, Q2.STEP_MIN, Q2.WARMUP
#: Season -> first day (MM-DD of 2017) of each period: two weekdays (Tuesday, Wednesday) to fit on,
#: the joint fit's cost being about proportional to the samples (``bench/energyplus.py --only floor``
#: fits the same two January days), and Q2's held-out days.
SEASONS = {
    "winter": {"calibration": "01-17", "heldout": Q2.SEASONS["winter"]["heldout"]},
    "summer": {"calibration": "07-18", "heldout": Q2.SEASONS["summer"]["heldout"]},
}
#: Period -> (days, sensor seed).
PERIODS = {"calibration": (2, 1), "heldout": (Q2.PERIODS["heldout"][0], Q2.PERIODS["heldout"][2])}
HORIZONS = "4,24,open"
SHOWN = ("1 h", "6 h", "open")
#: The lines of docs/energyplus.md between which ``--doc`` writes :func:`table`.
BEGIN, END = "<!-- energyplus_multizone.py: begin -->", "<!-- energyplus_multizone.py: end -->"


def _emulate(folder: Path, building: str, weather: str, season: str, period: str) -> dict | None:
    """Run one period in EnergyPlus unless its trend exists; its times, or None when reused."""
    if (folder / "trend.csv").exists():
        return None
    days, seed = PERIODS[period]
    args = ["emulate", "--building", building, "--weather", weather, "--start", SEASONS[season][period]]
    args += ["--days", str(days), "--step", str(STEP_MIN), "--test", "normal", "--seed", str(seed), "-q"]
    t0 = Q2._clock()
    if rczone([*args, "-o", str(folder)]) != 0:
        raise SystemExit(f"rczone emulate failed: {weather} {season} {period}")
    return {
        "building": building, "climate": weather, "season": season, "period": period, "days": days, **Q2._since(t0)
    }  # fmt: skip


def floor_zones(building: dict, floor: int = FLOOR) -> list[dict]:
    """The conditioned zones of ``floor`` in the building file, in its order."""
    return [z for z in building["zones"] if z.get("floor") == floor and z.get("conditioned")]


def _fit(trend: Path, columns: Path, model: str, out: Path, extra: list[str]) -> tuple[dict, Path, dict]:
    """``rczone fit`` (ML, default search): its JSON, the saved model and the times; reused when done."""
    saved, report, times = out / "model.json", out / "fit.json", out / "time.json"
    if not (saved.exists() and report.exists() and times.exists()):
        out.mkdir(parents=True, exist_ok=True)
        args = ["fit", str(trend), "--columns", str(columns), "--model", model, "--no-profiles", *extra]
        t0 = Q2._clock()
        code = rczone([*args, "--save-model", str(saved), "--json", str(report)])
        if code not in (0, 3):
            raise SystemExit(f"rczone fit failed on {trend} with {model} (exit {code})")
        write_json_atomic(times, Q2._since(t0))
    return json.loads(report.read_text()), saved, json.loads(times.read_text())


def scores(model: Path, heldout: Path, columns: str, outputs: dict[str, str]) -> dict:
    """Held-out RMSE per zone, horizon and predictor (model, persistence), and the model's coverage.

    ``outputs`` maps the model's output names to zone names.
    """
    import rczone as rz

    s = rz.score_horizons(
        str(model), heldout / "trend.csv", columns=heldout / columns, horizons=HORIZONS, baselines=True,
        warmup=WARMUP,
    )  # fmt: skip
    rows: dict = {}
    for r in s.table.itertuples():
        if r.predictor not in ("model", "persistence"):
            continue
        h = Q2.LABELS[None if r.steps != r.steps else int(r.steps)]
        stable = bool(r.stable) and r.predictor not in s.unstable
        zone = rows.setdefault(outputs[r.output], {}).setdefault(h, {})
        zone[r.predictor] = float(r.rmse_K) if stable else None
        if r.predictor == "model":
            zone["coverage"] = float(r.coverage_2sigma)
    return rows


def _record(
    fit: dict, weather: str, season: str, kind: str, zone: str | None, held: dict, time: dict
) -> dict:
    return {
        "climate": weather, "season": season, "model": kind, "zone": zone,
        "exit_code": fit["exit_code"], "reasons": fit["verdict"]["reasons"],
        "n_free": len(fit["parameters"]), "at_bound": sum(bool(p["at_bound"]) for p in fit["parameters"].values()),
        "one_step_rmse_K": fit["rmse_K"], "open_loop_rmse_K": fit["open_loop_rmse_K"],
        "heldout": held, "fit_time": time,
    }  # fmt: skip


def run_case(
    out: Path, weather: str, season: str, building: str = BUILDING, floor: int = FLOOR
) -> tuple[list[dict], list[dict]]:
    """Emulate one climate and season; fit the joint floor model and each zone's; score all on heldout."""
    name = f"{weather}_{season}" if building == BUILDING else f"{building}_floor{floor}_{weather}_{season}"
    case = out / name
    runs = [_emulate(case / p, building, weather, season, p) for p in PERIODS]
    cal, held = case / "calibration", case / "heldout"
    rooms = floor_zones(tomllib.loads((cal / "building.toml").read_text()), floor)
    from rczone.emulators.floor import alias

    floor_file = case / "joint" / f"floor{floor}.toml"
    if not floor_file.exists():
        floor_file.parent.mkdir(parents=True, exist_ok=True)
        gen = ["models", "generate", "--from", str(cal / "building.toml"), "--floor", str(floor)]
        if rczone([*gen, "-o", str(floor_file)]) != 0:
            raise SystemExit(f"rczone models generate failed on {cal}")
    columns = f"floor{floor}.columns.toml"
    fit, model, time = _fit(cal / "trend.csv", cal / columns, str(floor_file), case / "joint", [])
    joint = scores(model, held, columns, {f"T{alias(z['name'])}": z["name"] for z in rooms})
    rows = [_record(fit, weather, season, "joint", None, joint, time)]
    for z in rooms:
        extra = ["--floor-area", str(z["floor_area"])]
        cols = f"{z['name']}.columns.toml"
        fit, model, time = _fit(cal / "trend.csv", cal / cols, "second-order", case / z["name"], extra)
        one = scores(model, held, cols, {"Ti": z["name"]})
        rows.append(_record(fit, weather, season, "single", z["name"], one, time))
    rows = [{"building": building, "floor": floor, **r} for r in rows]
    return rows, [r for r in runs if r is not None]


def _verdict(r: dict) -> str:
    return (
        "trustworthy (0)"
        if r["exit_code"] == 0
        else f"flagged ({r['exit_code']}), {len(r['reasons'])} reasons"
    )


def _rmse(x: float | dict) -> str:
    """A fit's RMSE on its data (per output for the joint model: their range)."""
    if isinstance(x, dict):
        v = [float(y) for y in x.values()]
        return f"{min(v):.2f} to {max(v):.2f}"
    return f"{x:.2f}"


def _cases(results: list[dict]) -> dict[tuple, dict]:
    """(building, floor, climate, season) -> {"joint": record, "single": {zone: record}}, in the order of CLIMATES and SEASONS."""

    def order(k: tuple) -> tuple:
        climate = CLIMATES.index(k[2]) if k[2] in CLIMATES else len(CLIMATES)
        return (
            k[0] != BUILDING,
            k[:2],
            climate,
            list(SEASONS).index(k[3]) if k[3] in SEASONS else len(SEASONS),
        )

    cases: dict[tuple, dict] = {}
    for r in results:
        key = (r.get("building", BUILDING), r.get("floor", FLOOR), r["climate"], r["season"])
        c = cases.setdefault(key, {"joint": None, "single": {}})
        if r["model"] == "joint":
            c["joint"] = r
        else:
            c["single"][r["zone"]] = r
    return {k: cases[k] for k in sorted(cases, key=order)}


def table(results: list[dict]) -> str:
    """The page's tables: held-out RMSE per zone (joint, single, persistence), the fits, a line per case."""
    pred = (
        "| climate | season | zone | RMSE K 1 h: joint / single / persistence | 6 h | open loop | "
        "2σ coverage open loop: joint / single | single-zone fit verdict |\n|---|---|---|---|---|---|---|---|\n"
    )
    fits = (
        "| climate | season | model | fit verdict | free parameters (at a bound) | calibration RMSE K: "
        "one step / open loop | fit CPU s (wall) |\n|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for (building, floor, climate, season), c in _cases(results).items():
        joint = c["joint"]
        for zone, single in c["single"].items():
            j = joint["heldout"][zone] if joint else None
            s = single["heldout"][zone]
            cells = [
                " / ".join(
                    Q2._f(x) for x in (j[h]["model"] if j else None, s[h]["model"], s[h]["persistence"])
                )
                for h in SHOWN
            ]
            cover = " / ".join("-" if x is None else f"{100 * x['open']['coverage']:.0f} %" for x in (j, s))
            pred += (
                f"| {climate} | {season} | {zone} | {' | '.join(cells)} | {cover} | {_verdict(single)} |\n"
            )
        for r in ([joint] if joint else []) + list(c["single"].values()):
            who = (
                f"{building} floor {floor}, joint" if r["model"] == "joint" else f"{r['zone']}, second-order"
            )
            t = r["fit_time"]
            fits += (
                f"| {climate} | {season} | {who} | {_verdict(r)} | {r['n_free']} ({r['at_bound']}) | "
                f"{_rmse(r['one_step_rmse_K'])} / {_rmse(r['open_loop_rmse_K'])} | {t['cpu_s']:.0f} ({t['wall_s']:.0f}) |\n"
            )
        if joint and c["single"]:
            lines.append(compare(f"{building} floor {floor}, {climate}", season, joint, c["single"]))
    return pred + "\n" + fits + ("\n" + "\n".join(lines) + "\n" if lines else "")


def compare(where: str, season: str, joint: dict, single: dict[str, dict]) -> str:
    """One line per case: the zones' mean held-out RMSE of each predictor, and where the joint model wins."""
    zones = list(single)

    def mean(get) -> str:
        v = [get(z) for z in zones]
        return "unstable" if any(x is None for x in v) else f"{sum(v) / len(v):.2f}"

    parts, wins = [], []
    for h in SHOWN:
        j = mean(lambda z, h=h: joint["heldout"][z][h]["model"])
        s = mean(lambda z, h=h: single[z]["heldout"][z][h]["model"])
        p = mean(lambda z, h=h: single[z]["heldout"][z][h]["persistence"])
        parts.append(f"{h} {j} / {s} / {p}")
        better = sum(
            joint["heldout"][z][h]["model"] is not None
            and (single[z]["heldout"][z][h]["model"] is None
                 or joint["heldout"][z][h]["model"] < single[z]["heldout"][z][h]["model"])
            for z in zones
        )  # fmt: skip
        wins.append(f"{better} at {h}")
    trusted = sum(r["exit_code"] == 0 for r in single.values())
    return (
        f"- {where}, {season}: mean held-out RMSE over the {len(zones)} zones, joint / single / persistence (K): "
        f"{'; '.join(parts)}; the joint model better than the single zone in {', '.join(wins)} of {len(zones)} zones; "
        f"fits trustworthy: joint {'yes' if joint['exit_code'] == 0 else 'no'}, single {trusted} of {len(zones)}"
    )


def in_doc(text: str) -> str:
    """The part of a page between :data:`BEGIN` and :data:`END` (what ``--doc`` wrote)."""
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise ValueError(f"the page needs one line {BEGIN!r} and one line {END!r}")
    return text.split(BEGIN + "\n", 1)[1].split(END, 1)[0]


def write_doc(page: Path, results: list[dict]) -> None:
    """Replace the tables between the page's markers by :func:`table` of the runs."""
    text = page.read_text()
    old = in_doc(text)
    write_text_atomic(page, text.replace(BEGIN + "\n" + old + END, BEGIN + "\n" + table(results) + END))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument("--climates", default=",".join(CLIMATES))
    ap.add_argument("--seasons", default=",".join(SEASONS))
    ap.add_argument("--building", default=BUILDING, help="an office prototype of rczone emulate")
    ap.add_argument("--floor", type=int, default=FLOOR, help="its floor (1 the lowest)")
    ap.add_argument("--doc", type=Path, help="write the tables of <out>'s runs into this page and stop")
    a = ap.parse_args(argv)
    store, times = a.out / "energyplus_multizone.json", a.out / "energyplus_multizone_emulate.json"
    if a.doc:
        write_doc(a.doc, json.loads(store.read_text()))
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    for season in a.seasons.split(","):
        for weather in a.climates.split(","):
            done = json.loads(store.read_text()) if store.exists() else []
            key = (a.building, a.floor, weather, season)
            if any(
                (r.get("building", BUILDING), r.get("floor", FLOOR), r["climate"], r["season"]) == key
                for r in done
            ):
                continue
            rows, runs = run_case(a.out, weather, season, a.building, a.floor)
            results = (
                json.loads(store.read_text()) if store.exists() else []
            ) + rows  # another process may add
            emulations = (json.loads(times.read_text()) if times.exists() else []) + runs
            write_json_atomic(store, results)
            write_json_atomic(times, emulations)
            write_text_atomic(a.out / "energyplus_multizone.md", table(results))
            done_now = f"- {a.building} floor {a.floor}, {weather}, {season}:"
            print(next(x for x in table(results).splitlines() if x.startswith(done_now)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
