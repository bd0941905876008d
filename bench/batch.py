"""Throughput of batch calibration: zone-nights per second with LS and ML, using every core.

Usage::

    python bench/batch.py [--zones 1000] [--nights 100] [--workers N] [--backend auto|dask|processes]

``--nights`` distinct nights of the virtual building (autumn forced and summer closed-loop,
alternating seeds) are generated once and written as Parquet files (timed separately: data
generation is not calibration); zone ``i`` reads night ``i mod nights``. Then
``rczone.batch.run_batch`` calibrates the paper's reduced model for every zone by LS and by
ML (the manifest defaults: global search, uncertainty included; no diagnosis) into a fresh
results folder, end to end:
cluster start, reading and checking each zone's file, fitting, storing every result and
consolidating the table. Every zone is calibrated on its own (nothing is shared between
zones). Prints the figures, the time scaled to 1,000 zone-nights, and one JSON line
(``{"batch_1000_zone_nights": {"median_s": ..., ...}}``), and updates that entry of
``bench/results.json`` (``--out``). The ratio against the plain baseline is a lower bound:
the plain ML fit of ``bench/run.py`` times the zones over the workers.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

# single-threaded BLAS, as in bench/run.py (set before numpy loads it; the workers inherit it):
# the matrices are tiny, and BLAS threads contending for the cores made data generation 5-10x
# slower on a loaded 2-core machine, and SciPy's L-BFGS-B with them too
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from rczone.batch import read_manifest, run_batch  # noqa: E402
from rczone.files.atomic import write_json_atomic  # noqa: E402
from rczone.virtual.scenarios import generate_night  # noqa: E402


def write_nights(folder: Path, zones: int, nights: int, *, diagnose: bool = False) -> Path:
    """``nights`` nights as Parquet files in ``folder`` and a manifest ``m.toml`` of ``zones`` zones
    reading them in turn (LS and ML); the manifest's path."""
    lines = ['methods = ["ls", "ml"]', f"diagnose = {str(diagnose).lower()}"]
    for i in range(nights):
        season, mode = ("autumn", "forced") if i % 2 == 0 else ("summer", "closed-loop")
        generate_night(season, mode, i).to_parquet(folder / f"night{i}.parquet", index=False)
    for i in range(zones):
        lines += ["[[zone]]", f'id = "z{i}"', f'data = "night{i % nights}.parquet"']
    path = folder / "m.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def record(path: Path, name: str, entry: dict) -> None:
    """Set the entry ``name`` of the JSON file ``path`` (created if need be), atomically."""
    try:
        results = json.loads(path.read_text())
    except (OSError, ValueError):
        results = {}
    results[name] = entry
    write_json_atomic(path, results)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--zones", type=int, default=1000)
    ap.add_argument("--nights", type=int, default=100)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--backend", default="auto")
    ap.add_argument("--diagnose", action="store_true", help="also diagnose identifiability per zone")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results.json")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        t0 = time.perf_counter()
        nights = max(1, min(args.nights, args.zones))
        write_nights(d, args.zones, nights, diagnose=args.diagnose)
        gen = time.perf_counter() - t0
        m = read_manifest(d / "m.toml")
        t0 = time.perf_counter()
        run = run_batch(m, d / "out", workers=args.workers, backend=args.backend)
        wall = time.perf_counter() - t0
    per_zone = wall / args.zones
    print(
        f"{args.zones} zone-nights x (LS + ML{' + diagnosis' if args.diagnose else ''}) on {args.workers} worker(s): {wall:.1f} s "
        f"({per_zone * 1e3:.0f} ms per zone-night, {run.failed} failed); data generation {gen:.1f} s"
        f" for {nights} nights"
    )
    print(
        f"per 1,000 zone-nights: {per_zone * 1000:.0f} s (target 20 s); {run.submitted} tasks on"
        f" {run.workers} worker(s), compute {1e3 * run.compute_seconds / args.zones:.0f} ms per zone-night"
        f" ({1e3 * run.cpu_seconds / args.zones:.0f} ms of CPU),"
        f" overhead {100 * run.overhead:.1f} % of the workers' time (cluster start, scheduling, storing,"
        f" summary); load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    if args.diagnose:  # not the benchmark's definition: print, do not record
        return 0
    entry = {
        "median_s": per_zone * 1000,
        "zones_measured": args.zones,
        "distinct_nights": nights,
        "workers": args.workers,
        "ratio_vs_plain": None,
        "tasks": run.submitted,
        "compute_s": run.compute_seconds,
        "cpu_s": run.cpu_seconds,
        "overhead": run.overhead,
        "description": (
            f"python bench/batch.py --zones {args.zones} --nights {nights}: LS + ML fits of"
            " second-order-paper per zone-night (standard errors included, no diagnosis),"
            f" {args.workers} local workers, end to end; data generation excluded"
        ),
    }
    # the plain baseline is never run for a whole batch (about a day); its ML fits alone,
    # spread over the same workers, bound it from below
    try:
        plain_fit = json.loads(args.out.read_text())["fit_ml_2state"]["plain_median_s"]
    except (OSError, ValueError, KeyError, TypeError):
        plain_fit = None
    if plain_fit:
        bound = plain_fit * 1000 / args.workers
        entry.update(plain_lower_bound_s=bound, ratio_vs_plain=bound / entry["median_s"])
        print(
            f"plain baseline: >= {bound / 3600:.1f} h per 1,000 (its ML fit alone, {plain_fit:.0f} s,"
            f" on {args.workers} workers): ratio >= {entry['ratio_vs_plain']:.0f}x"
        )
    print(json.dumps({"batch_1000_zone_nights": entry}))
    if args.out.name:
        record(args.out, "batch_1000_zone_nights", entry)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
