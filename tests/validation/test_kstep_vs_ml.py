"""ML against k-step on real data (outside the project; skips without them, fails under CI=true)."""

import json

import pytest

from tests.shared_data import SHARED, require

from .scripts import assert_on_page, load_script


def test_skips_cleanly_without_data(tmp_path, capsys):
    code = load_script("kstep_vs_ml").main(["--shared", str(tmp_path / "nothing"), "--out", str(tmp_path)])
    assert code == 0 and "skipped: data not found" in capsys.readouterr().out


@pytest.mark.slow
def test_the_page_has_a_fresh_runs_table(tmp_path):
    """Both fits of each data set through ``rczone.fit``, scored on the held-out quarter; the page's table is this run's."""
    mod = load_script("kstep_vs_ml")
    require(*(SHARED / "data" / path for path, _ in mod.DATASETS.values()), what="shared real data")
    assert mod.main(["--shared", str(SHARED), "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "kstep_vs_ml.json").read_text())
    for r in res.values():
        # the last quarter held out (``rczone fit --holdout 0.25``), the first scored horizon one step
        n = r["calibration_samples"] + r["held_out_samples"]
        assert abs(r["held_out_samples"] - 0.25 * n) <= 1 and next(iter(r["ml"]["scores"])) == "1"
        for method in ("ml", "kstep"):
            assert set(r[method]["verdict"]) >= {"trustworthy", "reasons", "held_out"}
            assert r[method]["verdict"]["held_out"] is not None  # fitted with the held-out part: checked
    assert_on_page(mod.markdown(res))
