from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation.parameters import make_spec, noise_parameter_names

from .nets import NET2


def test_noise_parameter_names_follow_states() -> None:
    assert noise_parameter_names(NET2) == (
        "sigma_v",
        "sigma_w_Ti",
        "sigma_w_Tw",
        "x0_Ti",
        "x0_Tw",
        "sigma_x0_Ti",
        "sigma_x0_Tw",
    )


def test_transforms_round_trip_and_jacobian_matches_finite_difference() -> None:
    spec = make_spec(NET2, ["Cr", "Rw", "sigma_v", "x0_Tw", "g"], start={"x0_Tw": 20.0})
    assert spec.kinds == ("capacitance", "resistance", "noise", "state", "gain")
    np.testing.assert_array_equal(spec.log, [True, True, True, False, False])
    theta = np.array([3e5, 0.02, 0.05, 19.0, -0.5])
    eta = spec.to_eta(theta)
    np.testing.assert_allclose(eta, [np.log(3e5), np.log(0.02), np.log(0.05), 19.0, -0.5])
    np.testing.assert_allclose(spec.to_theta(eta), theta, rtol=1e-14)
    h = 1e-6
    fd = np.array(
        [
            (spec.to_theta(eta + h * e) - spec.to_theta(eta - h * e))[i] / (2 * h)
            for i, e in enumerate(np.eye(5))
        ]
    )
    np.testing.assert_allclose(spec.jacobian(eta), fd, rtol=1e-8)
    z = spec.to_z(eta)
    np.testing.assert_allclose(spec.from_z(z), eta, rtol=1e-12)
    # the bounded variable never leaves the bounds, even for huge z
    big = spec.from_z(np.full(5, 1e3))
    assert np.all(big <= spec.eta_upper) and np.all(spec.from_z(np.full(5, -1e3)) >= spec.eta_lower)


def test_defaults_fixed_values_and_construction() -> None:
    spec = make_spec(NET2, ["Cr"], fixed={"Rw": 0.02, "sigma_v": 0.3})
    assert spec.fixed["Rw"] == 0.02 and spec.fixed["sigma_v"] == 0.3 and spec.fixed["Cw"] == 6e6
    assert "R1" not in spec.fixed  # tied parameters follow Rw inside the network
    assert spec.construction[0] == 8e5
    assert spec.lower[0] == pytest.approx(8e2) and spec.upper[0] == pytest.approx(8e8)
    assert spec.values(np.array([1e5]))["Cr"] == 1e5


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"free": ["Rwn"]}, r"unknown free parameter 'Rwn'.*did you mean 'Rw"),
        ({"free": ["R1"]}, r"'R1' is tied .*Rw/2"),
        ({"free": ["sigma_w_Tx"]}, r"unknown free parameter 'sigma_w_Tx'.*did you mean"),
        ({"free": []}, "no free parameter"),
        ({"free": ["Cr", "Cr"]}, "listed twice"),
        ({"free": ["Cr"], "bounds": {"Cr": (1e6, 1e5)}}, r"lower 1e\+06 must be < upper 100000"),
        ({"free": ["Cr"], "bounds": {"Cr": (1e5, 1e5)}}, "must be < upper"),
        ({"free": ["Cr"], "bounds": {"Cr": (0.0, 1e7)}}, "needs a lower bound > 0"),
        ({"free": ["Cr"], "bounds": {"Cr": (1e6, 1e7)}}, r"start of 'Cr' = 800000 is outside its bounds"),
        ({"free": ["Cr"], "start": {"Cr": -1.0}}, r"start of 'Cr' = -1.0: expected a finite value > 0"),
        ({"free": ["Cr"], "bounds": {"Cw": (1.0, 2.0)}}, "not free"),
        ({"free": ["Cr"], "start": {"Cx": 1.0}}, r"unknown start value 'Cx'"),
        ({"free": ["Cr"], "fixed": {"Cr": 1.0}}, "both free and fixed"),
        ({"free": ["Cr"], "bounds": {"Cr": 5.0}}, r"must be a \(lower, upper\) pair"),
        ({"free": ["x0_Ti"]}, "has no start value"),
    ],
)
def test_bad_specs_raise_with_a_hint(kwargs, match) -> None:
    with pytest.raises(ParameterError, match=match):
        make_spec(NET2, **kwargs)


def test_near_bound_flags_estimates_at_bounds() -> None:
    spec = make_spec(NET2, ["Cr", "Rw"], bounds={"Cr": (1e5, 1e7), "Rw": (1e-3, 1.0)})
    np.testing.assert_array_equal(spec.near_bound(np.array([1e5 * (1 + 1e-6), 0.01])), [True, False])
    np.testing.assert_array_equal(spec.near_bound(np.array([1e6, 0.999999])), [False, True])
