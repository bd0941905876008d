"""The results store: exact round trip, atomic parts, damaged files ignored, one row per task."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tomllib
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rczone.batch.manifest import parse_manifest
from rczone.batch.store import RESULTS, ResultStore, part_name
from rczone.errors import OutputError


def row(key: str, **extra) -> dict:
    zone = key.split("::")[0]
    return {
        "key": key,
        "zone": zone,
        "method": "ls",
        "status": "ok",
        "error": "",
        "fingerprint": "f",
        **extra,
    }


def test_rows_round_trip_exactly_through_parts_and_the_table(tmp_path):
    store = ResultStore(tmp_path)
    x = 0.1 + 0.2  # not representable in a short decimal: must come back bit for bit
    store.write(
        row(
            "a::ls", Rw=x, Rw_se=np.float64(1e-300), n_evals=np.int64(7), converged=np.bool_(True), s=math.nan
        )
    )
    store.write(row("b::ls", status="failed", error="DataError: no column 'Ti'"))
    again = ResultStore(tmp_path)  # a new run reads the parts from disk
    assert again.done() == {"a::ls", "b::ls"}
    df = again.table().set_index("key")
    assert df.loc["a::ls", "Rw"] == x and df.loc["a::ls", "Rw_se"] == 1e-300
    assert df.loc["a::ls", "n_evals"] == 7 and bool(df.loc["a::ls", "converged"]) is True
    assert math.isnan(df.loc["a::ls", "s"]) and math.isnan(df.loc["b::ls", "Rw"])
    path = again.consolidate()
    assert path == tmp_path / RESULTS
    back = pd.read_parquet(path)
    assert back["key"].tolist() == ["a::ls", "b::ls"] and back["Rw"].iloc[0] == x
    assert back["status"].tolist() == ["ok", "failed"] and back["error"].iloc[1].startswith("DataError")


def test_damaged_or_foreign_parts_are_not_results_and_rewrites_replace(tmp_path):
    store = ResultStore(tmp_path)
    store.write(row("a::ls", Rw=1.0))
    store.write(row("a::ls", Rw=2.0))  # a recomputed task replaces its part
    (store.parts / "half-written.json").write_text('{"key": "x::ls", "Rw"')
    (store.parts / "list.json").write_text("[1, 2]")
    (store.parts / "nokey.json").write_text('{"zone": "z"}')
    fresh = ResultStore(tmp_path)
    assert fresh.done() == {"a::ls"}
    assert fresh.table()["Rw"].tolist() == [2.0]
    assert sorted(
        p.name for p in store.parts.iterdir() if not p.name.startswith(("half", "list", "nokey"))
    ) == [part_name("a::ls")]  # no temporary file left behind


def test_empty_store_has_an_empty_table(tmp_path):
    store = ResultStore(tmp_path)
    assert store.done() == set() and store.table().empty
    assert pd.read_parquet(store.consolidate()).empty


def test_a_part_with_wrong_types_is_not_a_result_and_the_table_still_consolidates(tmp_path):
    """Issue 14, defect 9: a valid-JSON part with wrong types blocked every later run (ArrowInvalid)."""
    store = ResultStore(tmp_path)
    store.write(row("a::ls", Rw=1.0, converged=True, n_evals=3))
    store.write(row("b::ls", Rw=2.0, converged=False, n_evals=4))
    bad = store.parts / part_name("b::ls")
    for damaged in (
        {**row("b::ls"), "Rw": "a lot"},
        {**row("b::ls"), "converged": "yes"},
        {**row("b::ls"), "n_evals": 1.5},
        {**row("b::ls"), "zone": 7},
        {**row("b::ls"), "status": "great"},
        {**row("b::ls"), "Rw": [1, 2]},
        {**row("x::ls"), "Rw": 1.0},  # a row under another task's file name
    ):
        bad.write_text(json.dumps(damaged))
        fresh = ResultStore(tmp_path)
        assert fresh.done() == {"a::ls"}, damaged
        assert pd.read_parquet(fresh.consolidate())["key"].tolist() == ["a::ls"]


def test_done_needs_the_same_fingerprint(tmp_path):
    """Issue 14, defect 4: a part is resumed only by a task with every setting and file the same."""
    (tmp_path / "z.csv").write_text("time,Ti\n0,20\n")
    m = parse_manifest(
        tomllib.loads('[[zone]]\nid = "z"\ndata = "z.csv"\nmethods = ["ls"]'), tmp_path / "m.toml"
    )
    task = m.tasks[0]
    store = ResultStore(tmp_path / "out")
    store.write(row("z::ls", fingerprint=task.fingerprint))
    assert ResultStore(tmp_path / "out").done(m.tasks) == {"z::ls"}
    for changed in (
        replace(task, settings=replace(task.settings, optimizer="powell")),
        replace(task, settings=replace(task.settings, n_starts=3)),
        replace(task, settings=replace(task.settings, free=("Cr",))),
        replace(task, settings=replace(task.settings, constants={"Q": 10.0})),
        replace(task, settings=replace(task.settings, seed=1)),
        replace(task, settings=replace(task.settings, noise="all")),
        replace(task, diagnose=False),
        replace(task, model="first-order"),
    ):
        assert changed.fingerprint != task.fingerprint
        assert ResultStore(tmp_path / "out").done([changed]) == set()
    (tmp_path / "z.csv").write_text("time,Ti\n0,21\n")  # the data file changed
    assert ResultStore(tmp_path / "out").done(m.tasks) == set()


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_one_run_at_a_time_holds_the_folder(tmp_path):
    """Issue 14, defect 8: a second run into the same folder is refused with one line."""
    store = ResultStore(tmp_path)
    code = (
        "import sys; from rczone.batch.store import ResultStore\n"
        "try:\n    ResultStore(sys.argv[1]).locked().__enter__()\n"
        "except Exception as e:\n    print(type(e).__name__, e)\n"
    )
    with store.locked():
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True)
        assert out.stdout.startswith("FolderBusyError results folder") and f"pid {os.getpid()}" in out.stdout
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True)
    assert out.stdout == "" and out.returncode == 0  # released when the run ends


def test_a_file_where_the_folder_should_be_is_one_line(tmp_path):
    (tmp_path / "out").write_text("not a folder")
    with pytest.raises(OutputError, match=r"'.*out' is a file, not a folder; give a folder name"):
        ResultStore(tmp_path / "out")


def test_a_units_rows_are_written_together_and_one_that_cannot_be_leaves_the_others_stored(tmp_path):
    store = ResultStore(tmp_path)
    rows = [row(f"z{i}::ls", Rw=0.001 * (i + 1), n_evals=np.int64(i)) for i in range(20)]
    (store.parts / part_name("z7::ls")).mkdir()  # a folder where one part belongs
    with pytest.raises(OutputError, match=r"z7_ls-.*\.json': it is a folder"):
        store.write_all(rows)
    assert store.done() == {r["key"] for r in rows} - {"z7::ls"}  # in memory: what was written
    again = ResultStore(tmp_path)  # and on disk: every other part complete, nothing temporary left
    assert again.done() == store.done()
    assert again.table().set_index("key").loc["z19::ls", "Rw"] == 0.02
    assert sorted(p.name for p in store.parts.iterdir() if p.is_file()) == sorted(
        part_name(r["key"]) for r in rows if r["key"] != "z7::ls"
    )
    (store.parts / part_name("z7::ls")).rmdir()
    assert len(store.write_all(rows)) == 20 and ResultStore(tmp_path).done() == {r["key"] for r in rows}
