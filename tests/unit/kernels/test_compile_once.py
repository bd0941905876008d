"""A new model structure compiles nothing once a structure of its size and kernel family has (issue 38).

Structure is data to the compiled kernels: the network's incidence, slots and sizes are arrays, so
numba's specializations depend only on the arrays' types (dtype, dimensions, layout and whether
they are read-only), never on a network. These tests count numba's own compile events
(``numba:compile``, fired on a cache miss only) while fitting two structures of the same size in a
row, in one process and, from the cache the first left, in a new one. Each pair differs in its
inputs and flows (a supply-air flow or none), which once compiled the checks' 2-state simulation a
second time: a read-only flow column of the data against a flow-free model's writable empty one.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[3]

#: Pairs of structures of one size, on the built-in night C (the second reads fewer of its columns).
FUSED = ("second-order", "TiTe")  # two states: the fused 2-state kernels
GENERAL = ("first-order", "Ti")  # one state: the general packed kernels
#: Two generated two-room joint models of one size (4 states, 2 outputs; ``rczone models generate``,
#: docs/multizone.md): one heating circuit split between the rooms by an estimated share (a tied
#: ``1 - s``), or a heater per room and the sun through an aperture per room. Both have heat-input
#: gains that are parameters, packed as affine terms of the compiled problem (its ``Slots.gain_*``:
#: the shares and apertures are data, not structure), with several outputs: paths the one-room
#: pairs do not take.
ROOMS = ("rooms-one-circuit", "rooms-heaters-and-sun")


def rooms_case(name: str):
    """The generated two-room model ``name`` of :data:`ROOMS`, and two days of data.

    The rooms' temperatures are the simulation of two rooms heated 60/40 by the circuit ``Ph``
    (``Q1``, ``Q2`` are those shares), with sensor noise; the sun ``Ps`` does nothing.
    """
    import numpy as np

    import rczone
    from rczone.models.multizone import multizone

    walls = [("1", "2")]
    if name == ROOMS[0]:
        net = multizone(2, walls, circuits={"Ph": ["1", "2"]}, name=name)
    else:
        net = multizone(2, walls, solar=True, name=name)
    rng = np.random.default_rng(3)
    n, dt = 289, 600.0
    t = np.arange(n) * dt
    ph = 400 + 1600 * (np.cumsum(rng.random(n) < dt / 7200) % 2)
    sun = np.clip(np.sin(2 * np.pi * (t / 86400 - 0.25)), 0, None) * 300
    frame = pd.DataFrame(
        {
            "time": t,
            "To": 5 + 3 * np.sin(2 * np.pi * t / 86400),
            "Ph": ph,
            "Q1": 0.6 * ph,
            "Q2": 0.4 * ph,
            "Ps": sun,
        }
    )
    states = rczone.simulate(multizone(2, walls), frame)
    for room in ("T1", "T2"):
        frame[room] = states[room].to_numpy() + rng.normal(0, 0.05, n)
    return net, frame


def compilations(models: Sequence[str]) -> dict[str, int]:
    """How many of rczone's kernels numba compiles while fitting each model on night C, in order.

    Every fit is the CLI's (one start, with its checks, profiles and diagnosis). The names of
    :data:`ROOMS` are fitted on their own data (:func:`rooms_case`), made before the count starts.
    """
    from numba.core import event

    import rczone

    counts: list[int] = []

    class Count(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            dispatcher = (ev.data or {}).get("dispatcher")
            if getattr(getattr(dispatcher, "py_func", None), "__module__", "").startswith("rczone."):
                counts[-1] += 1

        def on_end(self, ev: event.Event) -> None:
            pass

    cases = {name: rooms_case(name) if name in ROOMS else (name, "C") for name in models}
    listener = Count()
    event.register("numba:compile", listener)
    out = {}
    try:
        for name, (model, data) in cases.items():
            counts.append(0)
            rczone.fit(model, data, n_starts=1)
            out[name] = counts[-1]
    finally:
        event.unregister("numba:compile", listener)
    return out


def _in_child(models: Sequence[str], cache: Path) -> dict[str, int]:
    """:func:`compilations` in a new process whose numba cache is ``cache``."""
    code = (
        "import json, sys; from tests.unit.kernels.test_compile_once import compilations; "
        f"print(json.dumps(compilations({list(models)!r})))"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": os.pathsep.join([str(ROOT), *sys.path])}
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize(
    "pair",
    [FUSED, GENERAL, pytest.param(ROOMS, marks=pytest.mark.slow)],
    ids=["two-states", "one-state", "two-rooms"],
)
def test_second_structure_compiles_nothing_in_the_same_process(pair):
    first, second = pair
    counts = compilations(pair)
    assert counts[second] == 0, f"fitting {second} after {first} compiled {counts[second]} kernels"


@pytest.mark.slow
def test_second_structure_loads_everything_from_the_cache_in_a_new_process(tmp_path):
    cache = tmp_path / "numba-cache"
    pairs = (FUSED, GENERAL, ROOMS)
    warm = _in_child([first for first, _ in pairs], cache)
    # an empty cache: the first structures compile (the count sees numba's compilations)
    assert warm[FUSED[0]] > 0 and warm[GENERAL[0]] > 0, warm
    cold = _in_child([second for _, second in pairs], cache)
    assert cold == dict.fromkeys(cold, 0) and len(cold) == 3, (
        f"structures new to this process compiled: {cold}"
    )
