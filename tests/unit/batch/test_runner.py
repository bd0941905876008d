"""Running a batch: failures recorded, resume, the Dask path, and a kill in the middle."""

import json
import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from rczone.batch import ResultStore, read_manifest, run_batch, write_summary
from rczone.cli.main import main

MANIFEST = """
methods = ["ls"]
diagnose = false

[[zone]]
id = "forced"
virtual = { season = "autumn", mode = "forced", seed = 1 }

[[zone]]
id = "missing"
data = "no-such-file.csv"

[[zone]]
id = "garbage"
data = "garbage.csv"
"""


@pytest.fixture
def manifest(tmp_path):
    (tmp_path / "garbage.csv").write_text("time,Ti,To\n0,20,10\n60,20,10\n")
    (tmp_path / "m.toml").write_text(MANIFEST)
    return read_manifest(tmp_path / "m.toml")


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_failing_zones_are_recorded_and_the_batch_goes_on(tmp_path, manifest):
    run = run_batch(manifest, tmp_path / "out", backend="processes", workers=2)
    assert (run.total, run.computed, run.failed, run.skipped) == (3, 3, 2, 0)
    df = pd.read_parquet(run.results).set_index("zone")
    assert df.loc["forced", "status"] == "ok" and 0.002 < df.loc["forced", "Rw"] < 0.01
    assert "does not exist" in df.loc["missing", "error"]
    assert "missing column" in df.loc["garbage", "error"]
    s = write_summary(df.reset_index(), tmp_path / "out")
    assert s["ok"] == 1 and s["failed"] == 2 and {f["zone"] for f in s["failures"]} == {"missing", "garbage"}
    assert (tmp_path / "out" / "report.html").exists() and (tmp_path / "out" / "summary.json").exists()
    # a rerun computes nothing and keeps every row
    again = run_batch(manifest, tmp_path / "out", backend="processes")
    assert (again.computed, again.skipped) == (0, 3)
    assert len(pd.read_parquet(again.results)) == 3


def test_dask_scheduler_address_runs_the_same_code_path(tmp_path, manifest):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as c:
        run = run_batch(manifest, tmp_path / "out", scheduler=c.scheduler_address)
    assert (run.computed, run.failed) == (3, 2)
    assert set(pd.read_parquet(run.results)["key"]) == {t.key for t in manifest.tasks}


def test_scheduler_without_dask_is_a_clear_error(tmp_path, manifest, monkeypatch):
    import rczone.batch.runner as runner

    monkeypatch.setattr(runner, "have_dask", lambda: False)
    with pytest.raises(Exception, match=r"pip install 'rczone\[dask\]'"):
        run_batch(manifest, tmp_path / "out", scheduler="tcp://127.0.0.1:1")


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_killed_batch_reruns_without_losing_or_recomputing(tmp_path):
    """kill -9 the whole process group midway, rerun: every result once, none computed twice."""
    n = 16
    (tmp_path / "m.toml").write_text(
        f'methods = ["ls"]\ndiagnose = false\nn_starts = 1  # faults, not the search, are tested\n[[generate]]\nprefix = "k"\nseasons = ["autumn"]\n'
        f'modes = ["forced"]\nseeds = "0..{n - 1}"\n'
    )
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "rczone.cli",
        "fit-many",
        str(tmp_path / "m.toml"),
        "--out",
        str(out),
        "--backend",
        "processes",
        "--workers",
        "2",
    ]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    parts = out / "parts"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(parts.glob("*.json"))) < 3:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = {p.name: p.read_bytes() for p in parts.glob("*.json")}
    assert 3 <= len(before) < n, "the batch must be killed midway"
    assert not (out / "results.parquet").exists()
    store = ResultStore(out)
    done_before = store.done()
    run = run_batch(read_manifest(tmp_path / "m.toml"), out, backend="processes", workers=2)
    # none computed twice: the rerun computes exactly the tasks without a stored result
    assert run.skipped == len(done_before) and run.computed == n - len(done_before)
    # no result lost: the stored parts are untouched and the table has every task once
    assert all((parts / name).read_bytes() == data for name, data in before.items())
    df = pd.read_parquet(run.results)
    assert sorted(df["key"]) == sorted(f"k-autumn-forced-{i}::ls" for i in range(n))
    assert (df["status"] == "ok").all()


def test_cli_fit_many_prints_summary_and_bad_manifest_is_one_line(tmp_path, manifest, capsys):
    assert (  # 4: finished, and some zones failed with their own errors
        main(["fit-many", str(tmp_path / "m.toml"), "--out", str(tmp_path / "o"), "--backend", "processes"])
        == 4
    )
    out = capsys.readouterr().out
    assert "3 computed (2 failed)" in out and "failed missing (ls)" in out
    (tmp_path / "bad.toml").write_text('[[zone]]\nid = "a"\ndata = "C"\nmethods = ["lsq"]\n')
    assert main(["fit-many", str(tmp_path / "bad.toml")]) == 2
    err = capsys.readouterr().err
    assert "unknown method 'lsq'; did you mean 'ls'" in err and "Traceback" not in err


