"""The paper's question in closed loop: which model, from which data, with which estimator, is good enough for MPC.

Usage::

    python validation/closed_loop_study.py [--out validation-output/closed_loop] [--days 1] [--seeds 1,2,3]
                                           [--figures docs/figures] [--harder]

Fits the paper's models on the virtual building's nights (the 2-state reduced model of the paper,
free ``Cr`` and ``Rw``, by ML and LS on the forced night C and on the closed-loop night A; the
1-state model by ML on C), takes the construction values of the 13-state and 2-state models, and
runs ``rczone control-test`` for each model x estimator (with and without the disturbance
estimate) x scenario (summer, winter, summer under a time-of-use price) x seed, against the
building's own thermostat on the same days. Every run is appended to
``<out>/runs.jsonl`` as it finishes (a rerun skips those already there); prints the table of
docs/paper.md section 3 as Markdown and draws ``closed_loop_study.png``. About 45 minutes on one
core with the defaults (the 13-state MPC takes a minute or more per day).

``--harder``: the scenarios where the model should matter most, summer with a tight comfort band
(0.8 K occupied) and summer with a demand-response event (10x price from 2 pm to 4 pm, announced
at 11 am), with a reduced design: the 13-state and 2-state construction values, the 2-state ML
fits on C and on A, the 1-state ML fit on C, each with and without the disturbance estimate.
Output in ``<out>_harder``, figure ``closed_loop_harder.png``, and a second table of the event
(its energy, peak flow and discomfort). About 15 minutes of CPU with the defaults.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from rczone import datasets
from rczone.calibration import calibrate
from rczone.control.closedloop import closed_loop_test
from rczone.control.virtualplant import VirtualPlant
from rczone.models import load_model

#: scenario -> (season, price, comfort band)
SCENARIOS = {
    "summer": ("summer", "flat", "normal"),
    "winter": ("winter", "flat", "normal"),
    "summer, time-of-use": ("summer", "tou", "normal"),
}
HARDER = {
    "summer, tight band": ("summer", "flat", "tight"),
    "summer, DR event": ("summer", "dr", "normal"),
}
#: The reduced design of ``--harder`` (all with and without the disturbance estimate).
HARDER_MODELS = (
    "13-state, construction",
    "2-state, construction",
    "2-state, ML on C (forced)",
    "2-state, ML on A (closed loop)",
    "1-state, ML on C (forced)",
)


def models(only=None) -> dict[str, object]:
    """The models compared: construction values and fits (n_starts=1 from the construction values)."""
    c, a = datasets.load("C"), datasets.load("A")

    def fit(name, frame, method):
        return lambda: calibrate(name, frame, method=method, n_starts=1, uncertainty=False).model

    makers = {
        "13-state, construction": lambda: load_model("full-scale"),
        "2-state, construction": lambda: load_model("second-order-paper"),
        "2-state, ML on C (forced)": fit("second-order-paper", c, "ml"),
        "2-state, LS on C (forced)": fit("second-order-paper", c, "ls"),
        "2-state, ML on A (closed loop)": fit("second-order-paper", a, "ml"),
        "2-state, LS on A (closed loop)": fit("second-order-paper", a, "ls"),
        "1-state, ML on C (forced)": fit("first-order", c, "ml"),
    }
    return {k: make() for k, make in makers.items() if only is None or k in only}


#: Variants run without the disturbance estimate too (the others only with it).
WITHOUT_DISTURBANCE = ("2-state, ML on C (forced)", "13-state, construction")


def runs(names, seeds, scenarios=SCENARIOS, without=WITHOUT_DISTURBANCE):
    """Every (model or "thermostat", disturbance, scenario, seed) of the study."""
    for scen in scenarios:
        for seed in seeds:
            yield "thermostat", None, scen, seed
            for name in names:
                yield name, True, scen, seed
                if name in without:
                    yield name, False, scen, seed


def key(row) -> str:
    return f"{row['variant']}|{row['disturbance']}|{row['scenario']}|{row['seed']}"


def run_all(out: Path, days: float, seeds: list[int], harder: bool = False) -> list[dict]:
    out.mkdir(parents=True, exist_ok=True)
    log = out / "runs.jsonl"
    done = {key(r): r for r in map(json.loads, log.read_text().splitlines())} if log.exists() else {}
    zms = models(HARDER_MODELS if harder else None)
    thermostat_model = zms["2-state, ML on C (forced)"]
    scenarios = HARDER if harder else SCENARIOS
    plan = runs(list(zms), seeds, scenarios, HARDER_MODELS if harder else WITHOUT_DISTURBANCE)
    for variant, dist, scen, seed in plan:
        row = {"variant": variant, "disturbance": dist, "scenario": scen, "seed": seed}
        if key(row) in done:
            continue
        season, price, band = scenarios[scen]
        t0, c0 = time.perf_counter(), time.process_time()
        r = closed_loop_test(
            VirtualPlant(season, days=days, seed=seed, price=price, comfort_band=band),
            "naive" if variant == "thermostat" else "mpc",
            model=thermostat_model if variant == "thermostat" else zms[variant],
            disturbance=bool(dist),
        )
        row.update(r.scores, wall_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0, days=days)
        with log.open("a") as f:
            f.write(json.dumps(row) + "\n")
        done[key(row)] = row
        print(
            f"{variant:32s} dist={dist!s:5s} {scen:20s} seed {seed}: E {row['energy_kWh']:.2f} kWh,"
            f" cost {row['cost']:.2f}, comfort {row['comfort_Kh']:.2f} K h",
            flush=True,
        )
    return list(done.values())


def table(rows: list[dict], scenarios=SCENARIOS) -> str:
    """Markdown: per variant and scenario, mean and spread over seeds, savings against the thermostat."""
    seeds = sorted({r["seed"] for r in rows})
    lines = [
        f"| variant | disturbance estimate | {' | '.join(f'{s}: cost (saving) / comfort K h' for s in scenarios)} |",
        "|---|---|" + "---|" * len(scenarios),
    ]
    variants = list(dict.fromkeys((r["variant"], r["disturbance"]) for r in rows))
    for v, d in variants:
        cells = []
        for scen in scenarios:
            sel = [r for r in rows if (r["variant"], r["disturbance"], r["scenario"]) == (v, d, scen)]
            ref = {r["seed"]: r for r in rows if r["variant"] == "thermostat" and r["scenario"] == scen}
            if len(sel) < len(seeds):
                cells.append("-")
                continue
            cost = np.array([r["cost"] for r in sel])
            save = np.array([1 - r["cost"] / ref[r["seed"]]["cost"] for r in sel])
            comfort = np.array([r["comfort_Kh"] for r in sel])
            cells.append(
                f"{cost.mean():.2f} ({100 * save.mean():+.0f} % ± {100 * save.std():.0f}) /"
                f" {comfort.mean():.2f} ± {comfort.std():.2f}"
            )
        dist = "" if d is None else ("yes" if d else "no")
        lines.append(f"| {v} | {dist} | {' | '.join(cells)} |")
    return "\n".join(lines)


def event_table(rows: list[dict], scen: str = "summer, DR event") -> str:
    """Markdown: the demand-response event itself, mean ± standard deviation over seeds."""
    cols = ("event_energy_kWh", "event_peak_flow_kg_s", "event_comfort_Kh", "energy_kWh", "comfort_Kh")
    lines = [
        "| variant | disturbance estimate | event energy kWh | event peak flow kg/s | event discomfort K h"
        " | day's energy kWh | day's discomfort K h |",
        "|---|---|---|---|---|---|---|",
    ]
    for v, d in dict.fromkeys((r["variant"], r["disturbance"]) for r in rows):
        sel = [r for r in rows if (r["variant"], r["disturbance"], r["scenario"]) == (v, d, scen)]
        if not sel:
            continue
        cells = []
        for c in cols:
            x = np.array([r[c] for r in sel])
            f = ".3f" if "flow" in c else ".2f"
            cells.append(f"{x.mean():{f}} ± {x.std():{f}}")
        dist = "" if d is None else ("yes" if d else "no")
        lines.append(f"| {v} | {dist} | {' | '.join(cells)} |")
    return "\n".join(lines)


def figure(rows: list[dict], path: Path, scenarios=SCENARIOS) -> None:
    from matplotlib.figure import Figure

    variants = [v for v in dict.fromkeys((r["variant"], r["disturbance"]) for r in rows)]
    fig = Figure(figsize=(10, 5.2))
    axes = fig.subplots(1, len(scenarios), sharey=True)
    for ax, scen in zip(axes, scenarios):
        for i, (v, d) in enumerate(variants):
            sel = [r for r in rows if (r["variant"], r["disturbance"], r["scenario"]) == (v, d, scen)]
            x = [r["cost"] for r in sel]
            y = [r["comfort_Kh"] for r in sel]
            label = v + ("" if d in (None, True) else ", no disturbance")
            ax.scatter(x, y, s=18, marker="os^vD<>p*hXP"[i % 12], label=label)
        ax.set_title(scen, fontsize=10)
        ax.set_xlabel("cost (kWh, price-weighted)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("discomfort (K h, occupied)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.tight_layout(rect=(0, 0.16, 1, 1))
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=7)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def _kwh(series, window) -> float:
    return float(series["power_W"][window].sum() * 60 / 3.6e6)


def event_figure(path: Path, seed: int = 1, days: float = 1.0) -> str:
    """Room temperature and flow around the demand-response event, one seed; returns a Markdown table.

    The thermostat, and the MPC with the 2-state ML fit on C and with the 13-state model, under
    the event and (the 2-state MPC) under the flat price on the same day: the energy before the
    event (11 am to 2 pm, after its announcement) and during it shows what is shifted.
    """
    from matplotlib.figure import Figure

    from rczone.control.signals import DR_HOURS, DR_NOTICE

    zms = models(("2-state, ML on C (forced)", "13-state, construction"))
    two = zms["2-state, ML on C (forced)"]
    cases = {
        "thermostat": (two, "naive", "dr"),
        "MPC, 2-state ML on C, flat price": (two, "mpc", "flat"),
        "MPC, 2-state ML on C, DR event": (two, "mpc", "dr"),
        "MPC, 13-state, DR event": (zms["13-state, construction"], "mpc", "dr"),
    }
    fig = Figure(figsize=(9, 6))
    ax_t, ax_m = fig.subplots(2, 1, sharex=True)
    hour = 3600.0
    lines = [
        f"| run (seed {seed}) | energy 11 am-2 pm kWh | energy 2-4 pm kWh | peak flow 2-4 pm kg/s"
        " | Ti at 2 pm degC |",
        "|---|---|---|---|---|",
    ]
    for label, (zm, ctrl, price) in cases.items():
        r = closed_loop_test(VirtualPlant("summer", days=days, seed=seed, price=price), ctrl, model=zm)
        t, s = r.t, r.series
        pre = (t >= DR_HOURS[0] - DR_NOTICE) & (t < DR_HOURS[0])
        ev = (t >= DR_HOURS[0]) & (t < DR_HOURS[1])
        ti_start = s["Ti"][np.searchsorted(t, DR_HOURS[0])]
        lines.append(
            f"| {label} | {_kwh(s, pre):.2f} | {_kwh(s, ev):.2f} | {s['m'][ev].max():.3f} | {ti_start:.2f} |"
        )
        win = (t >= 14 * hour) & (t <= 24 * hour)
        clock = 18 + t[win] / hour - 24
        ax_t.plot(clock, s["Ti"][win], lw=1, label=label)
        ax_m.plot(clock, s["m"][win], lw=1, label=label)
        band_lo, band_hi = s["lower"][win], s["upper"][win]
    ax_t.plot(clock, band_lo, "k--", lw=0.7)
    ax_t.plot(clock, band_hi, "k--", lw=0.7, label="comfort band")
    for ax in (ax_t, ax_m):
        ax.axvspan(14, 16, color="0.85", zorder=0)
        ax.axvline(11, color="0.5", lw=0.7, ls=":")
        ax.grid(alpha=0.3)
    ax_t.set_ylabel("room air (degC)")
    ax_m.set_ylabel("supply flow (kg/s)")
    ax_m.set_xlabel("hour of day (event shaded, announced at 11 am)")
    ax_t.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("validation-output") / "closed_loop")
    ap.add_argument("--figures", type=Path, default=Path("docs") / "figures")
    ap.add_argument("--days", type=float, default=1.0)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--harder", action="store_true", help="the tight-band and demand-response scenarios")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    if args.harder:
        out = args.out.with_name(args.out.name + "_harder")
        rows = run_all(out, args.days, seeds, harder=True)
        print(table(rows, HARDER))
        print()
        print(event_table(rows))
        figure(rows, args.figures / "closed_loop_harder.png", HARDER)
        print()
        print(event_figure(args.figures / "closed_loop_dr_event.png", seeds[0], args.days))
        return
    rows = run_all(args.out, args.days, seeds)
    print(table(rows))
    figure(rows, args.figures / "closed_loop_study.png")


if __name__ == "__main__":
    main()
