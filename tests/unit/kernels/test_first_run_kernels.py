"""The first command a user runs compiles only the kernels it needs (issue 37, item 7).

``rczone fit C --starts 1`` is what CI times on a fresh install (``.ci/run``): from an empty
numba cache its CPU time is the time numba takes to compile every kernel the command reaches. The
list below is what that command reaches today, each kernel with its number of signatures
(specializations): the fused 2-state ML gradient and the kernels it calls, the start's assembly,
the 2-state discretization of the filter's matrices, the unrolled 2-state Kalman filter of the
band calibration and the open-loop checks (``rc2.filter_rc2``: the general ``kalman_filter``
costs about twenty seconds more), the k-step moments and the compiled propagation. A new
family (the general filter, the general engine's value or gradient, the expm route, Nelder-Mead) or a second
signature of one of them (a read-only array, an int where a float was passed) would add seconds
to every first run without a test failing; this test fails instead.

The command runs in a new process, so only what it touches holds a signature. A kernel loaded from
the disk cache holds the signature it was called with, as a compiled one does, but the kernels it
calls are then not loaded on their own: a warm run lists a subset of a cold one, so the test checks
that what the command touched is within the expected list, with at most the expected signatures,
and that its entry points are there.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

#: Every rczone kernel ``rczone fit C --starts 1`` may compile, with its number of signatures.
EXPECTED = {
    "adjoint.gradient_fused": 1,
    "adjoint.nll_rc2_adjoint": 1,
    "discretize._dd2": 1,
    "discretize._dd3": 1,
    "discretize._dd3_sorted": 1,
    "discretize._dd4": 1,
    "discretize._dd4_00": 1,
    "discretize._dd_series": 2,  # the series' order is a literal: 2 and 3
    "discretize._key_directions": 1,
    "discretize.phi1": 1,
    "discretize.phi2": 1,
    "discretize.rc2_discretize": 1,
    "discretize.rc2_interval_matrices": 1,
    "discretize.spectral_derivatives2": 1,
    "expm.lu_factor": 1,
    "expm.lu_solve": 1,
    "forecast.k_step_moments": 1,
    "problem._slot": 1,
    "problem.assemble": 1,
    "problem.assemble_derivatives": 1,
    "problem.assembled": 1,
    "problem.conductances": 1,
    "problem.element_values": 1,
    "problem.initial_state": 1,
    "problem.prior_terms": 1,
    "problem.with_prior": 1,
    "propagate.propagate_kernel": 1,
    "rc2.filter_rc2": 1,
    "reverse.contract": 1,
    "reverse.zero_adjoints": 1,
}

#: Called from Python by the command: they hold a signature whether compiled or loaded from the cache.
ENTRY_POINTS = (
    "adjoint.gradient_fused",
    "forecast.k_step_moments",
    "problem.initial_state",
    "propagate.propagate_kernel",
    "rc2.filter_rc2",
)


def signatures_after_first_command() -> dict[str, int]:
    """Run ``rczone fit C --starts 1`` in this process; each rczone kernel holding signatures, and how many."""
    import contextlib
    import importlib
    import io
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import rczone.kernels
    from rczone.cli.main import main

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(["fit", "C", "--starts", "1", "--quiet"])
    assert code in (0, 3), f"rczone fit C exited {code}"
    out = {}
    for info in pkgutil.iter_modules(rczone.kernels.__path__):
        module = importlib.import_module(f"rczone.kernels.{info.name}")
        for name, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == module.__name__ and obj.signatures:
                out[f"{info.name}.{name}"] = len(obj.signatures)
    return out


def test_first_command_compiles_only_its_kernel_families():
    code = (
        "import json; from tests.unit.kernels.test_first_run_kernels import signatures_after_first_command; "
        "print(json.dumps(signatures_after_first_command()))"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), *sys.path])}
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    held = json.loads(proc.stdout.strip().splitlines()[-1])
    unexpected = {k: v for k, v in held.items() if k not in EXPECTED}
    assert not unexpected, f"rczone fit C reached kernels beyond its families: {unexpected}"
    extra = {k: v for k, v in held.items() if v > EXPECTED[k]}
    assert not extra, f"kernels compiled more signatures than expected: {extra} (expected {EXPECTED})"
    missing = [k for k in ENTRY_POINTS if k not in held]
    assert not missing, f"the command no longer reaches {missing}: update EXPECTED to what it compiles"
