"""`rczone fit` and `rczone predict` end to end on files (diagnose and design: test_diagnose_cmd.py)."""

import json

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


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fit", "nonexistent.csv"], "does not exist"),
        (["fit", "{d}/bad.csv"], "missing column"),
        (["fit", "{d}/forced.csv", "--model", "second-order-papr"], "did you mean 'second-order-paper'"),
        (["fit", "{d}/forced.csv", "--free", "Rww"], "did you mean 'Rw'"),
        (["fit", "{d}/forced.csv", "--method", "lsq"], "method must be one of"),
        (["predict", "{d}/forced.csv", "{d}/forced.csv"], "expected a model file (.toml) or a saved model"),
    ],
)
def test_user_mistakes_exit_2_with_one_line(files, capsys, args, message):
    (files / "bad.csv").write_text("time,Ti,To\n0,20,10\n60,20,10\n")
    rc = main([a.replace("{d}", str(files)) for a in args])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and "Traceback" not in err
    assert len([ln for ln in err.splitlines() if ln.startswith("error:")]) == 1
