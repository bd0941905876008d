"""Drift detection on a virtual zone: detection delays and false alarms counted over seeds (issue 36).

Usage::

    python validation/drift_virtual.py [--seeds 20] [--first-seed 200] [--out validation-output]
        [--doc docs/validation.md] [--marker NAME]

The zone (truth by construction) is the one of ``tests/unit/calibration/test_drift.py``: TiTe
(``Ci`` 2 MJ/K, ``Ce`` 40 MJ/K, ``Rie`` 2 K/kW, ``Rea`` 10 K/kW), process noise 1e-3 K/sqrt(s) on
the room, 0.02 K sensor noise, 5-min samples, a PRBS heater and a daily outdoor cycle, simulated by
exact discretization. The model is the true one before any change. For each seed, three records
are scored as ``rczone predict --warmup 3d --conformal 1d --online --horizons 1,12`` does
(:func:`rczone.calibration.horizons.horizon_scores`):

* ``Rea`` halved from day 4 (7 days): drift found? the first alarm's delay after the change;
* a sensor bias of +1 K from day 4 (7 days): the same;
* nothing changed (13 days: ten days scored): any alarm is a false alarm.

The detector is rczone's (:mod:`rczone.calibration.drift`: a self-starting CUSUM whose decision
interval comes from its in-control run length); ``--cusum-h`` overrides the decision interval for a
trade-off study. Prints a Markdown table and the CPU time of the records' predictions, and writes
``<out>/drift_virtual.json``; with ``--doc`` also replaces the table between the markers
``<!-- drift-virtual:start -->`` and ``<!-- drift-virtual:end -->`` of that file (with
``--marker NAME``: ``<!-- drift-virtual-NAME:start -->`` ... ``<!-- drift-virtual-NAME:end -->``).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from tests.unit.calibration.test_drift import DAY, SIGMA_V, SIGMA_W, virtual_zone  # noqa: E402
from tests.unit.estimation.test_initial_state import MODEL  # noqa: E402

from rczone.calibration.conformal import ConformalSettings  # noqa: E402
from rczone.calibration.horizons import horizon_scores  # noqa: E402
from rczone.files.atomic import write_json_atomic, write_text_atomic  # noqa: E402
from rczone.models import ZoneModel, read_model_file  # noqa: E402

#: The records scored per seed: name, days, change.
CASES = (
    ("Rea halved from day 4", 7.0, {"rea_factor": 0.5}),
    ("sensor bias of 1 K from day 4", 7.0, {"bias_K": 1.0}),
    ("unchanged, ten days scored", 13.0, {}),
)
START = "<!-- drift-virtual:start -->"
END = "<!-- drift-virtual:end -->"


def true_model(folder: Path) -> ZoneModel:
    """The zone's model at its true values and noise levels."""
    (folder / "zone.toml").write_text(MODEL)
    zm = read_model_file(folder / "zone.toml")
    return zm.with_values(zm.theta, {"sigma_v": SIGMA_V, "sigma_w_Ti": SIGMA_W, "sigma_x0_Te": 2.0})


def one(model: ZoneModel, seed: int, days: float, change: dict) -> dict:
    """Score one record; whether and when drift was found."""
    frame = virtual_zone(seed, days=days, **change)
    settings = ConformalSettings(DAY, online=True)
    t0 = time.process_time()
    s = horizon_scores(
        model, frame, horizons=[1, 12], start=3 * DAY, parameters=False, baselines=False, conformal=settings
    )
    d = s.drift
    return {
        "seed": seed,
        "drifted": d.drifted,
        "detected_d": None if d.detected_s is None else d.detected_s / DAY,
        "since_d": None if d.since_s is None else d.since_s / DAY,
        "tests": sorted({sig.test for sig in d.signals}),
        "cpu_s": time.process_time() - t0,
    }


def markdown(results: dict) -> str:
    """The table of docs/validation.md."""
    lines = [
        "| record | seeds | flagged | within a day of the change | first alarm after the change, median (max), d | dated (median), d |",
        "|---|---|---|---|---|---|",
    ]
    for name, runs in results.items():
        flagged = [r for r in runs if r["drifted"]]
        if "unchanged" in name:
            lines.append(f"| {name} | {len(runs)} | {len(flagged)} false alarm(s) | — | — | — |")
            continue
        delays = np.array([r["detected_d"] - 4.0 for r in flagged])
        within = int(np.sum((delays >= 0) & (delays <= 1))) if delays.size else 0
        med = f"{np.median(delays):.2f} ({np.max(delays):.2f})" if delays.size else "—"
        since = f"{np.median([r['since_d'] for r in flagged]):.2f}" if flagged else "—"
        lines.append(f"| {name} | {len(runs)} | {len(flagged)} | {within} | {med} | {since} |")
    return "\n".join(lines)


def markers(name: str | None) -> tuple[str, str]:
    """The start and end markers of the table named ``name`` (None: the default one)."""
    if name is None:
        return START, END
    return f"<!-- drift-virtual-{name}:start -->", f"<!-- drift-virtual-{name}:end -->"


def write_doc(doc: Path, table: str, markers: tuple[str, str] = (START, END)) -> None:
    """Replace the table between the ``markers`` of ``doc``."""
    start, end = markers
    text = doc.read_text()
    if start not in text or end not in text:
        raise SystemExit(f"{doc}: markers {start} and {end} not found")
    new = re.sub(
        re.escape(start) + ".*?" + re.escape(end), lambda _: f"{start}\n{table}\n{end}", text, flags=re.S
    )
    write_text_atomic(doc, new)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=200)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument(
        "--cusum-h", type=float, help="the CUSUM's decision interval instead of rczone's (a trade-off study)"
    )
    ap.add_argument("--doc", type=Path, help="write the table into this Markdown file, between the markers")
    ap.add_argument("--marker", help="the markers' name: drift-virtual-NAME (default drift-virtual)")
    ap.add_argument(
        "--table-only", action="store_true", help="the table of <out>/drift_virtual.json, no runs"
    )
    args = ap.parse_args(argv)
    if args.table_only:
        import json

        table = markdown(json.loads((args.out / "drift_virtual.json").read_text()))
        print(table)
        if args.doc:
            write_doc(args.doc, table, markers(args.marker))
        return 0
    if args.cusum_h is not None:
        import rczone.calibration.drift as drift

        drift.CUSUM_H = args.cusum_h
    args.out.mkdir(parents=True, exist_ok=True)
    model = true_model(args.out)
    results: dict = {name: [] for name, _, _ in CASES}
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        for name, days, change in CASES:
            results[name].append(one(model, seed, days, change))
        write_json_atomic(args.out / "drift_virtual.json", results)
        print(
            f"seed {seed}: " + ", ".join(f"{n[:12]} {r[-1]['drifted']}" for n, r in results.items()),
            flush=True,
        )
    table = markdown(results)
    print(table)
    cpu = sum(r["cpu_s"] for runs in results.values() for r in runs)
    print(f"CPU time of the {sum(map(len, results.values()))} records' predictions: {cpu:.1f} s")
    if args.doc:
        write_doc(args.doc, table, markers(args.marker))
    return 0


if __name__ == "__main__":
    sys.exit(main())
