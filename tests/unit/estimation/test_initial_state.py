"""Open-loop predictions start their unmeasured nodes where the data say (estimate_initial_state).

Truth by construction: data simulated (by the heat balance written out here and scipy's ``expm``)
from a known initial state far from the steady state; the estimate must find it, and the
prediction started there must reproduce the data.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import expm

from rczone.calibration import dataset, prediction
from rczone.cli.main import main
from rczone.estimation.openloop import estimate_initial_state
from rczone.models import read_model_file

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


def _simulate(t: np.ndarray, to: np.ndarray, ph: np.ndarray, offset: float) -> tuple[np.ndarray, np.ndarray]:
    """The two-node heat balance written out here, discretized by ``scipy.linalg.expm`` (ZOH).

    ``Ci dTi/dt = (Te - Ti)/Rie + Ph``, ``Ce dTe/dt = (Ti - Te)/Rie + (To - Te)/Rea``; both nodes at
    rest for the first sample, then the envelope raised by ``offset``. Returns ``Ti`` and that start.
    """
    ci, ce, rie, rea = 2.0e6, 40.0e6, 2.0e-3, 10.0e-3  # the model file's values in SI
    a = np.array([[-1 / (rie * ci), 1 / (rie * ci)], [1 / (rie * ce), -(1 / rie + 1 / rea) / ce]])
    b = np.array([[0.0, 1 / ci], [1 / (rea * ce), 0.0]])  # inputs To, Ph
    aug = np.zeros((4, 4))
    aug[:2, :2], aug[:2, 2:] = a, b
    e = expm(aug * (t[1] - t[0]))
    u = np.column_stack([to, ph])
    x0 = np.linalg.solve(a, -b @ u[0]) + np.array([0.0, offset])
    x = np.empty((t.size, 2))
    x[0] = x0
    for k in range(t.size - 1):
        x[k + 1] = e[:2, :2] @ x[k] + e[:2, 2:] @ u[k]
    return x[:, 0], x0


@pytest.fixture(scope="module")
def zone(tmp_path_factory):
    d = tmp_path_factory.mktemp("x0")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 86400.0, 300.0)
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400.0)
    ph = np.repeat(rng.choice([0.0, 1500.0], t.size // 12 + 1), 12)[: t.size]
    y, x0 = _simulate(t, to, ph, OFFSET_K)
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
