"""Latent-force disturbances on real data (outside the project; skips without them, fails under CI=true)."""

import json

import pytest

from rczone.network.stochastic import is_noise_name
from tests.shared_data import SHARED, require

from .scripts import assert_on_page
from .scripts import load_script as load

#: The data sets on which the issue asks for the disturbance to win (issue 23, done-when).
CHECKED = ("armadillo_pysip", "leec_classroom_vav")


def load_script():
    return load("latent_force")


def test_skips_cleanly_without_data(tmp_path, capsys):
    assert load_script().main(["--shared", str(tmp_path / "nothing"), "--out", str(tmp_path)]) == 0
    assert "skipped: data not found" in capsys.readouterr().out


@pytest.mark.slow
def test_a_disturbance_wins_on_two_real_data_sets(tmp_path):
    """Selected by the LR test, innovations closer to white, lower held-out 6-h prediction error.

    And honestly so: no R, C or hyper-parameter of either model at a bound of its box (a noise level
    may sit at one), so the disturbance is neither white noise in disguise nor propping up a
    model that has run out of its physical range.
    """
    require(*(SHARED / "data" / name for name in CHECKED), what="shared real data")
    args = ["--shared", str(SHARED), "--out", str(tmp_path)]
    for name in CHECKED:
        args += ["--only", name]
    assert load_script().main(args) == 0
    res = json.loads((tmp_path / "latent_force.json").read_text())
    assert set(res) == set(CHECKED)
    for name in CHECKED:
        r = res[name]
        assert r["test"]["restriction"] == "sd -> 0" and r["test"]["df"] == 2
        assert r["test"]["p_value"] < 0.05 and r["test"]["selected"] == "with", name
        assert r["with"]["ljung_box_p"] > r["without"]["ljung_box_p"], name
        assert r["with"]["rmse_6h_K"] < r["without"]["rmse_6h_K"], name
        for which in ("without", "with"):
            stuck = [n for n in r[which]["at_bound"] if not is_noise_name(n)]
            assert not stuck, (name, which, stuck)
    # docs/validation.md's rows of these data sets are this run's, each fit's verdict included
    assert_on_page(load_script().markdown(res), some_rows=True)
