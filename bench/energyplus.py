"""EnergyPlus seconds per simulated day beside rczone's seconds per MPC step and per joint floor fit.

Usage::

    python bench/energyplus.py                      # all three; entries "energyplus_*" of bench/results.json
    python bench/energyplus.py --only day           # EnergyPlus alone (also: --only mpc, --only floor)
    python bench/energyplus.py --building office_small --step 5 --repeat 2

Offline: EnergyPlus, its prototypes and weather files come with ``pyenergyplus-lbnl``
(``rczone[energyplus]``), and every input is made in the run.

``day``
    A run costs a fixed part (reading the input, sizing, warm-up days) and a part per simulated
    day, so each building is run for 1 and for 8 days and the difference, divided by 7, is the
    cost of a day; the fixed part is the 1-day time less that. Each figure is the median of
    ``--repeat`` runs (wall clock, one EnergyPlus thread; the CPU time per day beside it). On a
    loaded machine the difference can drown in the noise (a negative day): then no ratio is made.
``floor``
    The trend: the small office, Chicago, 17-18 January, 15-minute steps, its own control,
    sensor seed 1 (``rczone emulate``); the joint model of its floor generated from the
    ``building.toml`` the run wrote (``rczone models generate --floor 1``: 5 zones, 10 states,
    32 R and C, 42 free with the noise levels), fitted by ML with rczone's default search (L-BFGS
    with exact gradients from the model's values and from sampled points, until the best optimum is
    reached twice or confirmed) and standard errors (``rczone.fit``, what ``rczone fit`` runs
    before its checks). After a warm-up fit of a few evaluations (numba compiles then), ``--fit-repeat`` fits,
    wall and CPU time (``time.process_time``); target 60 s.
``mpc``
    The supervisory MPC (``rczone control-test --emulator energyplus --controller mpc``) on the
    small office's south zone, one day from 19 January at 15-minute steps, with the paper's
    second-order model fitted (ML, one local search) on that zone's columns of the ``floor``
    trend. Each step's ``act`` (observer, condensed linear program, set points) is timed (wall and
    CPU), and so is each ``plant.step`` (EnergyPlus advancing one step in its thread, wall).

Ratios follow ``bench/run.py``'s convention (the other's time over rczone's):
``ratio_vs_energyplus_day`` is EnergyPlus's seconds per simulated day of the same building over
rczone's seconds per MPC step or per floor fit. BLAS is pinned to one thread, as in
``bench/run.py``. The machine's load matters: it is printed and stored beside each entry.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rczone.emulators.energyplus import EnergyPlusEmulator  # noqa: E402
from rczone.files.atomic import write_json_atomic  # noqa: E402

HERE = Path(__file__).resolve().parent
BUILDING, WEATHER = "office_small", "usa_il_chicago"
#: The fixed trend of the floor fit and of the MPC's zone model.
TREND = {"start": "01-17", "days": 2, "step_minutes": 15, "seed": 1}
MPC_ZONE, MPC_START = "Perimeter_ZN_1", "01-19"
FLOOR_TARGET_S = 60.0


def load() -> float:
    return round(os.getloadavg()[0], 2)


def timed(building: str, days: int, step: int) -> tuple[float, float]:
    """Wall and CPU seconds of one EnergyPlus run (in this process: its CPU is this process's)."""
    t, c = time.perf_counter(), time.process_time()
    EnergyPlusEmulator(building, WEATHER, start="01-10", days=days, step_minutes=step).run()
    return time.perf_counter() - t, time.process_time() - c


def energyplus_day(building: str, step: int, repeat: int) -> dict:
    """EnergyPlus's seconds per simulated day and fixed seconds per run, wall and CPU (module notes)."""
    one = [timed(building, 1, step) for _ in range(repeat)]
    eight = [timed(building, 8, step) for _ in range(repeat)]
    wall, cpu = (
        (statistics.median(r[i] for r in eight) - statistics.median(r[i] for r in one)) / 7 for i in (0, 1)
    )
    fixed = statistics.median(r[0] for r in one) - wall
    print(
        f"{building}: {wall:.2f} s per simulated day ({cpu:.2f} s CPU), {fixed:.1f} s fixed (step {step} min)"
        + ("" if wall > 0 else ": the load swamped the difference of the runs, no ratio (raise --repeat)")
    )
    return {
        "median_s": wall,
        "cpu_s": cpu,
        "fixed_s": fixed,
        "step_min": step,
        "load_1min": load(),
        "description": f"EnergyPlus {building}, wall s per simulated day (runs of 1 and 8 days, median of"
        f" {repeat}), one thread",
    }


def make_trend(folder: Path) -> None:
    """The fixed trend and building file of the floor fit (``rczone emulate ... -o folder``)."""
    from rczone.emulators.runs import emulate_to_folder

    emulate_to_folder(BUILDING, WEATHER, folder, **TREND)


def floor_problem(folder: Path):
    """``(network, data)`` of the joint model of floor 1, as ``rczone models generate`` and ``fit`` make them."""
    from rczone.calibration import dataset
    from rczone.emulators.floor import floor_model_file
    from rczone.models import load_model, model_to_toml
    from rczone.workflow.datasource import data_source

    model_file = folder / "floor1.toml"
    model_file.write_text(model_to_toml(floor_model_file(folder / "building.toml", 1)))
    zm = load_model(model_file)
    frame = data_source(folder / "trend.csv", folder / "floor1.columns.toml").frame(zm)
    return zm.network, dataset(zm, frame)


def floor_fit(folder: Path, repeat: int) -> dict:
    """Wall and CPU seconds of the joint ML fit of the small office's floor (module notes)."""
    from rczone.estimation import fit

    net, data = floor_problem(folder)
    fit(net, data, method="ml", n_starts=1, max_evals=5, uncertainty=False)  # warm-up: numba compiles here
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        res = fit(net, data, method="ml")  # rczone's default search, as `rczone fit` runs it
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    n_free = len(res.parameters)
    print(
        f"floor fit ({len(net.state_names)} states, {len(net.outputs)} outputs, {n_free} free,"
        f" {data.n_samples} samples, engine {res.engine!r}): {statistics.median(wall):.1f} s wall,"
        f" {statistics.median(cpu):.1f} s CPU, {res.n_evals} evaluations"
    )
    return {
        "median_s": statistics.median(wall),
        "fastest_s": min(wall),
        "median_cpu_s": statistics.median(cpu),
        "n_evals": res.n_evals,
        "engine": res.engine,
        "converged": res.converged,
        "local_searches": len(res.starts),
        "llf": res.llf,
        "search": res.search.reason if res.search is not None else None,
        "target_s": FLOOR_TARGET_S,
        "load_1min": load(),
        "description": f"joint ML fit of {BUILDING}'s floor 1 ({len(net.state_names)} states,"
        f" {len(net.outputs)} outputs, {n_free} free, {data.n_samples} samples of 15 min), the default"
        " search (L-BFGS with exact gradients from the model's values and sampled starts, until the best"
        f" optimum is confirmed), standard errors; median of {repeat} after a warm-up",
    }


def zone_model(folder: Path):
    """The paper's second-order model of :data:`MPC_ZONE` fitted on the trend (ML, one local search)."""
    from rczone.models import load_model
    from rczone.workflow import FitSettings, fit_and_check
    from rczone.workflow.datasource import data_source

    zm = load_model("second-order")
    frame = data_source(folder / "trend.csv", folder / f"{MPC_ZONE}.columns.toml").frame(zm)
    return fit_and_check(zm, frame, FitSettings(n_starts=1, checks=False), analyses=False).model


def mpc_step(folder: Path) -> dict:
    """Wall and CPU seconds per supervisory-MPC step on EnergyPlus, and EnergyPlus's per step (module notes)."""
    from rczone.emulators.control import make_controller_for
    from rczone.emulators.plant import EnergyPlusPlant

    model = zone_model(folder)
    plant = EnergyPlusPlant(
        BUILDING, WEATHER, zones=[MPC_ZONE], start=MPC_START, days=1, price="tou", forecast="medium"
    )
    act_wall, act_cpu, plant_wall = [], [], []
    try:
        t0 = time.perf_counter()
        y = plant.measure()  # EnergyPlus starts: input, sizing, warm-up days
        start_s = time.perf_counter() - t0
        ctl = make_controller_for("mpc", plant, model, None)
        while y["time"] < plant.end - 1e-9:
            fc = plant.forecast(ctl.horizon, interval=ctl.interval)
            t0, c0 = time.perf_counter(), time.process_time()
            a = ctl.act(y["time"], y, fc)
            t1 = time.perf_counter()
            act_wall.append(t1 - t0)
            act_cpu.append(time.process_time() - c0)
            y = plant.step(a)
            plant_wall.append(time.perf_counter() - t1)
    finally:
        plant.close()
    wall, cpu = np.array(act_wall[1:]), np.array(act_cpu[1:])  # the first: set-up
    steps_per_day = 86400.0 / plant.dt
    print(
        f"MPC step ({len(act_wall)} steps of {plant.dt / 60:.0f} min): {1e3 * np.median(wall):.1f} ms wall,"
        f" {1e3 * np.median(cpu):.1f} ms CPU (max {1e3 * wall.max():.0f} ms); EnergyPlus in the same loop"
        f" {np.median(plant_wall):.3f} s per step ({np.sum(plant_wall):.1f} s for the day after {start_s:.1f} s of"
        " start-up)"
    )
    return {
        "median_s": float(np.median(wall)),
        "fastest_s": float(wall.min()),
        "median_cpu_s": float(np.median(cpu)),
        "max_s": float(wall.max()),
        "steps": len(act_wall),
        "steps_per_day": steps_per_day,
        "energyplus_median_step_s": float(np.median(plant_wall)),
        "energyplus_loop_s": float(np.sum(plant_wall)),
        "energyplus_start_s": start_s,
        "load_1min": load(),
        "description": f"supervisory MPC step (observer, condensed LP by HiGHS, set points) on {BUILDING}"
        f" {MPC_ZONE}, second-order model fitted on the floor trend, one day of {plant.dt / 60:.0f}-min steps,"
        " TOU price, medium forecast error; median wall after the first step",
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--building",
        action="append",
        help="For --only day; repeat for several (default: small and medium office).",
    )
    ap.add_argument("--step", type=int, default=5, help="Zone time step of the day runs, minutes.")
    ap.add_argument("--repeat", type=int, default=2, help="Runs of each day figure.")
    ap.add_argument("--fit-repeat", type=int, default=1, help="Floor fits timed (minutes each).")
    ap.add_argument(
        "--only", choices=("day", "mpc", "floor"), action="append", help="Repeat for several (default all)."
    )
    ap.add_argument("--out", type=Path, default=HERE / "results.json")
    args = ap.parse_args(argv)
    parts = args.only or ["day", "mpc", "floor"]
    print(f"EnergyPlus against rczone on {os.cpu_count()} core(s), load {load():.2f}")
    got: dict = {}
    if "day" in parts:
        for b in args.building or [BUILDING, "office_medium"]:
            got[f"energyplus_day_{b}"] = energyplus_day(b, args.step, args.repeat)
    previous = previous_results(args.out)
    if {"mpc", "floor"} & set(parts):
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            make_trend(folder)
            if "mpc" in parts:
                got["energyplus_mpc_step"] = mpc_step(folder)
            if "floor" in parts:
                got["energyplus_floor_fit"] = floor_fit(folder, args.fit_repeat)
    day = {**previous, **got}.get(f"energyplus_day_{BUILDING}")
    if day is not None and not day["median_s"] > 0:
        day = None  # a load that swamped the 1- and 8-day runs' difference: no ratio
    for name in ("energyplus_mpc_step", "energyplus_floor_fit"):
        if name in got and day is not None:
            got[name]["ratio_vs_energyplus_day"] = day["median_s"] / got[name]["median_s"]
    report(got, day)
    write_json_atomic(args.out, {**previous, **got})
    print(json.dumps({"energyplus": got}))
    return 0


def report(got: dict, day: dict | None) -> None:
    """The three figures side by side, with their ratios."""
    if day is None:
        return
    print(f"\nEnergyPlus {BUILDING}: {day['median_s']:.2f} s per simulated day (load {day['load_1min']})")
    if "energyplus_mpc_step" in got:
        m = got["energyplus_mpc_step"]
        print(
            f"rczone MPC step:   {1e3 * m['median_s']:.1f} ms  -> ratio {m['ratio_vs_energyplus_day']:.0f}x"
            f" (a simulated day holds {m['steps_per_day']:.0f} steps: the MPC takes"
            f" {m['median_s'] * m['steps_per_day']:.1f} s of it)"
        )
    if "energyplus_floor_fit" in got:
        f = got["energyplus_floor_fit"]
        met = "met" if f["median_s"] <= f["target_s"] else "NOT met"
        print(
            f"rczone floor fit:  {f['median_s']:.1f} s ({f['median_cpu_s']:.1f} s CPU) -> ratio"
            f" {f['ratio_vs_energyplus_day']:.3f}x (the fit costs {1 / f['ratio_vs_energyplus_day']:.1f} simulated"
            f" days); target {f['target_s']:.0f} s {met}"
        )


def previous_results(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


if __name__ == "__main__":
    raise SystemExit(main())
