"""EnergyPlus seconds per simulated day, for the prototypes rczone emulates.

Usage::

    python bench/energyplus.py [--building office_small] [--step 5] [--repeat 2]

A run costs a fixed part (reading the input, sizing, warm-up days) and a part per simulated day,
so each building is run for 1 and for 8 days and the difference, divided by 7, is the cost of a
day; the fixed part is the 1-day time less that. Each figure is the median of ``--repeat`` runs
(wall clock, one EnergyPlus thread; the machine's load matters: print ``uptime`` beside it).
Prints one JSON line (``{"energyplus": {...}}``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

from rczone.emulators.energyplus import EnergyPlusEmulator


def timed(building: str, days: int, step: int) -> float:
    t = time.perf_counter()
    EnergyPlusEmulator(building, "usa_il_chicago", start="01-10", days=days, step_minutes=step).run()
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--building", action="append", help="Repeat for several (default: small and medium office)."
    )
    ap.add_argument("--step", type=int, default=5, help="Zone time step, minutes.")
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    out = {}
    for b in args.building or ["office_small", "office_medium"]:
        one = statistics.median(timed(b, 1, args.step) for _ in range(args.repeat))
        eight = statistics.median(timed(b, 8, args.step) for _ in range(args.repeat))
        per_day = (eight - one) / 7
        out[b] = {"s_per_day": round(per_day, 3), "fixed_s": round(one - per_day, 2), "step_min": args.step}
        print(f"{b}: {per_day:.2f} s per simulated day, {one - per_day:.1f} s fixed (step {args.step} min)")
    print(f"load: {os.getloadavg()[0]:.2f} (1 min)")
    print(json.dumps({"energyplus": out}))


if __name__ == "__main__":
    main()
