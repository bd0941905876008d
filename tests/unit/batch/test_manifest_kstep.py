"""A ``fit-many`` manifest with ``method = "kstep"``: its options reach the fit, and the fit finds the truth.

The zone is the virtual one of ``tests/unit/calibration/test_drift.py`` (simulated from its heat
balance by exact discretization; its R and C known by construction), unchanged for three days.
"""

from __future__ import annotations

import tomllib

import pytest

from rczone.batch import read_manifest, run_batch
from rczone.batch.manifest import parse_manifest
from rczone.errors import DataError
from rczone.estimation.methods.kstep import KStepOptions
from tests.unit.calibration.test_drift import TRUTH, virtual_zone
from tests.unit.estimation.test_initial_state import MODEL

ZONE = '[[zone]]\nid = "v"\ndata = "zone.csv"\n'


def test_the_kstep_options_of_a_manifest_reach_its_tasks(tmp_path):
    text = f'model = "second-order-paper"\nmethods = ["ml", "kstep"]\noptions = {{ kstep = {{ horizons = [1, 12] }} }}\n{ZONE}'
    tasks = {t.method: t for t in parse_manifest(tomllib.loads(text), tmp_path / "m.toml").tasks}
    assert tasks["kstep"].settings.options == KStepOptions(horizons=(1, 12))
    assert tasks["kstep"].settings.options != KStepOptions()  # not the defaults (1, 12, 72)
    assert tasks["ml"].settings.options.to_dict() == {}


@pytest.mark.parametrize("horizons", ["[0, 12]", "[1.5]", "[true]"])
def test_bad_kstep_horizons_in_a_manifest_are_one_line(tmp_path, horizons):
    text = f'methods = ["kstep"]\noptions = {{ kstep = {{ horizons = {horizons} }} }}\n{ZONE}'
    with pytest.raises(DataError, match="horizons") as info:
        parse_manifest(tomllib.loads(text), tmp_path / "m.toml")
    assert "\n" not in str(info.value) and str(info.value).startswith("manifest ")


@pytest.mark.slow
def test_fit_many_with_kstep_recovers_the_virtual_zones_resistances_and_capacities(tmp_path):
    (tmp_path / "zone.toml").write_text(MODEL)
    virtual_zone(11, days=3.0).to_csv(tmp_path / "zone.csv", index=False)
    (tmp_path / "m.toml").write_text(
        'model = "zone.toml"\nmethods = ["kstep"]\ndiagnose = false\nn_starts = 1\n'
        f"options = {{ kstep = {{ horizons = [1, 12] }} }}\n{ZONE}"
    )
    run = run_batch(read_manifest(tmp_path / "m.toml"), tmp_path / "out", backend="processes", workers=1)
    (row,) = run.table.to_dict("records")
    assert row["status"] == "ok" and row["method"] == "kstep", row["error"]
    names = {"ci": "Ci", "ce": "Ce", "rie": "Rie", "rea": "Rea"}
    for key, name in names.items():
        assert abs(row[name] / TRUTH[key] - 1) < 0.2, (name, row[name], TRUTH[key])
        assert row[f"{name}_se"] > 0  # the sandwich's
    assert row["drift"] is False or row["drift"] == False  # noqa: E712  (an unchanged zone)
