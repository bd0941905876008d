"""fit-many flags a zone whose record drifts: truth by construction.

The zone is the virtual one of ``tests/unit/calibration/test_drift.py`` (simulated there from its
heat balance, exact discretization): from day 4 its envelope resistance halves or its sensor
reads 1 K high. The record's second half is tested against its first
(:func:`rczone.calibration.drift.record_drift`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.batch import read_manifest, run_batch
from rczone.batch.store import valid_row
from rczone.batch.summary import summarize
from rczone.calibration.dataset import dataset
from rczone.calibration.drift import record_drift
from tests.unit.calibration.test_drift import DAY, model, virtual_zone  # noqa: F401  (fixture)
from tests.unit.estimation.test_initial_state import MODEL

CHANGES = {"changed": {"rea_factor": 0.5}, "bias": {"bias_K": 1.0}, "steady": {}}


@pytest.mark.parametrize("zone", ["changed", "bias"])
def test_a_record_whose_zone_changes_on_day_4_is_flagged_within_a_day(model, zone):  # noqa: F811
    check = record_drift(model, dataset(model, virtual_zone(11, days=7.0, **CHANGES[zone])))
    assert check.drifted, zone
    assert 4 * DAY <= check.detected_s <= 5 * DAY, check.detected_s / DAY
    assert check.since_s <= check.detected_s and "DRIFTED" in check.describe()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_an_unchanged_record_is_not_flagged(model, seed):  # noqa: F811
    check = record_drift(model, dataset(model, virtual_zone(seed, days=7.0)))
    assert not check.drifted and "Ti" in check.traces, check.describe()
    assert "only the CUSUM" in check.notes[-1]
    assert check.to_dict()["settings"]["cusum_reference"] == "self-starting"


def test_the_second_half_is_scored_from_its_first_block_against_the_first_half(model):  # noqa: F811
    # the trace starts at the record's middle: every block of the second half is scored, the
    # first one against the first half's blocks only
    check = record_drift(model, dataset(model, virtual_zone(1, days=7.0)))
    trace = check.traces["Ti"]
    assert 3.5 * DAY < trace.t[0] <= 3.5 * DAY + 3600.0 and trace.t[-1] > 6.9 * DAY
    assert np.isfinite(trace.mean_up).all() and (trace.mean_up >= 0).all()


def test_a_short_record_or_a_model_without_noise_is_not_tested(model):  # noqa: F811
    short = record_drift(model, dataset(model, virtual_zone(1, days=0.5)))
    assert not short.drifted and not short.traces and "too short" in short.notes[0]
    noiseless = model.with_values(model.theta, {})
    assert record_drift(noiseless, dataset(noiseless, virtual_zone(1, days=2.0))) is None


def test_the_drift_columns_are_stored_and_the_summary_lists_the_drifted_zones():
    rows = [
        {"key": f"{z}/ml", "zone": z, "method": "ml", "status": "ok", "fingerprint": "f", "trustworthy": True}
        | {"drift": d, "drift_since_s": s, "drift_detected_s": s, "drift_tests": tests}
        for z, d, s, tests in [
            ("a", True, 3.6e5, "innovation mean of Ti"),
            ("b", False, None, ""),
            ("c", None, None, None),
        ]
    ]
    assert all(valid_row(r) for r in rows)
    assert not valid_row({**rows[0], "drift": "yes"})
    drifted = summarize(pd.DataFrame(rows))["drifted"]
    assert drifted == [{"zone": "a", "method": "ml", "since_s": 3.6e5, "tests": "innovation mean of Ti"}]


@pytest.mark.slow
def test_fit_many_flags_the_zones_that_changed_and_not_the_one_that_did_not(tmp_path):
    (tmp_path / "zone.toml").write_text(MODEL)
    for z, change in CHANGES.items():
        virtual_zone(11, days=7.0, **change).to_csv(tmp_path / f"{z}.csv", index=False)
    zones = "".join(f'[[zone]]\nid = "{z}"\ndata = "{z}.csv"\n' for z in CHANGES)
    (tmp_path / "m.toml").write_text(
        f'model = "zone.toml"\nmethods = ["ml"]\ndiagnose = false\nn_starts = 1\n{zones}'
    )
    run = run_batch(read_manifest(tmp_path / "m.toml"), tmp_path / "out", backend="processes", workers=1)
    table = run.table.set_index("zone")
    assert (table["status"] == "ok").all(), table["error"].tolist()
    assert table.loc["changed", "drift"] and table.loc["bias", "drift"] and not table.loc["steady", "drift"]
    # the change is found in the record's second half, within a day of it
    assert 4 * DAY <= table.loc["changed", "drift_detected_s"] <= 5 * DAY
    assert np.isnan(table.loc["steady", "drift_since_s"])
    assert {d["zone"] for d in run.totals["drifted"]} == {"changed", "bias"}
    assert any("show drift" in line for line in run.summary_lines())
    assert "Drift" in (tmp_path / "out" / "report.html").read_text()


def test_a_drift_test_that_cannot_run_leaves_the_fit_standing(monkeypatch, model):  # noqa: F811
    from rczone.batch import task
    from rczone.calibration import drift
    from rczone.errors import DataError

    def broken(*_args):
        raise DataError("the filter diverged")

    monkeypatch.setattr(drift, "record_drift", broken)
    cols = task._drift_columns(model, None)
    assert cols == {"drift": None, "drift_tests": "not tested: DataError: the filter diverged"}
    assert valid_row({"key": "a", "zone": "a", "method": "ml", "status": "ok", "fingerprint": "f", **cols})
