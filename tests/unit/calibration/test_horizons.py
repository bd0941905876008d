"""``rczone predict --horizons --baselines``: one call, every horizon, against the single-horizon path."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rczone.calibration import prediction
from rczone.calibration.horizons import horizon_scores, parse_horizons
from rczone.cli.main import main
from tests.unit.estimation.test_initial_state import NOON, _with_noise, zone  # noqa: F401 (fixture)


def test_every_horizon_of_one_call_equals_its_own_prediction(zone):  # noqa: F811
    _, zm, frame, _, _ = zone
    zm = _with_noise(zm)
    scores = horizon_scores(zm, frame, horizons=[1, 12, None], start=NOON, parameters=False)
    for h, steps in enumerate(scores.horizons):
        single = prediction(zm, frame, steps=steps, start=NOON, parameters=False)
        np.testing.assert_allclose(scores.predicted["model"][h], single.predicted, rtol=1e-12)
        np.testing.assert_allclose(scores.sd[h], single.sd, rtol=1e-12)
        row = scores.table[(scores.table.steps.isna() if steps is None else scores.table.steps == steps)]
        model = row[row.predictor == "model"].iloc[0]
        e = single.measured[:, 0] - single.predicted[:, 0]
        assert model.rmse_K == pytest.approx(np.sqrt(np.nanmean(e**2)), rel=1e-12)
        assert model.bias_K == pytest.approx(np.nanmean(e), rel=1e-12)
        assert model.coverage_2sigma == pytest.approx(single.coverage[0], rel=1e-12)


def test_predict_cli_scores_horizons_with_baselines_in_one_table(zone, tmp_path, capsys):  # noqa: F811
    d, zm, frame, _, _ = zone
    _with_noise(zm).save(tmp_path / "noisy.json")
    args = ["predict", str(tmp_path / "noisy.json"), str(d / "zone.csv"), "--warmup", "12h"]
    out, series, rep = tmp_path / "h.json", tmp_path / "h.csv", tmp_path / "rep"
    extra = [
        "--horizons",
        "1,12,open",
        "--baselines",
        "--json",
        str(out),
        "-o",
        str(series),
        "--report",
        str(rep),
    ]
    assert main([*args, *extra]) == 0
    printed = capsys.readouterr().out
    assert "persistence" in printed and "12 steps (1 h)" in printed and "open loop" in printed
    res = json.loads(out.read_text())
    got = {(r["horizon"], r["predictor"]) for r in res["scores"]}
    horizons = ("1 step (5 min)", "12 steps (1 h)", "open loop")
    assert got == {(h, p) for h in horizons for p in ("model", "persistence", "arx")}
    assert "fitted by least squares on the 144 warm-up samples" in res["baselines"]
    s = pd.read_csv(series)
    persistence_1h = s["Ti_k12_persistence"].to_numpy()
    e = s["Ti_measured"].to_numpy() - persistence_1h
    row = next(
        r for r in res["scores"] if r["horizon"] == "12 steps (1 h)" and r["predictor"] == "persistence"
    )
    assert row["rmse_K"] == pytest.approx(np.sqrt(np.mean(e**2)), rel=1e-9)
    measured = frame["Ti"].to_numpy()
    np.testing.assert_array_equal(persistence_1h, measured[144 - 12 : -12])  # the measurement 1 h earlier
    html = (rep / "report.html").read_text()
    assert "Scores per horizon" in html and "horizons" in html


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("1,x", "--horizons must be comma-separated"),
        ("0", "--horizons must be"),
        ("-3,open", "--horizons must"),
    ],
)
def test_bad_horizons_are_one_line_errors(zone, capsys, value, message):  # noqa: F811
    d, _, _, _, _ = zone
    assert main(["predict", str(d / "zone.toml"), str(d / "zone.csv"), "--horizons", value]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and err.count("\n") == 1


def test_k_step_horizons_of_a_model_without_noise_levels_are_refused(zone, capsys):  # noqa: F811
    d, _, _, _, _ = zone
    assert main(["predict", str(d / "zone.toml"), str(d / "zone.csv"), "--horizons", "1,open"]) == 2
    assert "noise levels" in capsys.readouterr().err
    assert parse_horizons("open, 3,3") == [None, 3]


def test_the_scores_follow_the_results_protocol(zone):  # noqa: F811
    _, zm, frame, _, _ = zone
    scores = horizon_scores(_with_noise(zm), frame, horizons=[1, None], start=NOON, parameters=False)
    text = scores.summary()
    assert "1 step (5 min)" in text and "open loop" in text and "arx" in text
    assert "<table" in scores._repr_html_() and "\n" not in repr(scores)
    assert list(scores.to_frame().columns[:4]) == ["horizon", "steps", "horizon_s", "predictor"]
    assert json.loads(json.dumps(scores.to_dict()))["scores"][0]["predictor"] == "model"


def test_predict_of_an_unfitted_model_says_it_has_no_band_instead_of_nan(zone, tmp_path, capsys):  # noqa: F811
    d, _, _, _, _ = zone
    out = tmp_path / "p.json"
    assert main(["predict", str(d / "zone.toml"), str(d / "zone.csv"), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "nan%" not in printed and "no 2-sigma band" in printed
    doc = json.loads(out.read_text())
    assert doc["coverage_2sigma"] is None and doc["coverage_note"].startswith("no 2-sigma band")
