from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import Objective, fit, make_spec
from rczone.estimation.uncertainty import covariance, fix_parameter, hessian, profile

from .nets import NET1, data1


def test_hessian_matches_analytic_second_derivatives() -> None:
    def f(x: np.ndarray) -> float:
        return float(np.exp(x[0]) * x[1] ** 2 + np.sin(x[0] * x[2]) + 4 * x[2] ** 2)

    x = np.array([0.3, -1.5, 2.0])
    a, b, c = x
    exact = np.array(
        [
            [
                np.exp(a) * b**2 - c**2 * np.sin(a * c),
                2 * np.exp(a) * b,
                np.cos(a * c) - a * c * np.sin(a * c),
            ],
            [2 * np.exp(a) * b, 2 * np.exp(a), 0.0],
            [np.cos(a * c) - a * c * np.sin(a * c), 0.0, -(a**2) * np.sin(a * c) + 8],
        ]
    )
    np.testing.assert_allclose(hessian(f, x), exact, rtol=1e-6, atol=1e-6)


def test_delta_method_maps_log_covariance_to_physical_units() -> None:
    spec = make_spec(NET1, ["Cr", "R"])
    theta = np.array([2e6, 0.02])
    H = np.array([[400.0, 100.0], [100.0, 100.0]])
    unc = covariance(spec, theta, H)
    cov_eta = np.linalg.inv(H)
    np.testing.assert_allclose(unc.std_error, theta * np.sqrt(np.diag(cov_eta)), rtol=1e-12)
    assert unc.correlation[0, 1] == pytest.approx(cov_eta[0, 1] / np.sqrt(cov_eta[0, 0] * cov_eta[1, 1]))
    bad = covariance(spec, theta, np.array([[1.0, 2.0], [2.0, 1.0]]))
    assert not bad.positive_definite and np.isnan(bad.std_error).all()


def test_profile_likelihood_interval_agrees_with_wald_interval() -> None:
    """For a well-identified parameter the likelihood-ratio and Wald intervals nearly coincide."""
    rng = np.random.default_rng(11)
    d = data1(n=97)
    y = d.y + 0.05 * rng.standard_normal(d.y.shape)
    from rczone.estimation import Dataset

    data = Dataset(d.t, d.u, d.m, y, d.input_names, d.flow_names, d.output_names)
    fixed = {"sigma_w_Ti": 1e-7, "sigma_x0_Ti": 0.05}
    res = fit(NET1, data, ["Cr", "R", "sigma_v"], method="ml", optimizer="lbfgs", fixed=fixed)
    spec = make_spec(NET1, ["Cr", "R", "sigma_v"], fixed=fixed)
    obj = Objective(NET1, data, spec, "ml")
    theta = np.array([res.estimates[n] for n in spec.names])
    r, se = res.estimates["R"], res.std_errors["R"]
    grid = r + se * np.linspace(-3, 3, 13)
    prof = profile(obj, theta, "R", grid, optimizer="lbfgs")
    assert prof.cost.min() == pytest.approx(res.objective_value, abs=1e-6)  # the optimum lies on the profile
    assert int(np.argmin(prof.cost)) == 6
    lo, hi = prof.interval
    assert lo == pytest.approx(r - 1.96 * se, abs=0.15 * se)
    assert hi == pytest.approx(r + 1.96 * se, abs=0.15 * se)


def test_profile_and_fix_reject_bad_names_and_grids() -> None:
    spec = make_spec(NET1, ["Cr", "R"])
    with pytest.raises(ParameterError, match="not a free parameter"):
        fix_parameter(spec, "Rx", 1.0)
    with pytest.raises(ParameterError, match="only free parameter"):
        fix_parameter(make_spec(NET1, ["R"]), "R", 1.0)
    obj = Objective(NET1, data1(n=20), spec)
    with pytest.raises(ParameterError, match="inside its bounds"):
        profile(obj, spec.start, "R", [1e-6, 0.01])
