"""A fit's log-likelihood, information criteria and engine, checked against the plain NumPy engine."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rczone.estimation import fit
from rczone.estimation.costs import Objective
from rczone.estimation.parameters import make_spec
from tests.oracles import objective_reference_cost
from tests.unit.estimation.test_fit import NET2, data2

FREE = ["Cr", "Rw", "sigma_v"]
FIXED = {"sigma_w_Ti": 1e-3, "sigma_w_Tw": 1e-6}


@pytest.fixture(scope="module")
def data():
    return data2(noise=0.02, rng=np.random.default_rng(1))


def _reference_loglik(res, data) -> float:
    """``log L`` at the estimates by the reference engine (plain NumPy Kalman filter), no prior, no tempering."""
    spec = make_spec(NET2, res.names, fixed={**FIXED, **res.fixed})
    theta = np.array([res.estimates[n] for n in spec.names])
    return -objective_reference_cost(Objective(NET2, data, spec, "ml"), theta)


@pytest.mark.parametrize("method", ["ml", "map"])
def test_llf_is_the_likelihood_of_the_plain_filter_at_the_estimates(method, data) -> None:
    res = fit(
        NET2,
        data,
        FREE,
        method=method,
        optimizer="lbfgs",
        n_starts=1,
        fixed=FIXED,
        options={"correlation_time_s": 6000.0} if method == "map" else None,  # 10 samples
    )
    assert res.llf == pytest.approx(_reference_loglik(res, data), rel=1e-8)
    k, n = 3, int(np.isfinite(data.y).sum())
    assert res.nobs == n and res.n_params == k
    assert res.aic == pytest.approx(2 * k - 2 * res.llf) and res.bic == pytest.approx(
        k * math.log(n) - 2 * res.llf
    )
    assert res.engine in ("rc2-fused", "compiled", "general", "reference")
    d = res.to_dict()
    assert (
        d["engine"] == res.engine and d["llf"] == pytest.approx(res.llf) and d["objective"] == res.objective
    )
    if method == "map":  # the objective is the tempered posterior (weight dt / 6000 s = 1/10), not -llf
        assert abs(res.objective_value) < 0.2 * abs(res.llf)
    else:
        assert res.objective_value == pytest.approx(-res.llf, rel=1e-10)


def test_least_squares_has_no_likelihood(data) -> None:
    res = fit(NET2, data, ["Cr", "Rw"], method="ls", n_starts=1, uncertainty=False)
    assert math.isnan(res.llf) and math.isnan(res.aic) and "squared output error" in res.objective
    ci = res.conf_int()
    assert list(ci.columns) == ["lower", "upper"] and ci.isna().all().all()  # no standard errors asked for
