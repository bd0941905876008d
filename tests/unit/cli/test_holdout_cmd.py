"""``rczone fit --holdout`` and ``rczone select --holdout``: fit before, score after, through the CLI."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rczone.cli.main import main
from tests.unit.selection.synthetic import prbs_zone


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("holdout")
    prbs_zone(days=2, seed=2).to_csv(d / "zone.csv", index=False)
    return d


def test_fit_holdout_fits_the_first_part_and_scores_the_rest(files, capsys):
    out, rep = files / "fit.json", files / "rep"
    n = len(pd.read_csv(files / "zone.csv"))
    args = ["fit", str(files / "zone.csv"), "--model", "TiTe+heater", "--starts", "1", "--holdout", "0.25"]
    assert main([*args, "--json", str(out), "--report", str(rep), "--no-profiles"]) in (0, 3)
    text = capsys.readouterr().out
    assert "(held out)" in text and "persistence" in text and "open loop" in text
    res = json.loads(out.read_text())
    assert res["data_used"]["samples"] == round(0.75 * n)  # the fit never saw the held-out part
    held = res["holdout"]
    assert held["samples"] == n - round(0.75 * n) and held["warmup_samples"] == round(0.75 * n)
    rows = {(r["horizon"], r["predictor"]): r for r in held["scores"]}
    one_step = next(r for (h, p), r in rows.items() if h.startswith("1 step") and p == "model")
    assert 0.85 <= one_step["coverage_2sigma"] <= 1.0  # data from the model itself: an honest band
    assert {p for _, p in rows} == {"model", "persistence", "arx"}
    assert (rep / "holdout" / "report.html").exists()


def test_select_holdout_scores_the_selected_model(files, capsys):
    out = files / "sel.json"
    args = ["select", str(files / "zone.csv"), "--model", "Ti+heater", "--model", "TiTe+heater"]
    rc = main([*args, "--starts", "1", "--holdout", "0.25", "--json", str(out)])
    res = json.loads(out.read_text())
    assert res["selected"] == "TiTe+heater" and res["holdout"]["model"] == "TiTe+heater"
    # the held-out checks are in the selected fit's verdict and exit code, as fit's (0 or 3 there too)
    assert rc == res["exit_code"] in (0, 3) and (rc == 3 or not res["holdout"]["evidence"]["failed"])
    assert "(held out)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("command", "value", "message"),
    [
        ("fit", "1.5", "--holdout as a fraction must lie between 0 and 1"),
        ("fit", "tomorrow", "--holdout must be a time"),
        ("fit", "2009-02-09T12:00", "the data have no clock time"),
        ("select", "0", "--holdout as a fraction must lie between 0 and 1"),
    ],
)
def test_bad_holdout_values_are_one_line_errors(files, capsys, command, value, message):
    args = [command, str(files / "zone.csv"), "--model", "Ti+heater", "--model", "TiTe+heater"]
    args = args if command == "select" else args[:4]
    assert main([*args, "--holdout", value]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and err.count("\n") == 1


@pytest.mark.slow
def test_select_holdout_of_a_wrong_model_exits_3_like_fit_and_names_the_failed_checks(files, capsys):
    """The selected model fails the held-out checks: select's verdict and exit code say so, as fit's do."""
    out = files / "wrong.json"
    args = ["select", str(files / "zone.csv"), "--model", "Ti", "--model", "Ti+heater", "--starts", "1"]
    assert main(args) == 0  # on all the data, nothing flags the selected fit itself
    capsys.readouterr()
    assert main([*args, "--holdout", "0.3", "--json", str(out)]) == 3
    text = capsys.readouterr().out
    res = json.loads(out.read_text())
    failed = res["holdout"]["evidence"]["failed"]
    best = res["models"][res["selected"]]
    assert res["selected"] == "Ti+heater" and failed and res["exit_code"] == 3 and not best["trustworthy"]
    assert all(any(f.startswith(f"held out, {name} failed") for f in best["flags"]) for name in failed)
    assert "verdict: flagged" in text and all(f"held out, {name} failed" in text for name in failed)
    # fit of the same model with the same split reaches the same verdict
    fit = ["fit", str(files / "zone.csv"), "--model", "Ti+heater", "--starts", "1", "--holdout", "0.3"]
    assert main([*fit, "--noise", "all", "--no-profiles", "--json", str(files / "fit.json")]) == 3
    assert json.loads((files / "fit.json").read_text())["verdict"]["held_out"]["failed"] == failed
