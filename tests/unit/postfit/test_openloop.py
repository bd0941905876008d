from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import Dataset
from rczone.estimation.forecast import k_step_band
from rczone.postfit.openloop import (
    ljung_box,
    open_loop_error,
    per_output_errors,
)

from ..estimation.nets import NET2, data2

NOISE = {"sigma_v": 0.05, "sigma_w_Ti": 1e-3, "sigma_w_Tw": 1e-4, "sigma_x0_Ti": 0.1, "sigma_x0_Tw": 0.5}


def test_open_loop_error_zero_at_truth_and_reports_max() -> None:
    data = data2()
    ok = open_loop_error(NET2, {}, data)
    assert ok.rmse_K < 1e-9
    off = open_loop_error(NET2, {"Rw": 0.02}, data)
    assert off.max_abs_K == pytest.approx(np.nanmax(np.abs(data.y - off.y_hat)))
    assert off.max_abs_K >= off.rmse_K > 0.01


def test_k_step_prediction_error_grows_towards_open_loop_with_a_wrong_model() -> None:
    d = data2()
    data = Dataset(d.t, d.u, d.m, d.y, d.input_names, d.flow_names, d.output_names)
    wrong = {**NOISE, "Rw": 0.03}
    rm = []
    for k in (1, 3, 12):
        y_hat, _ = k_step_band(NET2, wrong, data, k)
        rm.append(float(np.sqrt(np.nanmean((data.y - y_hat) ** 2))))
    assert rm[0] < rm[1] < rm[2]
    with pytest.raises(ParameterError, match="k must be a positive integer"):
        k_step_band(NET2, NOISE, data, 0)


def test_ljung_box_accepts_white_noise_and_rejects_ar1() -> None:
    rng = np.random.default_rng(0)
    # under whiteness, Q ~ chi2(L): its mean over many series is L
    qs = [ljung_box(rng.standard_normal(400), n_lags=10).q_statistic for _ in range(300)]
    assert np.mean(qs) == pytest.approx(10.0, rel=0.1)
    e = rng.standard_normal(400)
    ar = np.empty(400)
    ar[0] = e[0]
    for k in range(1, 400):
        ar[k] = 0.8 * ar[k - 1] + e[k]
    res = ljung_box(ar, n_lags=10)
    assert res.p_value < 1e-10 and not res.white_at_5pct
    assert res.acf[0] == pytest.approx(0.8, abs=0.08)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"n_lags": 0}, "n_lags must be between"), ({"n_lags": 5, "dof": 5}, r"dof must be in \[0, n_lags\)")],
)
def test_ljung_box_bad_arguments(kwargs, match) -> None:
    with pytest.raises(ParameterError, match=match):
        ljung_box(np.random.default_rng(0).standard_normal(50), **kwargs)
    with pytest.raises(ParameterError, match="constant"):
        ljung_box(np.ones(50))


def test_a_non_finite_prediction_is_an_error_not_a_perfect_fit(monkeypatch) -> None:
    """NaN predictions dropped by nan-aware means once printed 'open-loop RMSE 0.000 K'."""
    import numpy as np
    import pytest

    from rczone.errors import InputShapeError
    from rczone.postfit import openloop as validation

    from ..estimation.nets import NET1, data1

    data = data1()

    def broken(network, values, data, hold="zoh"):
        y = np.full(data.y.shape, np.nan)
        return np.zeros((data.n_samples, 1)), y

    monkeypatch.setattr(validation, "simulate_output", broken)
    with pytest.raises(InputShapeError, match="not finite from sample 0"):
        validation.open_loop_error(NET1, {}, data)


def test_per_output_errors_skip_missing_samples_column_by_column():
    e = np.array([[1.0, np.nan, np.nan], [-3.0, 2.0, np.nan], [np.nan, -0.5, np.nan]])
    rmse, worst = per_output_errors(e)
    np.testing.assert_allclose(rmse[:2], [np.sqrt((1 + 9) / 2), np.sqrt((4 + 0.25) / 2)])
    np.testing.assert_allclose(worst[:2], [3.0, 2.0])
    assert np.isnan(rmse[2]) and np.isnan(worst[2])  # a column without measurements
