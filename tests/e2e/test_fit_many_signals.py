"""``rczone fit-many`` and its coordinator's end (issue 39): the workers never outlive it.

The third hostile campaign found fit-many's worker processes still running 8 s after a SIGTERM or
a ``kill -9`` of the coordinating process. Here the real command runs in its own session (its
process group holds the coordinator and every worker it starts), on both local engines, with the
calibration replaced by the quick stand-in of ``tests/unit/batch/test_faults.py`` (each zone
sleeps, so the run is still going when the signal lands); only the coordinator is signalled, as a
job scheduler or ``kill`` does, and ``/proc`` tells which processes of the group are alive.

* SIGTERM ends the run as Ctrl-C does: exit 130, no traceback, the zones stored until then kept
  whole (the parts a rerun resumes from, ``tests/unit/batch/test_runner.py``), and no worker left.
* ``kill -9`` runs no handler in the coordinator: its workers end by themselves within seconds
  (a parent-death signal, or a watch of the parent).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import rczone
from tests.unit.batch.test_faults import write_manifest

pytestmark = [
    pytest.mark.slow,  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups counted through /proc"),
]

ROOT = Path(__file__).resolve().parents[2]

#: The console script with the calibration replaced by the quick stand-in (forked workers inherit
#: it; Dask's spawned workers import it by name from the tests).
COMMAND = """
import sys
import rczone.batch.runner as runner
from tests.unit.batch.test_faults import quick_tasks
runner.run_tasks = quick_tasks
import rczone.cli
sys.exit(rczone.cli.run())
"""

ZONES = [f"z{i:02d}" for i in range(12)]


def alive_in_group(pgid: int) -> list[int]:
    """Processes of the process group ``pgid`` that are running (zombies are not)."""
    found = []
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            found.append(int(entry.name))
    return found


def start(tmp_path: Path, backend: str) -> tuple[subprocess.Popen, Path, Path]:
    manifest = write_manifest(tmp_path, ZONES)
    out, err = tmp_path / "out", tmp_path / "err.txt"
    src = str(Path(rczone.__file__).resolve().parents[1])
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([src, str(ROOT), os.environ.get("PYTHONPATH", "")]),
        "RCZONE_TEST_SLEEP": "0.4",
    }
    args = ["fit-many", str(manifest), "--out", str(out), "--backend", backend, "--workers", "2"]
    with open(err, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-c", COMMAND, *args],
            stdout=subprocess.DEVNULL,
            stderr=fh,
            env=env,
            start_new_session=True,  # its own process group: the coordinator and its workers
            cwd=tmp_path,
        )
    return proc, out, err


def wait_for_parts(proc: subprocess.Popen, out: Path, err: Path) -> int:
    """Wait until the run has stored a zone (and is still running); the zones stored."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        parts = list((out / "parts").glob("*.json")) if (out / "parts").is_dir() else []
        if parts:
            return len(parts)
        time.sleep(0.05)
    raise AssertionError(f"the run stored nothing while running (exit {proc.poll()}): {err.read_text()}")


def none_left(pgid: int, seconds: float) -> list[int]:
    """Wait up to ``seconds`` for the group to end; what is still alive."""
    deadline = time.monotonic() + seconds
    while (left := alive_in_group(pgid)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return left


@pytest.fixture
def group_cleanup():
    groups: list[int] = []
    yield groups
    for g in groups:  # whatever a failed test left behind
        try:
            os.killpg(g, signal.SIGKILL)
        except ProcessLookupError:
            pass


@pytest.mark.parametrize("backend", ["processes", pytest.param("dask", marks=pytest.mark.slow)])
def test_sigterm_to_the_coordinator_ends_the_run_as_ctrl_c(tmp_path, backend, group_cleanup):
    proc, out, err = start(tmp_path, backend)
    group_cleanup.append(proc.pid)
    wait_for_parts(proc, out, err)
    assert len(alive_in_group(proc.pid)) > 1  # the coordinator and its workers
    os.kill(proc.pid, signal.SIGTERM)  # the coordinator only, as kill or a job scheduler does
    code = proc.wait(timeout=60)
    text = err.read_text()
    assert code == 130 and "Traceback" not in text, text
    assert not none_left(proc.pid, 5.0), "worker processes outlived their coordinator"
    kept = [json.loads(p.read_text()) for p in (out / "parts").glob("*.json")]
    assert 1 <= len(kept) < len(ZONES)  # the zones stored before the signal are kept, whole
    assert {r["zone"] for r in kept} <= set(ZONES) and all(r["status"] == "ok" for r in kept)


@pytest.mark.parametrize("backend", ["processes", pytest.param("dask", marks=pytest.mark.slow)])
def test_workers_end_a_few_seconds_after_their_coordinator_is_killed(tmp_path, backend, group_cleanup):
    proc, out, err = start(tmp_path, backend)
    group_cleanup.append(proc.pid)
    wait_for_parts(proc, out, err)
    workers = [p for p in alive_in_group(proc.pid) if p != proc.pid]
    assert workers
    os.kill(proc.pid, signal.SIGKILL)  # no handler runs in the coordinator
    assert proc.wait(timeout=30) == -signal.SIGKILL
    left = none_left(proc.pid, 5.0)
    assert not left, f"{len(left)} worker process(es) alive 5 s after the coordinator was killed"
