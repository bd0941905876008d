"""``rczone.smooth``: the smoother through the public API, indexed by the data's time stamps."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import rczone
from rczone.calibration import dataset
from rczone.estimation.smoother import smooth_states

NOISE = {
    "sigma_v": 0.05,
    "sigma_w_Ti": 2e-3,
    "sigma_w_Tw": 5e-4,
    "sigma_x0_Ti": 0.1,
    "sigma_x0_Tw": 1.0,
    "x0_Tw": 99.0,
}


@pytest.fixture(scope="module")
def model_and_frame():
    zm = rczone.load_model("second-order-paper")
    zm = zm.with_values(zm.theta, noise=NOISE)
    frame = rczone.load_data("C", model=zm)
    stamps = pd.date_range("2024-03-05 22:00", periods=len(frame), freq="60s", tz="Europe/Zurich")
    return zm, frame.drop(columns="time").set_index(stamps)


def test_smooth_gives_a_column_per_node_and_its_sd_indexed_by_the_datas_time_stamps(model_and_frame):
    zm, frame = model_and_frame
    res = rczone.smooth(zm, frame, label="night C")
    df = res.to_frame()
    assert list(df.columns) == ["Ti", "Ti_sd", "Tw", "Tw_sd"]
    pd.testing.assert_index_equal(df.index, frame.index, check_names=False, check_freq=False)
    assert str(df.index.tz) == "Europe/Zurich"
    # the same numbers as the estimation layer's smoother on the same data set, the fit's own
    # initial state (x0_Tw) left out
    values = {**zm.theta, **{k: v for k, v in NOISE.items() if k != "x0_Tw"}}
    direct = smooth_states(zm.network, values, dataset(zm, frame))
    np.testing.assert_array_equal(df["Tw"].to_numpy(), direct.x[:, 1])
    np.testing.assert_array_equal(df["Tw_sd"].to_numpy(), direct.sd[:, 1])
    assert np.all(df["Tw"].between(10, 35))  # not started at the saved 99 degC
    text = res.summary()
    assert "night C: Tw smoothed" in text and "filtered" in text
    d = res.to_dict()
    assert d["samples"] == len(frame) and d["mean_sd_K"]["Tw"] < d["mean_filtered_sd_K"]["Tw"]
    assert "night C" in repr(res) and len(repr(res)) < 200
    assert "<table" in res._repr_html_()


def test_smooth_without_noise_levels_is_one_clear_error():
    with pytest.raises(rczone.DataError, match=r"noise levels.*fit it by ML"):
        rczone.smooth("second-order-paper", "C")


def test_smooth_holds_the_inputs_as_the_model_was_fitted(model_and_frame):
    import dataclasses

    zm, frame = model_and_frame
    foh = dataclasses.replace(zm, provenance={**zm.provenance, "hold": "foh"})
    values = {**zm.theta, **{k: v for k, v in NOISE.items() if k != "x0_Tw"}}
    direct = smooth_states(zm.network, values, dataset(zm, frame), hold="foh")
    tw = rczone.smooth(foh, frame).to_frame()["Tw"].to_numpy()
    np.testing.assert_array_equal(tw, direct.x[:, 1])
    assert np.max(np.abs(tw - rczone.smooth(zm, frame).to_frame()["Tw"].to_numpy())) > 1e-4
