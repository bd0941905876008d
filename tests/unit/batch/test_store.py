"""The results store: exact round trip, atomic parts, damaged files ignored, one row per task."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from rczone.batch.store import RESULTS, ResultStore, part_name


def row(key: str, **extra) -> dict:
    return {"key": key, "zone": key.split("::")[0], "method": "ls", "status": "ok", "error": "", **extra}


def test_rows_round_trip_exactly_through_parts_and_the_table(tmp_path):
    store = ResultStore(tmp_path)
    x = 0.1 + 0.2  # not representable in a short decimal: must come back bit for bit
    store.write(row("a::ls", Rw=x, Rw_se=np.float64(1e-300), n=np.int64(7), ok=np.bool_(True), s=math.nan))
    store.write(row("b::ls", status="failed", error="DataError: no column 'Ti'"))
    again = ResultStore(tmp_path)  # a new run reads the parts from disk
    assert again.done() == {"a::ls", "b::ls"}
    df = again.table().set_index("key")
    assert df.loc["a::ls", "Rw"] == x and df.loc["a::ls", "Rw_se"] == 1e-300
    assert df.loc["a::ls", "n"] == 7 and bool(df.loc["a::ls", "ok"]) is True
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
