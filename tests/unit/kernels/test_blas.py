"""The API runs BLAS on one thread for the call's duration and leaves it as it was (rczone.kernels.blas)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytest.importorskip("threadpoolctl")

_PROBE = """
import numpy, scipy.linalg
from threadpoolctl import threadpool_info, threadpool_limits
import rczone
import rczone.workflow.api as api
from rczone import datasets

def threads():
    return sorted({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})

seen = []
def spy(*args, **kwargs):
    seen.append(threads())
    raise RuntimeError("stop here")

api.fit_and_check = spy
import os
night = datasets.load("C")
for chosen in (None, "2"):  # then as if the user had set OPENBLAS_NUM_THREADS=2
    if chosen:
        os.environ["OPENBLAS_NUM_THREADS"] = chosen
    with threadpool_limits(limits=2, user_api="blas"):
        before = threads()
        try:
            rczone.fit("first-order", night, checks=False)
        except RuntimeError:
            pass
        after = threads()
    print(before, seen[-1], after)
"""


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_a_fit_runs_blas_on_one_thread_and_restores_the_count_unless_the_user_chose() -> None:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    }
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-2:] == ["[2] [1] [2]", "[2] [2] [2]"]
