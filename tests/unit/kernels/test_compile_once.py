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

import pytest

ROOT = Path(__file__).resolve().parents[3]

#: Pairs of structures of one size, on the built-in night C (the second reads fewer of its columns).
FUSED = ("second-order", "TiTe")  # two states: the fused 2-state kernels
GENERAL = ("first-order", "Ti")  # one state: the general packed kernels


def compilations(models: Sequence[str]) -> dict[str, int]:
    """How many of rczone's kernels numba compiles while fitting each model on night C, in order.

    Every fit is the CLI's (one start, with its checks, profiles and diagnosis).
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

    listener = Count()
    event.register("numba:compile", listener)
    out = {}
    try:
        for name in models:
            counts.append(0)
            rczone.fit(name, "C", n_starts=1)
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


@pytest.mark.parametrize("pair", [FUSED, GENERAL], ids=["two-states", "one-state"])
def test_second_structure_compiles_nothing_in_the_same_process(pair):
    first, second = pair
    counts = compilations(pair)
    assert counts[second] == 0, f"fitting {second} after {first} compiled {counts[second]} kernels"


@pytest.mark.slow
def test_second_structure_loads_everything_from_the_cache_in_a_new_process(tmp_path):
    cache = tmp_path / "numba-cache"
    warm = _in_child([FUSED[0], GENERAL[0]], cache)
    # an empty cache: the first structures compile (the count sees numba's compilations)
    assert warm[FUSED[0]] > 0 and warm[GENERAL[0]] > 0, warm
    cold = _in_child([FUSED[1], GENERAL[1]], cache)
    assert cold == {FUSED[1]: 0, GENERAL[1]: 0}, f"structures new to this process compiled: {cold}"
