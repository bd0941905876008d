"""`rczone fit`, `rczone predict`, `rczone diagnose` and `rczone design` end to end on files."""

import json

import pandas as pd
import pytest

from rczone.cli.main import main
from tests.unit.diagnostics.synthetic import night

TRUE = {"Rw": 0.012, "Cr": 6e5}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    night("forced", seed=1, theta=TRUE).to_csv(d / "forced.csv", index=False)
    night("closed-loop", seed=2, theta=TRUE).to_csv(d / "closed.csv", index=False)
    return d


def test_fit_then_predict(files, capsys):
    out, model = files / "fit.json", files / "model.json"
    rc = main(
        ["fit", str(files / "forced.csv"), "--method", "ls", "--json", str(out), "--save-model", str(model)]
    )
    assert rc == 0
    res = json.loads(out.read_text())
    rw = res["parameters"]["Rw"]
    assert rw["estimate"] == pytest.approx(TRUE["Rw"], rel=0.05)
    assert rw["construction"] == pytest.approx(0.00839, rel=0.01) and rw["std_error"] > 0
    assert res["rmse_K"] < 0.1 and res["identifiability"]["Rw"]["verdict"] == "identifiable"
    pred = files / "pred.json"
    assert main(["predict", str(model), str(files / "closed.csv"), "--json", str(pred)]) == 0
    p = json.loads(pred.read_text())
    assert p["rmse_K"] < 0.1 and p["max_error_K"] < 0.3


def test_diagnose_flags_the_closed_loop_night(files, capsys):
    out = files / "diag.json"
    assert main(["diagnose", str(files / "closed.csv"), "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["parameters"]["Rw"]["verdict"] in ("weak", "not identifiable")
    assert "stayed within" in d["parameters"]["Rw"]["reason"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fit", "nonexistent.csv"], "does not exist"),
        (["fit", "{d}/bad.csv"], "missing column"),
        (["fit", "{d}/forced.csv", "--model", "second-order-papr"], "did you mean 'second-order-paper'"),
        (["fit", "{d}/forced.csv", "--free", "Rww"], "did you mean 'Rw'"),
        (["fit", "{d}/forced.csv", "--method", "lsq"], "method must be one of"),
        (["predict", "{d}/forced.csv", "{d}/forced.csv"], "expected a model file (.toml) or a saved model"),
        (["design", "--band", "25,20"], "band must be"),
        (["design", "--ts-range", "cold"], "two numbers"),
    ],
)
def test_user_mistakes_exit_2_with_one_line(files, capsys, args, message):
    (files / "bad.csv").write_text("time,Ti,To\n0,20,10\n60,20,10\n")
    rc = main([a.replace("{d}", str(files)) for a in args])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and "Traceback" not in err
    assert len([ln for ln in err.splitlines() if ln.startswith("error:")]) == 1


def test_diagnose_builtin_sets_with_report(tmp_path, capsys):
    """Before any fit: the closed-loop nights A and B cannot identify Rw, the forced night C can."""
    verdicts = {}
    for name in "ABC":
        out = tmp_path / f"{name}.json"
        args = ["diagnose", name, "--json", str(out)] + (
            ["--report", str(tmp_path / "rep")] if name == "C" else []
        )
        assert main(args) == 0
        verdicts[name] = json.loads(out.read_text())["parameters"]["Rw"]["verdict"]
    assert verdicts == {"A": "not identifiable", "B": "not identifiable", "C": "identifiable"}
    html = (tmp_path / "rep" / "report.html").read_text()
    assert "identifiable" in html and "<img" in html and (tmp_path / "rep" / "data_overview.png").exists()


def test_design_writes_a_playable_schedule(tmp_path, capsys):
    sched, js = tmp_path / "schedule.csv", tmp_path / "design.json"
    assert main(["design", "--hours", "6", "--out", str(sched), "--json", str(js)]) == 0
    s = pd.read_csv(sched)
    assert list(s.columns) == ["time_s", "Ts_setpoint_degC", "m_setpoint_kg_s"] and len(s) > 1
    assert s["Ts_setpoint_degC"].between(12, 35).all() and s["m_setpoint_kg_s"].between(0.02, 0.12).all()
    # every command is held at least the minimum hold time (30 min default)
    assert (s["time_s"].diff().dropna() >= 1800).all()
    d = json.loads(js.read_text())
    assert d["within_band"] and 17 <= d["ti_min_degC"] < d["ti_max_degC"] <= 28
    assert all(0 < v < 0.25 for v in d["expected_rel_se"].values())
