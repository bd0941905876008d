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
from rczone.estimation.initial import estimate_initial_state
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
    rest for the first sample, then the envelope raised by ``offset``. Returns both nodes' temperatures
    and that start.
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
    return x, x0


@pytest.fixture(scope="module")
def zone(tmp_path_factory):
    d = tmp_path_factory.mktemp("x0")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 86400.0, 300.0)
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400.0)
    ph = np.repeat(rng.choice([0.0, 1500.0], t.size // 12 + 1), 12)[: t.size]
    x, x0 = _simulate(t, to, ph, OFFSET_K)
    frame = pd.DataFrame({"time": t, "Ti": x[:, 0] + rng.normal(0, 0.01, t.size), "To": to, "Ph": ph})
    frame.to_csv(d / "zone.csv", index=False)
    return d, zm, frame, x0, x


def test_the_estimate_finds_the_true_initial_state(zone):
    _, zm, frame, x0, _ = zone
    data = dataset(zm, frame)
    est = estimate_initial_state(zm.network, dict(zm.theta), data, [0.01], {"Ti": 1.0, "Te": 100.0})
    assert est.values["x0_Te"] == pytest.approx(x0[1], abs=0.05)
    assert est.steady["x0_Te"] == pytest.approx(x0[1] - OFFSET_K, abs=0.05)
    assert est.sd["x0_Te"] < 0.05 and set(est.sd) == {"x0_Te"}  # the measured node is not estimated


def test_a_tight_prior_holds_the_estimate_near_the_steady_state(zone):
    _, zm, frame, _, _ = zone
    data = dataset(zm, frame)
    loose = estimate_initial_state(zm.network, dict(zm.theta), data, [0.01], {"Ti": 1.0, "Te": 100.0})
    tight = estimate_initial_state(zm.network, dict(zm.theta), data, [10.0], {"Ti": 1.0, "Te": 0.01})
    assert abs(tight.values["x0_Te"] - tight.steady["x0_Te"]) < 0.1 * OFFSET_K
    assert tight.sd["x0_Te"] <= 0.01  # the posterior is never wider than the prior
    assert abs(loose.values["x0_Te"] - loose.steady["x0_Te"]) > 0.9 * OFFSET_K


def test_prediction_started_at_the_estimate_removes_the_bias(zone):
    _, zm, frame, _, _ = zone
    steady = prediction(zm, frame, initial_state="steady")
    estimated = prediction(zm, frame, initial_state="estimated")
    assert steady.rmse_K[0] > 0.5  # the envelope's unknown start shows as a lasting bias
    assert estimated.rmse_K[0] < 0.05
    with pytest.raises(Exception, match="initial_state must be one of warmup, steady, estimated"):
        prediction(zm, frame, initial_state="warm")


def test_predict_cli_reports_the_estimated_start(zone, capsys):
    d, _, _, x0, _ = zone
    out = d / "pred.json"
    rep = d / "rep"
    assert (
        main(
            [
                "predict",
                str(d / "zone.toml"),
                str(d / "zone.csv"),
                "--initial-state",
                "estimated",
                "--json",
                str(out),
                "--report",
                str(rep),
            ]
        )
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


#: Half a day of warm-up: the prediction starts at noon.
NOON = 43200.0


def _with_noise(zm):
    """The model with noise levels (as a likelihood fit leaves it): its predictions come from the Kalman filter."""
    return zm.with_values(zm.theta, {"sigma_v": 0.01, "sigma_w_Ti": 1e-4, "sigma_x0_Te": 10.0})


def _future_changed(frame):
    """The same data with every measurement from noon on moved by 3 K."""
    other = frame.copy()
    other.loc[other["time"] >= NOON, "Ti"] += 3.0
    return other


@pytest.mark.parametrize("noise", [False, True], ids=["no noise levels", "Kalman filter"])
def test_warm_up_start_finds_the_envelope_and_ignores_the_scored_data(zone, noise):
    _, zm, frame, _, _ = zone
    zm = _with_noise(zm) if noise else zm
    cold = prediction(zm, frame[frame["time"] >= NOON])  # no warm-up: the envelope at the steady state
    warm = prediction(zm, frame, start=NOON)
    assert warm.t[0] == NOON and warm.warmup_samples == 144
    assert cold.rmse_K[0] > 0.3  # the envelope, still warm from the night, shows as a bias
    assert warm.rmse_K[0] < 0.05  # truth by construction: the warm-up found where the envelope is
    assert "warm-up" in warm.start_note and "first sample only" in cold.start_note
    moved = prediction(zm, _future_changed(frame), start=NOON)
    np.testing.assert_array_equal(moved.predicted, warm.predicted)  # no sample after the start is used
    assert moved.rmse_K[0] > 2.0


def test_k_step_predictions_use_no_sample_after_their_origin(zone):
    _, zm, frame, _, _ = zone
    zm = _with_noise(zm)
    k = 6
    base = prediction(zm, frame, steps=k, start=NOON)
    moved = prediction(zm, _future_changed(frame), steps=k, start=NOON)
    np.testing.assert_array_equal(moved.predicted[:k], base.predicted[:k])  # origins before noon
    assert not np.allclose(moved.predicted[k:], base.predicted[k:])


def test_the_series_file_has_every_node_with_its_standard_deviation(zone):
    d, zm, frame, _, x = zone
    _with_noise(zm).save(d / "noisy.json")
    out = d / "series.csv"
    assert (
        main(["predict", str(d / "noisy.json"), str(d / "zone.csv"), "--warmup", "12h", "-o", str(out)]) == 0
    )
    series = pd.read_csv(out)
    assert {"Ti_smoothed", "Ti_smoothed_sd", "Te_smoothed", "Te_smoothed_sd"} <= set(series.columns)
    truth = x[frame["time"].to_numpy() >= NOON, 1]
    err = series["Te_smoothed"].to_numpy() - truth
    sd = series["Te_smoothed_sd"].to_numpy()
    assert np.max(np.abs(err)) < 0.2 and np.all(np.abs(err) < 4 * sd + 0.02)  # the envelope, never measured


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("soon", "--warmup must be a duration with its unit"),
        ("5", "--warmup must be a duration with its unit"),
        ("2d", "leaves no data on one side"),
        ("2009-02-09T12:00", "the data have no clock time"),
    ],
)
def test_bad_warmup_values_are_one_line_errors(zone, capsys, value, message):
    d, _, _, _, _ = zone
    assert main(["predict", str(d / "zone.toml"), str(d / "zone.csv"), "--warmup", value]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_the_factors_saved_with_a_fit_scale_the_noise_band_per_horizon(zone):
    _, zm, frame, _, _ = zone
    zm = _with_noise(zm)
    saved = {"horizon_s": [300.0, 3600.0], "scale": [1.0, 3.0], "open_loop": 4.0}
    calibrated = zm.with_values(zm.theta, band_scale=saved)
    for steps, factor in ((6, 1 + 2 * np.log(6) / np.log(12)), (None, 4.0)):
        raw = prediction(zm, frame, steps=steps, start=NOON, parameters=False)
        wide = prediction(calibrated, frame, steps=steps, start=NOON, parameters=False)
        np.testing.assert_array_equal(wide.predicted, raw.predicted)
        np.testing.assert_allclose(wide.sd_noise, factor * raw.sd_noise, rtol=1e-12)
        assert "calibrated on the fit's own errors" in wide.band_source
