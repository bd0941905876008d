"""Forward model selection on the Bacher & Madsen PRBS data (outside the project; skips without them)."""

import json

import pytest

from tests.shared_data import SHARED, require

from .scripts import assert_on_page
from .scripts import load_script as load


def load_script():
    return load("model_selection")


def test_the_comparison_table_puts_the_path_beside_the_published_one():
    res = {"forward": {"path": ["Ti+solar", "TiTh+solar", "TiTeTh+solar", "TiTeThRia+solar"]}}
    table = load_script().comparison(res)
    assert "| rczone | Ti → TiTh → TiTeTh → TiTeThRia | TiTeThRia |" in table
    assert "| Bacher & Madsen (2011) | Ti → TiTh → TiTeTh → … | TiTmTeThAeRia |" in table


def test_skips_cleanly_without_data(tmp_path, capsys):
    assert load_script().main(["--shared", str(tmp_path / "nothing"), "--out", str(tmp_path)]) == 0
    assert "skipped: data not found" in capsys.readouterr().out


@pytest.mark.slow
def test_forward_selection_runs_on_the_prbs_experiment(tmp_path):
    require(SHARED / "data" / "bacher_madsen_prbs", what="shared real data")
    assert load_script().main(["--shared", str(SHARED), "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "model_selection.json").read_text())
    steps = res["forward"]["steps"]
    assert res["forward"]["path"][0] == "Ti+heater+solar" and steps[0]["accepted"]
    # each accepted step raised the likelihood significantly; the selected model is the last accepted
    assert all(s["p_value"] < 0.05 for s in steps if s["accepted"])
    assert res["selected"] == res["forward"]["path"][-1] != "Ti+heater+solar"
    # the extended family carries the path past TiTeTh, where the classic five stop
    path = [name.partition("+")[0] for name in res["forward"]["path"]]
    assert path[:3] == ["Ti", "TiTh", "TiTeTh"] and len(path) > 3, path
    assert (tmp_path / "model_selection" / "report.html").is_file()
    # docs/validation.md's tables of the whole family are this run's, each candidate's verdict included
    assert_on_page(load_script().markdown(res), after="### The whole family")


@pytest.mark.slow
def test_the_classic_five_on_the_page_are_a_fresh_runs(tmp_path):
    """``--classic``: the five candidates of ``select`` by a criterion, the first tables of the section."""
    require(SHARED / "data" / "bacher_madsen_prbs", what="shared real data")
    assert load_script().main(["--shared", str(SHARED), "--out", str(tmp_path), "--classic"]) == 0
    res = json.loads((tmp_path / "model_selection_classic.json").read_text())
    assert set(res["models"]) == {f"{b}+heater+solar" for b in load_script().CLASSIC}
    assert_on_page(load_script().markdown(res), after="## Model selection on the Bacher")
