"""`rczone select`, the residual lines of `rczone fit` and `rczone predict --steps` on files."""

import json

import pytest

from rczone.cli.main import main
from tests.unit.selection.synthetic import prbs_zone


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("select")
    prbs_zone(days=2, seed=2).to_csv(d / "zone.csv", index=False)
    return d


def test_select_table_json_report_and_model(files, capsys):
    out, rep, model = files / "sel.json", files / "rep", files / "best.json"
    args = ["select", str(files / "zone.csv"), "--model", "Ti+heater", "--model", "TiTe+heater"]
    rc = main([*args, "--json", str(out), "--report", str(rep), "--save-model", str(model)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "selected: TiTe+heater (BIC)" in text and "Ce -> 0" in text
    res = json.loads(out.read_text())
    assert res["selected"] == "TiTe+heater" and res["rule"] == "bic"
    for name in ("Ti+heater", "TiTe+heater"):
        m = res["models"][name]
        assert {"loglik", "n_params", "aic", "bic"} <= set(m) and 0 <= m["innovations"]["ljung_box_p"] <= 1
    assert res["tests"][0]["df"] == 3 and res["tests"][0]["restriction"] == "Ce -> 0"
    html = (rep / "report.html").read_text()
    assert "Likelihood-ratio tests" in html and "Forward selection" not in html
    assert (rep / "innovations_compared.png").stat().st_size > 1000
    assert json.loads(model.read_text())["network"]["name"] == "TiTe+heater"
    # forward selection, JSON on stdout
    assert main([*args, "--forward", "--json", "-"]) == 0
    fwd = json.loads(capsys.readouterr().out)
    assert fwd["forward"]["path"] == ["Ti+heater", "TiTe+heater"] and fwd["selected"] == "TiTe+heater"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--model", "Ti+heater"], "at least two"),
        (["--model", "Ti+heater", "--model", "TiTe+heater", "--criterion", "hqc"], "bic or aic"),
        (["--model", "Ti+heater", "--model", "TiTe+heatr"], "did you mean"),
    ],
)
def test_select_mistakes_exit_2_with_one_line(files, capsys, extra, message):
    rc = main(["select", str(files / "zone.csv"), *extra])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err


def test_fit_reports_innovations_for_ml_and_labelled_open_loop_residuals_for_ls(files, capsys):
    ml, ls, model = files / "ml.json", files / "ls.json", files / "ml_model.json"
    zone = str(files / "zone.csv")
    base = ["fit", zone, "--model", "TiTe+heater", "--no-profiles"]
    assert main([*base, "--method", "ml", "--json", str(ml), "--save-model", str(model)]) in (0, 3)
    text = capsys.readouterr().out
    assert "innovations of Ti (one-step, standardized)" in text
    d = json.loads(ml.read_text())
    assert d["innovations"]["kind"] == "innovations" and 0 <= d["innovations"]["ljung_box_p"] <= 1
    assert d["innovations"]["outputs"]["Ti"]["acf"]["lag_h"][1] == pytest.approx(5 / 60)
    assert d["open_loop_residuals"]["kind"] == "open-loop"
    assert main([*base, "--method", "ls", "--json", str(ls)]) in (0, 3)
    assert "not expected to be white" in capsys.readouterr().out
    d = json.loads(ls.read_text())
    assert d["innovations"] is None and "not expected" in d["open_loop_residuals"]["note"]
    # k steps ahead with the ML model: a band from the noise and from the estimates
    pred = files / "pred.json"
    assert main(["predict", str(model), zone, "--steps", "6", "--json", str(pred)]) == 0
    p = json.loads(pred.read_text())
    assert p["horizon"] == "6 steps ahead" and 0.85 < p["coverage_2sigma"]["Ti"] <= 1.0
    assert set(p["mean_sd_K"]) == {"noise", "estimates"}
    assert p["mean_sd_K"]["estimates"]["Ti"] < p["mean_sd_K"]["noise"]["Ti"]


