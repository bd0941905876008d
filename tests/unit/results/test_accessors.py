"""statsmodels' accessors on what ``rczone.fit`` returns, checked against statsmodels itself.

statsmodels' ``LikelihoodModelResults`` is given the same estimates and covariance: its
``bse``, ``tvalues``, ``pvalues`` and normal ``conf_int`` are the reference. R and C are searched
on a log scale, so their intervals are statsmodels' intervals of ``log v`` (standard error
``se / v``, the delta method) mapped back by ``exp``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm
from statsmodels.base.model import LikelihoodModelResults

import rczone
from rczone.errors import ParameterError
from tests.unit.selection.synthetic import prbs_zone

MODEL = "TiTe+heater"


class _Names:
    """The little of a statsmodels model its results read: the parameter names."""

    def __init__(self, names):
        self.exog_names = list(names)
        self.data = type("Data", (), {"param_names": list(names), "xnames": list(names)})()


@pytest.fixture(scope="module")
def zone():
    return prbs_zone(days=1, seed=7)


@pytest.fixture(scope="module")
def cal(zone):
    return rczone.fit(MODEL, zone, method="ml", n_starts=1, checks=False, profiles=False)


def statsmodels_of(params: np.ndarray, cov: np.ndarray, names) -> LikelihoodModelResults:
    return LikelihoodModelResults(_Names(names), params, normalized_cov_params=cov, scale=1.0)


def test_params_bse_and_cov_params_are_labelled(cal):
    names = list(cal.result.names)
    assert isinstance(cal.params, pd.Series) and list(cal.params.index) == names
    assert cal.params.to_dict() == cal.result.estimates
    np.testing.assert_array_equal(cal.bse.to_numpy(), [cal.result.std_errors[n] for n in names])
    cov = cal.cov_params()
    assert list(cov.index) == names == list(cov.columns)
    np.testing.assert_allclose(np.diag(cov.to_numpy()), cal.bse.to_numpy() ** 2, rtol=1e-12)
    np.testing.assert_allclose(cov.to_numpy(), cov.to_numpy().T, rtol=1e-12)
    assert list(cal.correlation.index) == names and np.allclose(np.diag(cal.correlation), 1.0)


def test_tvalues_pvalues_and_bse_equal_statsmodels(cal):
    sm = statsmodels_of(cal.params.to_numpy(), cal.cov_params().to_numpy(), cal.params.index)
    np.testing.assert_allclose(cal.bse.to_numpy(), sm.bse, rtol=1e-12)
    np.testing.assert_allclose(cal.tvalues.to_numpy(), sm.tvalues, rtol=1e-12)
    np.testing.assert_allclose(cal.pvalues.to_numpy(), sm.pvalues, rtol=1e-9, atol=1e-300)


@pytest.mark.parametrize("alpha", [0.01, 0.05, 0.3])
def test_conf_int_is_statsmodels_interval_on_the_search_scale(cal, alpha):
    est = cal.result.parameters
    names = list(est)
    logs = np.array([est[n].log_scale for n in names])
    v, se = cal.params.to_numpy(), cal.bse.to_numpy()
    scale = np.where(logs, v, 1.0)  # d log v = dv / v
    params = np.where(logs, np.log(v), v)
    cov = cal.correlation.to_numpy() * np.outer(se / scale, se / scale)
    ref = np.asarray(statsmodels_of(params, cov, names).conf_int(alpha))
    ref = np.where(logs[:, None], np.exp(ref), ref)
    np.testing.assert_allclose(cal.conf_int(alpha=alpha).to_numpy(), ref, rtol=1e-10)


def test_likelihood_and_criteria_are_at_the_top(cal):
    r = cal.result
    assert (cal.llf, cal.aic, cal.bic, cal.nobs, cal.df_model) == (r.llf, r.aic, r.bic, r.nobs, r.n_params)
    assert np.isfinite(cal.llf) and cal.nobs > 100
    assert cal.aic == pytest.approx(2 * cal.df_model - 2 * cal.llf)


def test_summary_opens_with_a_header_block(cal):
    text = cal.summary()
    head = text.split("\n\n")[0].splitlines()
    assert head[0].startswith("Model:") and MODEL in head[0]
    assert any(line.startswith("Log-Likelihood:") and f"{cal.llf:.6g}" in line for line in head)
    assert any(line.startswith("No. Observations:") for line in head)
    assert "fitted to" in text  # the command line's summary follows


@pytest.mark.parametrize("alpha", [0.0455, 0.1, 0.5])
def test_summary_frame_gives_a_band_at_any_alpha(cal, zone, alpha):
    pred = cal.get_prediction(zone, steps=3)
    frame = pred.summary_frame(alpha=alpha)
    assert list(frame.columns) == ["mean", "mean_se", "mean_ci_lower", "mean_ci_upper"]
    z = norm.ppf(1 - alpha / 2)
    np.testing.assert_allclose(frame["mean_ci_upper"] - frame["mean"], z * pred.sd[:, 0], rtol=1e-12)
    np.testing.assert_allclose(frame["mean"] - frame["mean_ci_lower"], z * pred.sd[:, 0], rtol=1e-12)
    if alpha == 0.0455:  # about two standard deviations: the report's band
        np.testing.assert_allclose(frame["mean_ci_upper"], pred.band[1][:, 0], atol=1e-3)


def test_forecast_is_the_k_step_prediction(cal, zone):
    fc = cal.forecast(2, zone)
    np.testing.assert_array_equal(fc["Ti"].to_numpy(), cal.get_prediction(zone, steps=2).predicted[:, 0])


@pytest.mark.parametrize("alpha", [0, 1, -0.1, True, "0.05"])
def test_a_bad_alpha_is_one_line(cal, alpha):
    with pytest.raises(ParameterError, match="alpha must be a number in"):
        cal.conf_int(alpha=alpha)
