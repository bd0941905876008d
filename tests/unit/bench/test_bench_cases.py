"""``make bench`` builds every benchmark before it times any: a renamed rczone name breaks it all.

(``bench/run.py`` once referred to ``engines.interval_derivatives`` after that function became
``derivatives_kernel``, and every case failed to start.) Here each case is built, so a stale name
fails in ``make test`` instead of in a benchmark run; the two sides of the two-zone gradient, whose
plain side patches the engine, are called once (slow: it compiles the Frechet derivatives).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[3] / "bench"


@pytest.fixture(scope="module")
def run():
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("run")
    finally:
        sys.path.remove(str(BENCH))


def test_every_benchmark_case_is_built(run):
    cases = run.cases()
    names = [c.name for c in cases]
    assert len(names) == len(set(names)) and "grad_2zone_virtual" in names


@pytest.mark.slow  # compiles the matrix exponentials' Frechet derivatives (~40 s from an empty cache)
def test_the_two_zone_gradient_runs_on_both_sides_and_they_agree(run):
    (case,) = [c for c in run.cases() if c.name == "grad_2zone_virtual"]
    assert case.agree(case.ours(), case.theirs()) < 1e-8