def test_a_flagged_fit_is_passed_over_not_selected(files, tmp_path, capsys):
    """TiTe+heater with Ce capped at 1.5e6 J/K (the data were made with 8e6): its fit pins Ce at the bound.

    It still scores better than Ti+heater, but a flagged fit must not win without saying why: BIC passes
    it over and names the flag; forward selection refuses the step (issue: select returned a model whose
    heater-node noise sat at its upper bound).
    """
    from rczone.models import model_to_toml
    from tests.unit.diagnostics.synthetic import family

    toml = model_to_toml(family("TiTe+heater"))
    capped = toml.replace(
        'Ce = { value = 10000000.0, unit = "J/K", bounds = [100000.0, 100000000000.0]',
        'Ce = { value = 1000000.0, unit = "J/K", bounds = [100000.0, 1500000.0]',
    )
    assert capped != toml
    (tmp_path / "capped.toml").write_text(capped)
    args = [
        "select",
        str(files / "zone.csv"),
        "--model",
        "Ti+heater",
        "--model",
        str(tmp_path / "capped.toml"),
    ]
    out = tmp_path / "sel.json"
    assert main([*args, "--json", str(out)]) == 0  # the selected model is sound
    text = capsys.readouterr().out
    res = json.loads(out.read_text())
    capped_name = next(n for n in res["models"] if n != "Ti+heater")
    flagged = res["models"][capped_name]
    assert not flagged["trustworthy"] and flagged["bic"] < res["models"]["Ti+heater"]["bic"]
    assert res["selected"] == "Ti+heater" and set(res["passed_over"]) == {capped_name}
    assert "bound" in res["passed_over"][capped_name]
    assert "passed over" in text and "selected: Ti+heater" in text
    # forward: the likelihood-ratio test favours the capped model, but its step is refused
    assert main([*args, "--forward", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    fwd = json.loads(out.read_text())
    step = fwd["forward"]["steps"][0]
    assert step["p_value"] < 0.05 and not step["accepted"] and step["refused_flagged"]
    assert fwd["selected"] == "Ti+heater" and "refused: the fit of" in text


def test_select_fixes_and_frees_noise_and_initial_states_like_fit(files, tmp_path, capsys):
    """--fix sigma_v=0.02 (the data's true measurement noise) and --free +sigma_w_Te +x0_Te, parsed as fit parses them.

    Each candidate gets the names it has (Ti+heater has no Te); the "same fit alone" line repeats them,
    and ``rczone fit`` with it reaches the log-likelihood select reported for the selected model.
    """
    import shlex

    out, model = tmp_path / "sel.json", tmp_path / "best.json"
    args = ["select", str(files / "zone.csv"), "--model", "Ti+heater", "--model", "TiTe+heater"]
    extra = ["--noise", "measured", "--starts", "1", "--fix", "sigma_v=0.02", "--free", "+sigma_w_Te,+x0_Te"]
    assert main([*args, *extra, "--json", str(out), "--save-model", str(model)]) == 0
    text = capsys.readouterr().out
    res = json.loads(out.read_text())
    ti, tite = (set(res["models"][n]["parameters"]) for n in ("Ti+heater", "TiTe+heater"))
    assert ti == {"Ci", "Ria", "sigma_w_Ti"}
    assert tite == {"Ci", "Ce", "Rie", "Rea", "sigma_w_Ti", "sigma_w_Te", "x0_Te"}
    assert res["selected"] == "TiTe+heater" and json.loads(model.read_text())["noise"]["sigma_v"] == 0.02
    line = next(ln for ln in text.splitlines() if ln.startswith("rczone fit "))
    alone = shlex.split(line)[2:]
    assert "--fix" in alone and "sigma_v=0.02" in alone and "+x0_Te" in alone and "+sigma_w_Te" in alone
    fit_json = tmp_path / "fit.json"
    assert main(["fit", *alone, "--no-profiles", "--json", str(fit_json)]) in (0, 3)
    llf = json.loads(fit_json.read_text())["llf"]
    assert llf == pytest.approx(res["models"]["TiTe+heater"]["loglik_fit"], abs=0.05)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--free", "sigma_w_Te"], "write +sigma_w_Te"),
        (["--fix", "sigma_q"], "no candidate has a parameter 'sigma_q'"),
        (["--fix", "sigma_v", "--free", "+sigma_v"], "both free and fixed"),
        (["--fix", "sigma_v=abc"], "--fix must be NAME or NAME=VALUE"),
    ],
)
def test_select_fix_and_free_mistakes_exit_2_with_one_line(files, capsys, extra, message):
    rc = main(["select", str(files / "zone.csv"), "--model", "Ti+heater", "--model", "TiTe+heater", *extra])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err, err
