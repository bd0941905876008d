"""``rczone control-test``: the scores as JSON, the report, one-line errors."""

import json

import pytest

from rczone.cli.main import main

KEYS = {"comfort_Kh", "energy_kWh", "peak_flow_kg_s", "prediction_rmse_K", "solve_time_s"}


@pytest.mark.parametrize("controller", ["naive", "mpc"])
def test_control_test_writes_the_scores_and_the_report(tmp_path, capsys, controller):
    out = tmp_path / "scores.json"
    args = ["control-test", "--model", "second-order", "--scenario", "summer", "--days", "0.1", "--seed", "1"]
    code = main([*args, "--controller", controller, "--json", str(out), "--report", str(tmp_path / "rep")])
    assert code == 0
    doc = json.loads(out.read_text())
    assert KEYS <= set(doc) and doc["setup"]["controller"] == controller
    assert (doc["solve_time_s"] is None) == (controller == "naive")
    assert doc["setup"]["constraints"]["target"]["flow_min_occupied"] == 0.05
    assert (tmp_path / "rep" / "report.html").exists() and (tmp_path / "rep" / "closed_loop.png").exists()
    assert "comfort" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--scenario", "spring"], "spring"),
        (["--controller", "pid"], "pid"),
        (["--days", "-1"], "days"),
        (["--days", "1e-9"], "scored minute"),
        (["--days", "0.0001"], "scored minute"),
        (["--seed", "-1"], "seed"),
        (["--forecast", "psychic"], "psychic"),
    ],
)
def test_control_test_mistakes_are_one_line_and_exit_2(tmp_path, capsys, extra, match):
    out = tmp_path / "scores.json"
    assert main(["control-test", *extra, "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err
    assert not out.exists()


def test_control_test_runs_the_tight_band_and_the_event_and_refuses_an_unknown_band(tmp_path, capsys):
    out = tmp_path / "scores.json"
    args = ["control-test", "--scenario", "summer", "--days", "0.1", "--controller", "naive"]
    assert main([*args, "--band", "tight", "--price", "dr", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["setup"]["band"] == "tight" and doc["setup"]["price"] == "dr"
    assert doc["event_energy_kWh"] == 0.0  # the first 2.4 h hold no event
    capsys.readouterr()
    assert main([*args, "--band", "wide", "--json", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "wide" in err