def test_fit_many_prints_the_runs_summary_and_the_result_follows_the_protocol(
    tmp_path, manifest, capsys, monkeypatch
):
    """Issue 20: the CLI prints ``summary()``; ``to_dict()`` holds summary.json, ``to_frame()`` the table."""
    import rczone.batch

    runs = []

    def recording(*args, **kwargs):
        runs.append(run_batch(*args, **kwargs))
        return runs[-1]

    monkeypatch.setattr(rczone.batch, "run_batch", recording)
    out = tmp_path / "o"
    assert main(["fit-many", str(tmp_path / "m.toml"), "--out", str(out), "--backend", "processes"]) == 4
    (run,) = runs
    printed = capsys.readouterr().out
    assert printed == run.summary(width=10_000)  # lines are never wrapped on the console either
    assert run.lost_lines() == [] and "failed missing (ls)" in printed
    d = run.to_dict()
    assert {k: v for k, v in d.items() if k != "run"} == json.loads((out / "summary.json").read_text())
    assert d["run"]["computed"] == 3 and d["run"]["failed"] == 2 and d["run"]["total"] == 3
    # both clocks are recorded (their ratio depends on the machine's load: not a property to test)
    assert d["run"]["cpu_seconds"] > 0 and d["run"]["compute_seconds"] > 0 and d["run"]["submitted"] == 3
    table, stored = run.to_frame(), pd.read_parquet(out / "results.parquet")
    assert list(table.columns) == list(stored.columns) and table["key"].tolist() == stored["key"].tolist()
    pd.testing.assert_series_equal(table["Rw"], stored["Rw"])
    assert "failed missing (ls)" in run._repr_html_() and "<table" in run._repr_html_()
    assert repr(run) == "<BatchRun: 3 computed, 0 resumed, 0 lost of 3>"


@pytest.mark.parametrize(
    ("zones", "workers", "size"),
    [(1, 1, 1), (31, 2, 1), (1000, 2, 31), (1000, 1, 62), (30_000, 32, 58), (10**6, 2, 64), (5, 64, 1)],
)
def test_units_give_each_worker_about_sixteen_tasks_of_at_most_64_zones(zones, workers, size):
    from rczone.batch.runner import MAX_UNIT, UNITS_PER_WORKER, unit_size

    assert unit_size(zones, workers) == size
    units = -(-zones // size)
    assert size == MAX_UNIT or size == 1 or units >= workers * UNITS_PER_WORKER


@pytest.mark.slow
def test_a_local_dask_cluster_of_two_processes_gives_the_results_of_local_processes(tmp_path):
    """The same zones on 2 Dask worker processes, in units of 2 zones, and on plain local processes:
    the same estimates bit for bit (data read in the workers, the model shared by a worker's zones)."""
    pytest.importorskip("dask.distributed")
    zones = "".join(
        f'[[zone]]\nid = "v{i}"\nvirtual = {{ season = "autumn", mode = "forced", seed = {i} }}\n'
        for i in range(5)
    )
    (tmp_path / "m.toml").write_text(f'methods = ["ls", "ml"]\ndiagnose = false\nn_starts = 1\n{zones}')
    m = read_manifest(tmp_path / "m.toml")
    dask_run = run_batch(m, tmp_path / "dask", backend="dask", workers=2, unit=2)
    plain = run_batch(m, tmp_path / "plain", backend="processes", workers=2)
    assert (dask_run.computed, dask_run.failed, dask_run.lost, dask_run.submitted) == (10, 0, 0, 3)
    assert dask_run.workers == 2 and 0 < dask_run.compute_seconds
    a = pd.read_parquet(dask_run.results).set_index("key")
    b = pd.read_parquet(plain.results).set_index("key")
    for col in ("Rw", "Cr", "Rw_se", "objective_value", "open_loop_rmse_K"):
        assert a[col].equals(b[col]), col


def test_the_manifests_fit_settings_reach_the_fit(tmp_path):
    """Issue 20: ``noise`` and ``seed`` of the manifest are the FitSettings the fit runs with."""
    from rczone.batch.task import run_tasks, task_model
    from rczone.network.stochastic import process_noise_names

    zone = '[[zone]]\nid = "v"\nvirtual = { season = "autumn", mode = "forced", seed = 3 }\n'
    rows = {}
    for noise in ("measured", "all"):
        (tmp_path / "m.toml").write_text(
            f'methods = ["ml"]\ndiagnose = false\nn_starts = 1\nnoise = "{noise}"\nseed = 5\n{zone}'
        )
        (task,) = read_manifest(tmp_path / "m.toml").tasks
        assert task.settings.noise == noise and task.settings.seed == 5
        (rows[noise],) = run_tasks([task])
        assert rows[noise]["status"] == "ok", rows[noise]["error"]
    net = task_model(task).network
    every = set(process_noise_names(net.state_names))
    measured = set(process_noise_names(net.outputs))
    assert measured < every  # the paper's 2-state model measures one of its two states
    assert {n for n in every if f"{n}_se" in rows["all"]} == every
    assert {n for n in every if f"{n}_se" in rows["measured"]} == measured


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_a_local_clusters_worker_leaves_without_teardown_but_flushes_its_output():
    # what _connect runs in its own workers: the process ends with code 0 and its buffered output
    # (a pipe: fully buffered) is written before it leaves
    code = (
        "from rczone.batch.runner import _exit_without_teardown\n"
        "import atexit, sys\n"
        "atexit.register(lambda: print('a handler registered before it', flush=True))\n"
        "_exit_without_teardown()\n"
        "print('result written', end='')\n"
        "sys.stderr.write('log line')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0
    assert done.stdout == "result written" and done.stderr == "log line"


def _profiler_setting() -> bool:
    import dask

    return bool(dask.config.get("distributed.worker.profile.enabled"))


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_the_runs_own_cluster_runs_its_workers_without_the_statistical_profiler():
    pytest.importorskip("dask.distributed")
    from rczone.batch.runner import _close, _connect

    client, cluster = _connect(None, 1)
    try:
        assert list(client.run(_profiler_setting).values()) == [False]
    finally:
        _close(client, cluster)
    assert _profiler_setting()  # the coordinator's own configuration is left as it was
