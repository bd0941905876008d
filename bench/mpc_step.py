"""The reference MPC's time per step: the condensed QP against the plain uncondensed one, same run.

Usage::

    python bench/mpc_step.py [--model full-scale] [--hours 8] [--season summer] [--seed 3]

Runs the virtual building (:class:`~rczone.control.virtualplant.VirtualPlant`) with the MPC on
``--model`` for ``--hours`` after the plant's warm-up and records what the MPC was given at every
decision (the measured temperature and its forecast). That record is then replayed through two
fresh MPCs in this process, one per QP form of :class:`~rczone.control.mpc.MPCSettings`:
``condensed`` (the states eliminated, one OSQP problem updated and warm-started) and
``uncondensed`` (states as variables, a new OSQP problem per pass: the form before issue 33).
Both get the same inputs, so their actions must agree to the solver's tolerance; the largest
differences are printed beside the median and largest wall time per step (``time.perf_counter``,
observer, linearization, QP set-up and solve) and the median CPU time (``time.process_time``, one
BLAS thread: less sensitive to the neighbours' load). The first step of each (set-up, no warm start) is
excluded from the median. One JSON line; the machine's load matters: print ``uptime`` beside it.
"""

from __future__ import annotations

import argparse
import json
import os
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rczone.control.controllers import MPCController  # noqa: E402
from rczone.control.disturbance import Disturbance  # noqa: E402
from rczone.control.mpc import MPC, MPCSettings  # noqa: E402
from rczone.control.virtualplant import WARMUP, VirtualPlant  # noqa: E402
from rczone.models import load_model  # noqa: E402


def record(model, season: str, hours: float, seed: int) -> list[tuple]:
    """``(t, measurements, forecast)`` of every MPC decision of a closed-loop run."""
    plant = VirtualPlant(season, days=hours / 24.0, seed=seed)
    ctl = MPCController(MPC(model, disturbance=Disturbance("heat")))
    seen = []
    step = ctl.mpc.step

    def spy(t, y, fc):
        seen.append((t, dict(y), fc))
        return step(t, y, fc)

    ctl.mpc.step = spy
    y = plant.measure()
    while y["time"] < plant.end - 1e-9:
        y = plant.step(ctl.act(y["time"], y, plant.forecast(ctl.horizon, interval=ctl.interval)))
    return seen


def replay(model, stream: list[tuple], formulation: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wall and CPU time per step (s) and the actions ``(m, reheat)`` per step of a fresh MPC."""
    mpc = MPC(model, MPCSettings(formulation=formulation), disturbance=Disturbance("heat"))
    wall, cpu, actions = [], [], []
    for t, y, fc in stream:
        t0, c0 = time.perf_counter(), time.process_time()
        a = mpc.step(t, y, fc)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        actions.append((a.m, a.reheat))
    return np.array(wall), np.array(cpu), np.array(actions)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="full-scale")
    ap.add_argument("--hours", type=float, default=8.0, help="scored hours (after the 6-h warm-up)")
    ap.add_argument("--season", default="summer")
    ap.add_argument("--seed", type=int, default=3)
    a = ap.parse_args(argv)
    model = load_model(a.model)
    stream = record(model, a.season, a.hours, a.seed)
    out = {"model": a.model, "steps": len(stream), "warmup_h": WARMUP / 3600.0, "hours": a.hours}
    acts = {}
    for form in ("condensed", "uncondensed"):
        t, cpu, acts[form] = replay(model, stream, form)
        out[form] = {
            "median_s": float(np.median(t[1:])),
            "median_cpu_s": float(np.median(cpu[1:])),
            "max_s": float(t[1:].max()),
            "first_s": float(t[0]),
        }
    d = np.abs(acts["condensed"] - acts["uncondensed"])
    out["speedup"] = out["uncondensed"]["median_s"] / out["condensed"]["median_s"]
    out["max_diff"] = {"m_kg_s": float(d[:, 0].max()), "reheat_W": float(d[:, 1].max())}
    print(json.dumps({"mpc_step": out}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
