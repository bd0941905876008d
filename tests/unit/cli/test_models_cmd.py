"""`rczone models`, `--model FILE` everywhere, saved models as the start, predict's series, --json -."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rczone.cli.main import main
from rczone.models import read_model_file


def test_models_lists_the_built_ins_and_show_writes_a_model_file(tmp_path, capsys) -> None:
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    for name in ("second-order-paper", "full-scale", "TiTe", "TiTeTh", "TiTm"):
        assert name in out
    assert "heater, solar, air, gain" in out
    assert main(["models", "show", "TiTe+heater+solar", "-o", str(tmp_path / "m.toml")]) == 0
    zm = read_model_file(tmp_path / "m.toml")
    assert zm.network.input_names == ("To", "Ph", "Ps")
    assert main(["models", "show", "TiTee"]) == 2
    assert "did you mean 'TiTe'" in capsys.readouterr().err


def test_fit_saves_a_model_that_predict_and_a_second_fit_use(tmp_path, capsys) -> None:
    saved = tmp_path / "zone.json"
    rc = main(["fit", "C", "--method", "ml", "--save-model", str(saved), "--no-profiles"])
    assert rc in (0, 3)
    series = tmp_path / "pred.csv"
    assert (
        main(
            [
                "predict",
                str(saved),
                "A",
                "--out",
                str(series),
                "--report",
                str(tmp_path / "rep"),
                "--json",
                "-",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    d = json.loads(out[out.index("{") :])
    assert d["band"].startswith("the model's noise levels times ")  # the fit's calibrated factor
    assert d["band"].endswith("calibrated on the fit's own errors and the estimates' covariance")
    assert 0.5 < d["coverage_2sigma"]["Ti"] <= 1.0
    df = pd.read_csv(series)
    assert list(df.columns) == [
        "time",
        "Ti_measured",
        "Ti_predicted",
        "Ti_lower",
        "Ti_upper",
        "Ti_sd_noise",
        "Ti_sd_parameters",
        "Ti_smoothed",  # every node's smoothed temperature and its sd
        "Ti_smoothed_sd",
        "Tw_smoothed",
        "Tw_smoothed_sd",
    ]
    assert (df["Ti_lower"] < df["Ti_predicted"]).all() and (df["Ti_predicted"] < df["Ti_upper"]).all()
    assert (tmp_path / "rep" / "report.html").exists()
    # the saved model is a valid start of a new fit (its values are the start) and a model file too
    fit_json = tmp_path / "again.json"
    assert main(
        ["fit", "C", "--model", str(saved), "--method", "ml", "--json", str(fit_json), "--no-profiles"]
    ) in (0, 3)
    again = json.loads(fit_json.read_text())
    first = json.loads(saved.read_text())
    assert again["parameters"]["Rw"]["estimate"] == pytest.approx(first["theta"]["Rw"], rel=1e-3)
    assert again["model"] == "zone.json"  # titles use the file name, not the path
    toml = tmp_path / "zone.toml"
    assert main(["fit", "C", "--method", "ls", "--save-model", str(toml), "--no-profiles"]) in (0, 3)
    assert read_model_file(toml).theta["Rw"] > 0


def test_json_to_stdout_is_pure_json(capsys) -> None:
    assert main(["fit", "C", "--method", "ls", "--json", "-", "--no-profiles"]) in (0, 3)
    out = capsys.readouterr().out
    d = json.loads(out)
    assert d["method"] == "ls" and "search" in d and d["model"] == "second-order-paper"


def test_version_flag(capsys) -> None:
    from rczone import __version__

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == __version__


def test_a_user_model_reads_its_own_columns_without_a_map(tmp_path, capsys) -> None:
    """A file with the model's signal names (and an unnamed index column for time) needs no column map."""
    import numpy as np

    from rczone.models import load_model
    from rczone.simulation import simulate

    zm = load_model("TiTe+heater")
    t = np.arange(0.0, 86400.0, 600.0)
    rng = np.random.default_rng(0)
    u = np.column_stack(
        [5 + np.sin(t / 9000.0), np.repeat(rng.choice([0.0, 1500.0], t.size // 6 + 1), 6)[: t.size]]
    )
    y = simulate(zm.state_space(), t, u).y[:, 0]
    frame = pd.DataFrame({"Ti": y, "To": u[:, 0], "Ph": u[:, 1]}, index=pd.Index(t))
    frame.to_csv(tmp_path / "d.csv")  # the time is the unnamed first column
    rc = main(
        [
            "fit",
            str(tmp_path / "d.csv"),
            "--model",
            "TiTe+heater",
            "--method",
            "ls",
            "--json",
            str(tmp_path / "f.json"),
            "--no-profiles",
        ]
    )
    assert rc in (0, 3), capsys.readouterr().err
    assert main(["fit", str(tmp_path / "d.csv"), "--model", "TiTe+heater+solar"]) == 2
    assert "missing column(s) 'Ps'" in capsys.readouterr().err
