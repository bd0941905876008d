"""Open-loop predictions start their unmeasured nodes where the data say (estimate_initial_state).

Truth by construction: data simulated from a known initial state far from the steady state; the
estimate must find it, and the prediction started there must reproduce the data.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rczone.calibrate import dataset, prediction
from rczone.cli.main import main
from rczone.estimation.validation import estimate_initial_state
from rczone.models import read_model_file
from rczone.simulation import simulate

MODEL = """
name = "room and envelope"
boundaries = ["To"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]

[nodes]
Ti = "Ci"
Te = "Ce"

[heat_inputs]
Ph = "Ti"

[parameters]
Ci = { value = 2.0, unit = "MJ/K" }
Ce = { value = 40.0, unit = "MJ/K" }
Rie = { value = 2.0, unit = "K/kW" }
Rea = { value = 10.0, unit = "K/kW" }
"""
#: The envelope starts 4 K above its steady state for the first sample: it cools all day.
OFFSET_K = 4.0


@pytest.fixture(scope="module")
def zone(tmp_path_factory):
    d = tmp_path_factory.mktemp("x0")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 86400.0, 300.0)
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400.0)
    ph = np.repeat(rng.choice([0.0, 1500.0], t.size // 12 + 1), 12)[: t.size]
    u = np.column_stack([to, ph])
    ss = zm.state_space()
    x_ss = np.linalg.solve(ss.A, -ss.B @ u[0])  # both nodes at rest for the first sample
    x0 = np.array([x_ss[0], x_ss[1] + OFFSET_K])
    y = simulate(ss, t, u, x0=x0).y[:, 0]
    frame = pd.DataFrame({"time": t, "Ti": y + rng.normal(0, 0.01, t.size), "To": to, "Ph": ph})
    frame.to_csv(d / "zone.csv", index=False)
    return d, zm, frame, x0


def test_the_estimate_finds_the_true_initial_state(zone):
    _, zm, frame, x0 = zone
    data = dataset(zm, frame)
    est = estimate_initial_state(zm.network, dict(zm.theta), data, [0.01], {"Ti": 1.0, "Te": 100.0})
    assert est.values["x0_Te"] == pytest.approx(x0[1], abs=0.05)
    assert est.steady["x0_Te"] == pytest.approx(x0[1] - OFFSET_K, abs=0.05)
    assert est.sd["x0_Te"] < 0.05 and set(est.sd) == {"x0_Te"}  # the measured node is not estimated


def test_a_tight_prior_holds_the_estimate_near_the_steady_state(zone):
    _, zm, frame, _ = zone
    data = dataset(zm, frame)
    loose = estimate_initial_state(zm.network, dict(zm.theta), data, [0.01], {"Ti": 1.0, "Te": 100.0})
    tight = estimate_initial_state(zm.network, dict(zm.theta), data, [10.0], {"Ti": 1.0, "Te": 0.01})
    assert abs(tight.values["x0_Te"] - tight.steady["x0_Te"]) < 0.1 * OFFSET_K
    assert tight.sd["x0_Te"] <= 0.01  # the posterior is never wider than the prior
    assert abs(loose.values["x0_Te"] - loose.steady["x0_Te"]) > 0.9 * OFFSET_K


def test_prediction_started_at_the_estimate_removes_the_bias(zone):
    _, zm, frame, _ = zone
    steady = prediction(zm, frame, initial_state="steady")
    estimated = prediction(zm, frame)
    assert steady.rmse_K[0] > 0.5  # the envelope's unknown start shows as a lasting bias
    assert estimated.rmse_K[0] < 0.05
    with pytest.raises(Exception, match="initial_state must be one of estimated, steady"):
        prediction(zm, frame, initial_state="warm")


def test_predict_cli_reports_the_estimated_start(zone, capsys):
    d, _, _, x0 = zone
    out = d / "pred.json"
    rep = d / "rep"
    assert (
        main(["predict", str(d / "zone.toml"), str(d / "zone.csv"), "--json", str(out), "--report", str(rep)])
        == 0
    )
    assert "initial temperatures of the unmeasured nodes" in capsys.readouterr().out
    assert "Initial temperatures of the unmeasured nodes" in (rep / "report.html").read_text()
    res = json.loads(out.read_text())
    assert res["initial_state"]["Te"]["estimate_degC"] == pytest.approx(x0[1], abs=0.5)
    rc = main(
        [
            "predict",
            str(d / "zone.toml"),
            str(d / "zone.csv"),
            "--initial-state",
            "steady",
            "--json",
            str(out),
        ]
    )
    assert rc == 0 and json.loads(out.read_text())["initial_state"] is None
