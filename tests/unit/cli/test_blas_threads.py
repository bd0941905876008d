"""The console script runs the BLAS libraries on one thread unless the user chose a number."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

_PROBE = """
import os, sys
import rczone.cli as cli
assert "numpy" not in sys.modules  # the variables only act if set before numpy loads
sys.argv = ["rczone", "--help"]
try:
    cli.run()
except SystemExit:
    pass
print(",".join(os.environ.get(v, "-") for v in cli.BLAS_THREADS))
"""


@pytest.mark.parametrize(("given", "expected"), [(None, "1,1,1"), ("3", "3,1,1")])
def test_the_console_script_caps_blas_threads_unless_set(given, expected) -> None:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    }
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == expected
