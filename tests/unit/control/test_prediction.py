"""Prediction scores on a run: zero for data the model itself made, larger for a wrong R and C."""

import numpy as np
import pytest

from rczone.control.model import ControlModel
from rczone.control.prediction import SENSOR_RESOLUTION_K, floored, prediction_scores
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.virtual.scenarios import SURROUNDINGS


def synthetic_log(zm, hours=8.0):
    """A run made by the model itself (exact ZOH, inputs held over 10-min intervals), 1-min samples."""
    n = round(hours * 60)
    t = 60.0 * np.arange(-60, n + 1)
    block = np.floor(t / 600.0)
    to = 25.0 + 5.0 * np.sin(2 * np.pi * block * 600.0 / 86400.0)
    ts = np.where(block % 3 == 0, 30.0, 14.0)
    m = np.where(block % 2 == 0, 0.08, 0.03)
    d = {k: zm.discrete(60.0, m=mk) for k, mk in ((0.08, 0.08), (0.03, 0.03))}
    names = zm.network.input_names
    x = np.array([23.0, 22.5])
    ti = []
    for k in range(len(t)):
        ti.append(x[0])
        u = np.array([{"To": to[k], "Tsd": 22.0, "Ts": ts[k], "Q": 50.0}[nm] for nm in names])
        x = d[m[k]].Ad @ x + d[m[k]].Bd @ u
    values = {
        "To": to,
        "Ti_target": np.array(ti),
        "m_target": np.r_[np.nan, m[:-1]],
        "Ts_target": np.r_[np.nan, ts[:-1]],
    }
    values.update({f"Ti_{z}": np.full(len(t), 22.0) for z in SURROUNDINGS.values()})
    return values, t


def test_a_model_scored_on_its_own_output_predicts_it_and_a_wrong_one_does_not():
    zm = load_model("second-order")
    values, t = synthetic_log(zm)
    own = prediction_scores(values, t, zm)
    assert own["prediction_1h_rmse_K"] < 0.02 and own["open_loop_rmse_K"] < 0.02
    wrong = zm.with_values({k: 0.4 * v for k, v in zm.theta.items() if k.startswith("R")})
    bad = prediction_scores(values, t, wrong)
    assert bad["open_loop_rmse_K"] > 5 * own["open_loop_rmse_K"] + 0.1
    assert bad["prediction_1h_rmse_K"] > own["prediction_1h_rmse_K"]


def test_the_noise_floor_is_the_sensors_resolution_unless_overridden():
    zm = load_model("second-order")
    cm = ControlModel(zm)
    low = floored(cm.noise, 0.0)
    np.testing.assert_array_equal(low.R, cm.noise.R)
    hi = floored(cm.noise, 1.0)
    assert hi.R[0, 0] == 1.0 and SENSOR_RESOLUTION_K == pytest.approx(0.0556, abs=1e-4)
    with pytest.raises(ParameterError, match="floor"):
        floored(cm.noise, float("nan"))
    values, t = synthetic_log(zm, hours=1.0)  # too short to score
    assert set(prediction_scores(values, t, zm).values()) == {None}
