"""Batch fault tests (issue 14): kill a worker, kill the scheduler, fill the disk, two runs at once.

The invariants: nothing stored is lost or computed again, and no failure is stored that was not
the zone's own. The infrastructure is real (worker processes killed with ``os.kill``, a Dask
``LocalCluster`` in another process killed with its scheduler, a small tmpfs that fills up); the
calibration itself is replaced by a quick stand-in (:func:`quick_tasks`) that logs every zone it
computes, so the tests can count what was computed, and run in seconds. Forked workers inherit
the stand-in through ``monkeypatch``; Dask workers import it from this module.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

import rczone.batch.runner as runner
from rczone.batch import ResultStore, read_manifest, run_batch
from rczone.batch.store import FolderBusyError
from rczone.cli.main import main

LOG_ENV = "RCZONE_TEST_COMPUTED_LOG"
ROOT = Path(__file__).resolve().parents[3]


def quick_tasks(tasks: list) -> list[dict]:
    """Stand-in for run_tasks: a little work, a log line per zone, then rows like run_task's.

    A zone named ``die-*`` kills its own worker (as the kernel's out-of-memory killer would), a
    zone named ``oom-*`` raises MemoryError, and ``bad-*`` fails with its own error.
    """
    zone = tasks[0].zone
    if zone.startswith("die-"):
        os.kill(os.getpid(), signal.SIGKILL)
    if zone.startswith("oom-"):
        raise MemoryError("cannot allocate")
    time.sleep(float(os.environ.get("RCZONE_TEST_SLEEP", "0.05")))
    log = os.environ.get(LOG_ENV)
    if log:
        with open(log, "a") as fh:
            fh.write(zone + "\n")
    bad = zone.startswith("bad")
    return [
        {
            "key": t.key,
            "zone": t.zone,
            "method": t.method,
            "model": t.model,
            "source": "test",
            "status": "failed" if bad else "ok",
            "error": "DataError: the zone's own problem" if bad else "",
            "Rw": None if bad else 0.005,
            "Rw_se": None if bad else 0.001,
            "converged": not bad,
            "n_evals": 10,
            "flags": "x" * int(os.environ.get("RCZONE_TEST_PAD", "0")),
            "seconds": 0.05,
        }
        for t in tasks
    ]


def write_manifest(folder: Path, zones: list[str], **settings: str) -> Path:
    # one local search per zone: the faults are tested, not the search
    text = (
        'methods = ["ls"]\ndiagnose = false\n'
        + ("" if "n_starts" in settings else "n_starts = 1\n")
        + "".join(f"{k} = {v}\n" for k, v in settings.items())
    )
    text += "".join(
        f'[[zone]]\nid = "{z}"\nvirtual = {{ season = "autumn", seed = {i} }}\n' for i, z in enumerate(zones)
    )
    path = folder / "m.toml"
    path.write_text(text)
    return path


def computed(log: Path) -> list[str]:
    return log.read_text().split() if log.exists() else []


@pytest.fixture
def quick(monkeypatch, tmp_path):
    """Replace the calibration by :func:`quick_tasks`; return the log of computed zones."""
    log = tmp_path / "computed.log"
    monkeypatch.setenv(LOG_ENV, str(log))
    monkeypatch.setattr(runner, "run_tasks", quick_tasks)
    return log


def stored_errors(out: Path) -> list[str]:
    return [json.loads(p.read_text())["error"] for p in (out / "parts").glob("*.json")]


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_killing_a_worker_loses_nothing_and_stores_no_failure(tmp_path, quick, monkeypatch):
    """Defect 1: killing one worker stored BrokenProcessPool as the result of 376 of 400 zones."""
    monkeypatch.setenv("RCZONE_TEST_SLEEP", "0.3")
    zones = [f"z{i}" for i in range(12)]
    m = read_manifest(write_manifest(tmp_path, zones))
    killed = []

    def on_result(row, done, total):
        if done == 3 and not killed:
            victim = multiprocessing.active_children()[0]
            os.kill(victim.pid, signal.SIGKILL)
            killed.append(victim.pid)

    run = run_batch(m, tmp_path / "out", backend="processes", workers=2, on_result=on_result)
    assert killed
    assert (run.computed, run.failed, run.lost) == (12, 0, 0)
    assert all(e == "" for e in stored_errors(tmp_path / "out"))
    assert sorted(pd.read_parquet(run.results)["zone"]) == sorted(zones)
    # the zone in flight on the killed worker ran twice (once lost), every other zone once
    counts = pd.Series(computed(quick)).value_counts()
    assert set(counts.index) == set(zones) and counts.max() == 1


def test_a_worker_killed_between_zones_is_replaced(tmp_path, quick, monkeypatch):
    """An idle worker that died made the next submission raise BrokenProcessPool out of the batch."""
    monkeypatch.setenv("RCZONE_TEST_SLEEP", "0.05")
    zones = [f"z{i}" for i in range(5)]
    m = read_manifest(write_manifest(tmp_path, zones))
    killed = []

    def on_result(row, done, total):
        if done in (1, 3):  # the only worker is idle now: its zone is done, the next not yet submitted
            for child in multiprocessing.active_children():
                os.kill(child.pid, signal.SIGKILL)
                killed.append(child.pid)
            time.sleep(0.2)  # let the executor notice, so the next submission meets a broken pool

    run = run_batch(m, tmp_path / "out", backend="processes", workers=1, on_result=on_result)
    assert killed
    assert (run.computed, run.failed, run.lost) == (5, 0, 0)
    assert sorted(pd.read_parquet(run.results)["zone"]) == sorted(zones)


@pytest.mark.parametrize("culprit", ["die-0", "oom-0"])
def test_a_zone_that_kills_its_worker_is_retried_never_stored(tmp_path, quick, capsys, culprit):
    """Defect 1: a zone exhausting memory took the queue with it and the command exited 0."""
    zones = ["a", culprit, "b", "bad-c", "d"]
    path = write_manifest(tmp_path, zones)
    out = tmp_path / "out"
    args = ["fit-many", str(path), "--out", str(out), "--backend", "processes", "--workers", "2"]
    assert main(args) == 5
    captured = capsys.readouterr()
    assert "1 calibration(s) could not run" in captured.err and "rerun the same command" in captured.err
    assert "Traceback" not in captured.err
    keys = set(pd.read_parquet(out / "results.parquet")["key"])
    assert keys == {"a::ls", "b::ls", "bad-c::ls", "d::ls"}  # the culprit is not stored
    assert sorted(computed(quick)) == ["a", "b", "bad-c", "d"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tasks"] == 4 and summary["failed"] == 1  # only the zone's own error
    # the next run tries the lost zone again (and only it)
    assert main(args) == 5
    assert sorted(computed(quick)) == ["a", "b", "bad-c", "d"]


def test_own_failures_exit_4_and_a_complete_batch_exits_0(tmp_path, quick, capsys):
    path = write_manifest(tmp_path, ["a", "bad[/]zone [vav-3]"])
    out = tmp_path / "out"
    args = ["fit-many", str(path), "--out", str(out), "--backend", "processes", "--workers", "1"]
    assert main(args) == 4
    # defect 7: the zone id is printed as written (rich markup was parsed and crashed)
    assert "failed bad[/]zone [vav-3] (ls): DataError" in capsys.readouterr().out
    assert main(args) == 4  # a rerun resumes and still reports the stored failure
    ok = write_manifest(tmp_path, ["a"])
    assert main(["fit-many", str(ok), "--out", str(tmp_path / "ok"), "--backend", "processes"]) == 0


def test_a_changed_setting_is_computed_again_not_resumed(tmp_path, quick):
    """Defect 4: parts keyed by zone and method only resumed results of another optimizer."""
    out = tmp_path / "out"
    run_batch(read_manifest(write_manifest(tmp_path, ["a", "b"])), out, backend="processes", workers=1)
    again = run_batch(
        read_manifest(write_manifest(tmp_path, ["a", "b"], optimizer='"powell"')),
        out,
        backend="processes",
        workers=1,
    )
    assert (again.skipped, again.computed) == (0, 2)
    same = run_batch(
        read_manifest(write_manifest(tmp_path, ["a", "b"], optimizer='"powell"')),
        out,
        backend="processes",
        workers=1,
    )
    assert (same.skipped, same.computed) == (2, 0)
    assert computed(quick) == ["a", "b", "a", "b"] or sorted(computed(quick)) == ["a", "a", "b", "b"]


CONCURRENT = """
import sys
import rczone.batch.runner as runner
from tests.unit.batch.test_faults import quick_tasks
from rczone.batch import read_manifest, run_batch
runner.run_tasks = quick_tasks
run = run_batch(read_manifest(sys.argv[1]), sys.argv[2], backend="processes", workers=1)
print(run.computed)
"""


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_two_runs_into_one_folder_never_disagree(tmp_path, quick, capsys):
    """Defect 8: concurrent runs doubled the work and left results.parquet disagreeing with summary.json."""
    zones = [f"z{i}" for i in range(10)]
    path = write_manifest(tmp_path, zones)
    out = tmp_path / "out"
    env = {**os.environ, "RCZONE_TEST_SLEEP": "0.3", "PYTHONPATH": str(ROOT)}
    first = subprocess.Popen(
        [sys.executable, "-c", CONCURRENT, str(path), str(out)], env=env, stdout=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not list((out / "parts").glob("*.json")):
        time.sleep(0.05)
    assert first.poll() is None, "the first run must still be running"
    with pytest.raises(FolderBusyError, match=r"is in use by another run \(pid \d+\)"):
        run_batch(read_manifest(path), out, backend="processes", workers=1)
    assert main(["fit-many", str(path), "--out", str(out), "--backend", "processes"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: results folder")
    assert first.communicate(timeout=120)[0].strip() == "10"
    again = run_batch(read_manifest(path), out, backend="processes", workers=1)
    assert (again.computed, again.skipped) == (0, 10)
    assert sorted(computed(quick)) == sorted(zones)  # nothing computed twice
    table = pd.read_parquet(out / "results.parquet")
    summary = json.loads((out / "summary.json").read_text())
    assert len(table) == summary["tasks"] == 10


def _tmpfs(path: Path, size: str) -> bool:
    path.mkdir(exist_ok=True)
    if os.geteuid() != 0:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)]).returncode == 0


def test_a_full_disk_stops_the_run_with_one_line_and_the_rerun_resumes(tmp_path, quick, monkeypatch, capsys):
    """A real full disk: a 96 KiB tmpfs. Parts stored before it filled stay complete and are resumed."""
    disk = tmp_path / "disk"
    if not _tmpfs(disk, "96k"):
        pytest.skip("mounting a tmpfs needs root (the monkeypatched ENOSPC test covers the rest)")
    try:
        monkeypatch.setenv("RCZONE_TEST_PAD", "6000")
        zones = [f"z{i}" for i in range(30)]
        path = write_manifest(tmp_path, zones)
        out = disk / "out"
        args = ["fit-many", str(path), "--out", str(out), "--backend", "processes", "--workers", "1"]
        assert main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err[-1].startswith("error: cannot write") and err[-1].endswith("no space left on the device")
        assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]  # no partial file
        stored = ResultStore(out).done()
        assert 0 < len(stored) < len(zones)
        first = computed(quick)
        subprocess.run(["mount", "-o", "remount,size=8m", str(disk)], check=True)  # space is freed
        assert main(args) == 0
        again = computed(quick)[len(first) :]
        assert sorted(again) == sorted(z for z in zones if f"{z}::ls" not in stored)  # none stored redone
        assert len(pd.read_parquet(out / "results.parquet")) == len(zones)
    finally:
        subprocess.run(["umount", "-l", str(disk)])


def test_a_full_disk_by_enospc_from_the_operating_system(tmp_path, quick, monkeypatch, capsys):
    """The same without root: the fourth write of a part fails with ENOSPC (monkeypatched os.replace)."""
    import errno

    import rczone.files.atomic as atomic

    real, calls = os.replace, []

    def replace(src, dst):
        calls.append(dst)
        if len(calls) == 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    path = write_manifest(tmp_path, [f"z{i}" for i in range(6)])
    out = tmp_path / "out"
    args = ["fit-many", str(path), "--out", str(out), "--backend", "processes", "--workers", "1"]
    assert main(args) == 2
    assert capsys.readouterr().err.strip().endswith("no space left on the device")
    assert len(ResultStore(out).done()) == 3
    assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]
    monkeypatch.setattr(atomic.os, "replace", real)
    assert main(args) == 0
    assert sorted(computed(quick)).count("z0") == 1  # stored before the disk filled: not redone


CLUSTER = """
import sys, time
from dask.distributed import LocalCluster
cluster = LocalCluster(n_workers=int(sys.argv[1]), threads_per_worker=1, processes=True,
                       dashboard_address=None)
print(cluster.scheduler_address, flush=True)
time.sleep(600)
"""


def _cluster(workers: int, env: dict) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [sys.executable, "-c", CLUSTER, str(workers)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        start_new_session=True,
    )
    return proc, proc.stdout.readline().strip()


@pytest.mark.slow
def test_killing_the_dask_scheduler_stores_nothing_lost_and_the_rerun_computes_the_rest(tmp_path, quick):
    """Defect 1: a lost Dask scheduler stored FutureCancelledError as results."""
    pytest.importorskip("dask.distributed")
    env = {**os.environ, "RCZONE_TEST_SLEEP": "0.5", "PYTHONPATH": str(ROOT)}
    zones = [f"z{i}" for i in range(30)]
    m = read_manifest(write_manifest(tmp_path, zones))
    out = tmp_path / "out"
    proc, address = _cluster(2, env)
    try:

        def on_result(row, done, total):
            if done == 4:
                os.killpg(proc.pid, signal.SIGKILL)  # the scheduler, its nannies and workers

        run = run_batch(m, out, scheduler=address, on_result=on_result)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert run.lost > 0 and run.computed + run.lost == len(zones)
    assert all(e == "" for e in stored_errors(out))  # no cancelled future stored as a result
    stored = ResultStore(out).done()
    proc, address = _cluster(2, env)
    try:
        again = run_batch(m, out, scheduler=address)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert (again.skipped, again.computed, again.lost) == (len(stored), len(zones) - len(stored), 0)
    assert len(pd.read_parquet(again.results)) == len(zones)


@pytest.mark.slow
def test_killing_a_dask_worker_loses_nothing(tmp_path, quick):
    pytest.importorskip("dask.distributed")
    env = {**os.environ, "RCZONE_TEST_SLEEP": "0.3", "PYTHONPATH": str(ROOT)}
    zones = [f"z{i}" for i in range(12)]
    proc, address = _cluster(2, env)
    try:
        from dask.distributed import Client

        with Client(address) as c:
            pids = list(c.run(os.getpid).values())

        def on_result(row, done, total):
            if done == 2:
                os.kill(pids[0], signal.SIGKILL)

        run = run_batch(
            read_manifest(write_manifest(tmp_path, zones)),
            tmp_path / "out",
            scheduler=address,
            on_result=on_result,
        )
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert (run.computed, run.failed, run.lost) == (12, 0, 0)
    assert all(e == "" for e in stored_errors(tmp_path / "out"))


def test_a_cluster_without_workers_gives_up_with_a_reason(tmp_path, quick):
    """Defect 12: a Dask cluster with no workers waited forever, silently."""
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as c:
        run = run_batch(
            read_manifest(write_manifest(tmp_path, ["a", "b"])),
            tmp_path / "out",
            scheduler=c.scheduler_address,
            worker_timeout=1.0,
        )
    assert (run.computed, run.lost) == (0, 2)
    assert "no Dask worker joined" in run.lost_reasons[0] and "within 1 s" in run.lost_reasons[0]
    assert ResultStore(tmp_path / "out").done() == set()


@pytest.mark.parametrize(
    ("address", "match"),
    [
        ("not-an-address", r"--scheduler 'not-an-address' is not a Dask scheduler address"),
        ("tcp://", r"is not a Dask scheduler address"),
        ("tcp://127.0.0.1:1", r"cannot connect to the Dask scheduler 'tcp://127.0.0.1:1'"),
    ],
)
def test_a_bad_scheduler_address_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, address, match):
    pytest.importorskip("dask.distributed")
    monkeypatch.setattr(runner, "CONNECT_TIMEOUT", 2.0)
    path = write_manifest(tmp_path, ["a"])
    assert main(["fit-many", str(path), "--out", str(tmp_path / "o"), "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.search(match, err), err


def test_out_at_a_file_is_one_line_and_exit_2(tmp_path, capsys):
    path = write_manifest(tmp_path, ["a"])
    (tmp_path / "taken").write_text("a file")
    assert main(["fit-many", str(path), "--out", str(tmp_path / "taken")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a file, not a folder" in err


def test_a_unit_whose_zone_runs_out_of_memory_is_split_and_only_that_zone_is_lost(tmp_path, quick):
    """Issue 24: zones travel in units; a unit that fails is rerun zone by zone, so one zone costs only itself."""
    distributed = pytest.importorskip("dask.distributed")
    zones = ["a", "oom-0", "b", "c", "d"]
    m = read_manifest(write_manifest(tmp_path, zones))
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as c:
        run = run_batch(m, tmp_path / "out", scheduler=c.scheduler_address, unit=3)
    assert (run.computed, run.failed, run.lost) == (4, 0, 1)
    assert "MemoryError" in run.lost_reasons[0]
    assert sorted(pd.read_parquet(run.results)["zone"]) == ["a", "b", "c", "d"]
    # units [a, oom-0, b] and [c, d]; the first failed and ran again as three single zones
    assert run.submitted == 2 + 3 and run.workers == 1
    counts = pd.Series(computed(quick)).value_counts()
    assert counts["a"] == 2 and counts["b"] == counts["c"] == counts["d"] == 1


def test_rows_stream_to_parquet_while_the_run_goes_on(tmp_path, quick, monkeypatch):
    """Issue 24: the rows are readable as Parquet during the run; results.parquet replaces the stream at the end."""
    import rczone.batch.store as store

    monkeypatch.setattr(store, "STREAM_ROWS", 3)
    zones = [f"z{i}" for i in range(8)]
    out = tmp_path / "out"
    seen = {}

    def on_result(row, done, total):
        if done == 7:
            seen["stream"] = pd.read_parquet(out / "stream")

    run = run_batch(
        read_manifest(write_manifest(tmp_path, zones)),
        out,
        backend="processes",
        workers=1,
        on_result=on_result,
    )
    assert run.computed == 8
    # segments of 3 rows: after 7 rows stored, the first 6 are in the stream, as stored
    streamed = seen["stream"].sort_values("key")
    assert len(streamed) == 6 and set(streamed["key"]) <= {f"{z}::ls" for z in zones}
    assert (streamed["Rw"] == 0.005).all() and streamed["fingerprint"].str.len().eq(32).all()
    assert list((out / "stream").iterdir()) == []  # the table holds every row now
    assert len(pd.read_parquet(out / "results.parquet")) == 8
