from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import Objective, fit, make_spec
from rczone.estimation.uncertainty import (
    covariance,
    curvature_from_gradient,
    fix_parameter,
    hessian,
    hessian_from_gradient,
    profile,
)

from .nets import NET1, NET2, data1, data2


def _analytic_hessian(x: np.ndarray) -> np.ndarray:
    """Second derivatives of ``exp(a) b^2 + sin(a c) + 4 c^2``, by hand."""
    a, b, c = x
    return np.array(
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


def test_hessian_matches_analytic_second_derivatives() -> None:
    def f(x: np.ndarray) -> float:
        return float(np.exp(x[0]) * x[1] ** 2 + np.sin(x[0] * x[2]) + 4 * x[2] ** 2)

    x = np.array([0.3, -1.5, 2.0])
    exact = _analytic_hessian(x)
    np.testing.assert_allclose(hessian(f, x), exact, rtol=1e-6, atol=1e-6)


def _analytic_value_and_gradient(x: np.ndarray) -> tuple[float, np.ndarray]:
    a, b, c = x
    f = float(np.exp(a) * b**2 + np.sin(a * c) + 4 * c**2)
    g = np.array([np.exp(a) * b**2 + c * np.cos(a * c), 2 * np.exp(a) * b, a * np.cos(a * c) + 8 * c])
    return f, g


def test_hessian_and_curvature_from_exact_gradients_match_analytic_second_derivatives() -> None:
    x = np.array([0.3, -1.5, 2.0])
    exact = _analytic_hessian(x)
    np.testing.assert_allclose(
        hessian_from_gradient(_analytic_value_and_gradient, x), exact, rtol=1e-8, atol=1e-8
    )
    np.testing.assert_allclose(
        curvature_from_gradient(_analytic_value_and_gradient, x), np.diag(exact), rtol=1e-5
    )

    def invalid_above(z: np.ndarray) -> tuple[float, np.ndarray]:  # a bound just above x[2]: one-sided there
        return (np.inf, np.zeros(3)) if z[2] > x[2] else _analytic_value_and_gradient(z)

    np.testing.assert_allclose(hessian_from_gradient(invalid_above, x)[2, 2], exact[2, 2], rtol=1e-4)
    np.testing.assert_allclose(curvature_from_gradient(invalid_above, x)[2], exact[2, 2], rtol=1e-4)


def test_two_state_standard_errors_from_adjoint_gradients_match_those_from_values() -> None:
    """An ML fit of the fused 2-state engine takes its Hessian from differences of the adjoint gradient;
    its standard errors and correlations agree with those of the four-point value Hessian used before."""
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v"]
    fixed = {"sigma_w_Ti": 1e-3, "sigma_w_Tw": 1e-6}
    res = fit(NET2, data, free, method="ml", n_starts=1, fixed=fixed)
    spec = make_spec(NET2, free, fixed=fixed)
    obj = Objective(NET2, data, spec, "ml")
    assert obj.adjoint_gradient
    theta = np.array([res.estimates[n] for n in spec.names])
    by_values = covariance(spec, theta, hessian(obj, spec.to_eta(theta)))
    se = np.array([res.std_errors[n] for n in spec.names])
    assert np.isfinite(se).all()
    np.testing.assert_allclose(se, by_values.std_error, rtol=1e-4)
    by_gradients = covariance(spec, theta, hessian_from_gradient(obj.value_and_gradient, spec.to_eta(theta)))
    np.testing.assert_allclose(by_gradients.std_error, se, rtol=1e-12)
    np.testing.assert_allclose(by_gradients.correlation, by_values.correlation, atol=1e-4)


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


def test_the_adaptive_search_hands_its_first_hessian_to_the_standard_errors() -> None:
    """The default ML search computes the Hessian at its first search's end (its diagonal scales the
    restart that confirms it); the standard errors are those of a Hessian computed anew at the estimate,
    wherever the winning end lies."""
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v"]
    fixed = {"sigma_w_Ti": 1e-3, "sigma_w_Tw": 1e-6}
    res = fit(NET2, data, free, method="ml", fixed=fixed)
    spec = make_spec(NET2, free, fixed=fixed)
    obj = Objective(NET2, data, spec, "ml")
    first = res.starts[0]
    assert first.hessian is not None and res.starts[1].hessian is None
    np.testing.assert_array_equal(
        first.hessian, hessian_from_gradient(obj.value_and_gradient, spec.to_eta(first.end))
    )
    theta = np.array([res.estimates[n] for n in spec.names])
    fresh = covariance(spec, theta, hessian_from_gradient(obj.value_and_gradient, spec.to_eta(theta)))
    np.testing.assert_array_equal([res.std_errors[n] for n in spec.names], fresh.std_error)


@pytest.mark.parametrize("seed", [3, 5])
def test_standard_errors_of_a_reverse_pass_fit_equal_those_of_value_differences(
    seed: int, monkeypatch
) -> None:
    """Where the gradient is the general filter's reverse pass, the standard errors come from 2 d
    gradients; on a well-conditioned fit they equal those of the Hessian of 2 d^2 likelihood values
    (an independent route; near-singular Hessians differ by the two routes' rounding)."""
    from .test_reverse_gradient import bilinear

    net, data = bilinear(seed)
    free = [*net.free_parameter_names, "sigma_v_" + net.outputs[1]]

    def no_values(*args, **kwargs):
        raise AssertionError("the fit took the Hessian of 2 d^2 values")

    with monkeypatch.context() as m:
        m.setattr("rczone.estimation.minimize.hessian", no_values)
        res = fit(net, data, free, method="ml", n_starts=1)
    spec = make_spec(net, free)
    obj = Objective(net, data, spec, "ml")
    assert obj.engine == "compiled" and obj.backward_gradient and not obj.adjoint_gradient
    theta = np.array([res.estimates[n] for n in spec.names])
    by_values = covariance(spec, theta, hessian(obj, spec.to_eta(theta)), held=spec.near_bound(theta))
    got = np.array([res.std_errors[n] for n in spec.names])
    off = ~spec.near_bound(theta)  # estimates at a bound are held: no standard error either way
    assert off.sum() >= 6 and np.isfinite(by_values.std_error[off]).all()
    np.testing.assert_allclose(got[off], by_values.std_error[off], rtol=1e-3)
