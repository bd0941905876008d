"""fit-many on a local Dask cluster: zone-nights per core-second, scaling from 1 to 2 workers, overhead.

Usage::

    python bench/cluster.py [--zones 400] [--nights 50] [--workers 1 2] [--units auto 1] [--out FILE]

``--nights`` distinct nights of the virtual building are written as Parquet files (timed apart:
data generation is not calibration); zone ``i`` reads night ``i mod nights`` from its file, in the
worker, as on a cluster. For every worker count a ``dask.distributed.LocalCluster`` of
single-threaded worker processes is started and warmed up (each worker imports rczone and loads
its compiled kernels by fitting one zone: a nightly cluster's workers are long-lived), then
``run_batch(scheduler=...)`` calibrates every zone by LS and ML (the manifest defaults: global
search, standard errors; no diagnosis) into a fresh folder, for every unit size asked
(``auto``: :func:`rczone.batch.runner.unit_size`; ``1``: one zone per Dask task).

Printed per run: wall time, zone-nights per core-second (``zones / (wall x workers)``), the
overhead ``1 - sum(task compute) / (wall x workers)`` (scheduling, transfers, storing results,
idle workers at the end), the compute per zone-night and per unit, and the workers' resident
memory. Then the scaling efficiency ``rate(2 workers) / (2 x rate(1 worker))``. The machine's load
(``os.getloadavg``) is printed before and after: on a shared machine the efficiency is bounded by
the cores other processes take. One JSON line (``{"cluster_scaling": ...}``) is printed, and
written into ``--out`` when given.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

# single-threaded BLAS in the workers, as in bench/batch.py (the matrices are tiny)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from batch import record, write_nights  # noqa: E402  (bench/batch.py, beside this script)
from rczone.batch import read_manifest, run_batch  # noqa: E402
from rczone.batch.runner import unit_size  # noqa: E402
from rczone.batch.task import run_tasks  # noqa: E402


def _rss() -> int:
    import psutil

    return psutil.Process().memory_info().rss


def measure(manifest: Path, workers: int, units: list[str], out: Path) -> list[dict]:
    """Calibrate the manifest on a warmed-up LocalCluster of ``workers`` processes, once per unit size."""
    from dask.distributed import Client, LocalCluster

    m = read_manifest(manifest)
    zones = len(m.zones)
    warm = [t for t in m.tasks if t.zone == m.zones[0]]
    rows = []
    with (
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        t0 = time.perf_counter()
        client.run(run_tasks, warm)  # every worker: imports, compiled kernels loaded, one zone fitted
        warm_s = time.perf_counter() - t0
        for unit in units:
            size = unit_size(zones, workers) if unit == "auto" else int(unit)
            run = run_batch(m, out / f"w{workers}-u{unit}", scheduler=cluster.scheduler_address, unit=size)
            rss = max(client.run(_rss).values())
            row = {
                "workers": workers,
                "unit": size,
                "unit_asked": unit,
                "tasks": run.submitted,
                "zones": zones,
                "wall_s": run.seconds,
                "compute_s": run.compute_seconds,
                "zone_nights_per_core_s": zones / (run.seconds * workers),
                "overhead": run.overhead,
                "overhead_per_task_ms": 1e3 * (run.seconds * workers - run.compute_seconds) / run.submitted,
                "compute_per_zone_ms": 1e3 * run.compute_seconds / zones,
                "cpu_per_zone_ms": 1e3 * run.cpu_seconds / zones,
                "compute_per_task_s": run.compute_seconds / run.submitted,
                "worker_rss_mb": rss / 2**20,
                "warm_up_s": warm_s,
                "failed": run.failed,
            }
            rows.append(row)
            print(
                f"{workers} worker(s), {size} zone(s) per task ({run.submitted} tasks): {run.seconds:.1f} s wall,"
                f" {row['zone_nights_per_core_s']:.2f} zone-nights per core-second,"
                f" overhead {100 * run.overhead:.1f} % ({row['overhead_per_task_ms']:.0f} ms per task),"
                f" compute {row['compute_per_zone_ms']:.0f} ms per zone-night ({row['cpu_per_zone_ms']:.0f} ms of CPU),"
                f" {row['compute_per_task_s']:.2f} s"
                f" per task; worker memory {row['worker_rss_mb']:.0f} MB; {run.failed} failed",
                flush=True,
            )
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--zones", type=int, default=400)
    ap.add_argument("--nights", type=int, default=50)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--units", nargs="+", default=["auto"], help='zones per task: "auto" and/or integers')
    ap.add_argument("--out", type=Path, default=None, help="JSON file to record the figures in")
    args = ap.parse_args(argv)
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        manifest = write_nights(folder, args.zones, max(1, min(args.nights, args.zones)))
        print(f"data generation: {time.perf_counter() - t0:.1f} s for {args.nights} nights", flush=True)
        rows = [r for w in args.workers for r in measure(manifest, w, args.units, folder)]
    load_after = os.getloadavg()
    entry: dict = {
        "runs": rows,
        "load_before": load_before,
        "load_after": load_after,
        "cores": os.cpu_count(),
    }
    one = {r["unit_asked"]: r for r in rows if r["workers"] == 1}
    for r in (r for r in rows if r["workers"] == 2):
        base = one.get(r["unit_asked"])
        if base:
            eff = r["zone_nights_per_core_s"] / base["zone_nights_per_core_s"]
            r["scaling_efficiency"] = eff
            print(f"scaling 1 -> 2 workers ({r['unit_asked']} zones per task): efficiency {100 * eff:.0f} %")
    print(f"load average before {load_before[0]:.1f}, after {load_after[0]:.1f} on {os.cpu_count()} cores")
    print(json.dumps({"cluster_scaling": entry}))
    if args.out is not None:
        record(args.out, "cluster_scaling", entry)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
