"""Sandwich (Huber-White) standard errors: the formula against statsmodels, the scores against the likelihood.

* The formula: statsmodels' SARIMAX fitted with ``cov_type='robust'`` on an AR(1) with
  heteroscedastic noise (where the sandwich and the Hessian differ); rczone's :func:`sandwich` of
  statsmodels' own inverse Hessian and per-observation scores must give its covariance.
* The scores: the per-sample log-densities sum to minus rczone's ML cost, and the per-sample
  scores sum to the gradient of the whole log-likelihood taken by differences of the cost.
"""

from __future__ import annotations

import numpy as np
import pytest

from rczone.postfit.robust import sample_loglik, sandwich


def test_the_sandwich_equals_statsmodels_robust_covariance_of_sarimax():
    sm = pytest.importorskip("statsmodels.api")
    rng = np.random.default_rng(0)
    n = 1500
    scale = np.where(np.arange(n) % 200 < 100, 0.3, 1.5)  # the model assumes one variance: misspecified
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + scale[k] * rng.standard_normal()
    model = sm.tsa.SARIMAX(y, order=(1, 0, 0))
    robust = model.fit(disp=False, cov_type="robust")
    hessian_inv = robust.cov_params_approx  # statsmodels' inverse Hessian (approx), the bread
    scores = model.score_obs(robust.params, approx_complex_step=True)  # statsmodels' per-observation scores
    mine = sandwich(np.asarray(hessian_inv), np.asarray(scores))
    np.testing.assert_allclose(mine, np.asarray(robust.cov_params_robust_approx), rtol=1e-6)
    # the covariance cached at fit time was taken from the optimizer's last state: 0.1 % away
    np.testing.assert_allclose(mine, np.asarray(robust.cov_params()), rtol=5e-3)
    # and the two differ here, so the comparison is not of two equal numbers
    assert not np.allclose(np.diag(mine), np.diag(np.asarray(hessian_inv)), rtol=0.2)


@pytest.fixture(scope="module")
def problem():
    from rczone.calibration import dataset
    from rczone.models import load_model
    from tests.unit.selection.synthetic import prbs_zone

    zm = load_model("TiTe+heater")
    frame = prbs_zone(days=1, seed=4)
    data = dataset(zm, frame)
    from rczone.estimation.parameters import noise_parameter_names
    from rczone.network.stochastic import default_value

    defaults = {n: default_value(n) for n in noise_parameter_names(zm.network)}
    values = {**zm.theta, **{k: v for k, v in defaults.items() if v is not None}}
    values.update({"sigma_v": 0.05, "sigma_w_Ti": 2e-3, "sigma_w_Te": 1e-3})
    return zm.network, values, data


def test_the_per_sample_log_densities_sum_to_the_log_likelihood(problem):
    from rczone.estimation.costs import ml_cost

    net, values, data = problem
    ll = sample_loglik(net, values, data)
    assert ll.shape == (data.n_samples,)
    assert ll.sum() == pytest.approx(-ml_cost(net, values, data), rel=1e-10)


def test_the_scores_sum_to_the_gradient_of_the_log_likelihood(problem):
    from rczone.estimation.costs import ml_cost
    from rczone.postfit.robust import scores

    net, values, data = problem

    from types import SimpleNamespace

    from rczone.results import Estimate

    names = ("Ci", "Rea")
    fit = SimpleNamespace(  # the fields of a FitResult that scores() reads
        names=names,
        fixed={k: v for k, v in values.items() if k not in names},
        estimates={k: values[k] for k in names},
        hold="zoh",
        correlation=np.eye(2),
        parameters={
            k: Estimate(k, values[k], 0.1 * values[k], 0.0, np.inf, np.nan, False, log_scale=True)
            for k in names
        },
    )
    s = scores(net, fit, data, list(names))
    for i, name in enumerate(names):  # d(-cost)/d(log theta) by a wider central difference of the total
        h = 1e-3
        up = ml_cost(net, {**values, name: values[name] * np.exp(h)}, data)
        down = ml_cost(net, {**values, name: values[name] * np.exp(-h)}, data)
        assert s[:, i].sum() == pytest.approx(-(up - down) / (2 * h), rel=1e-4)
