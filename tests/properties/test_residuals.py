"""The compiled residuals of least squares and their Jacobian (:mod:`rczone.kernels.residuals`).

* ``sum r^2`` is the cost the LS fit minimizes (the Objective, fused 2-state kernel or general
  compiled filter) and the NumPy reference cost of ``tests/oracles.py``;
* the Jacobian equals central differences of the residual vector, column by column (relative to
  the column's size), on random RC networks with several outputs, supply-air flows, irregular
  sampling, missing samples and free initial states, with both holds.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rczone.estimation import Objective, make_spec
from rczone.kernels.residuals import residuals, trapezoid_weights
from tests.oracles import objective_reference_cost
from tests.properties.test_gradients import problem
from tests.unit.estimation.nets import NET2, data2


def residual_in_eta(obj: Objective, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    res = residuals(obj.spec.to_theta(eta), obj.compiled)
    assert res.valid
    return res.r, res.jac * obj.spec.jacobian(eta)


def central_jacobian(obj: Objective, eta: np.ndarray, h: float = 1e-4) -> np.ndarray:
    # truncation ~h^2 of a log-scale variable (1e-8 relative); rounding ~1e-14 / h
    cols = []
    for j in range(eta.size):
        e = np.zeros(eta.size)
        e[j] = h
        cols.append((residual_in_eta(obj, eta + e)[0] - residual_in_eta(obj, eta - e)[0]) / (2 * h))
    return np.column_stack(cols)


def assert_jacobian_matches(obj: Objective, eta: np.ndarray) -> None:
    r, jac = residual_in_eta(obj, eta)
    fd = central_jacobian(obj, eta)
    # relative to the column, plus the differences' own rounding (~1e-13 |r| / h) for columns near zero
    for j in range(eta.size):
        err = np.linalg.norm(jac[:, j] - fd[:, j])
        assert err <= 1e-6 * np.linalg.norm(fd[:, j]) + 1e-7 * np.linalg.norm(r), obj.spec.names[j]


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 4),
    st.integers(1, 3),
    st.sampled_from(["zoh", "foh"]),
    st.integers(1, 2),
)
def test_residuals_square_to_the_ls_cost_and_their_jacobian_is_the_finite_difference_one(
    seed, n_cap, n_outputs, hold, n_flows
):
    obj, eta = problem(seed, n_cap, 0, n_outputs, "ls", hold, n_flows)
    assert obj.compiled is not None
    r, _ = residual_in_eta(obj, eta)
    theta = obj.spec.to_theta(eta)
    assert np.sum(r**2) == pytest.approx(obj(eta), rel=1e-10)
    assert np.sum(r**2) == pytest.approx(objective_reference_cost(obj, theta), rel=1e-10)
    assert_jacobian_matches(obj, eta)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_two_state_residuals_match_the_fused_kernel_the_fit_minimizes(hold) -> None:
    """NET2 (bilinear supply air, a flow changing every 4 h, a tied resistance) takes the fused 2-state kernel."""
    d = data2(noise=0.05, rng=np.random.default_rng(2))
    y = d.y.copy()
    y[[5, 6, 60]] = np.nan
    data = type(d)(d.t, d.u, d.m, y, d.input_names, d.flow_names, d.output_names)
    spec = make_spec(NET2, ["Cr", "Cw", "Rw", "Rwin", "x0_Tw"], start={"x0_Tw": 21.0})
    obj = Objective(NET2, data, spec, "ls", hold)
    assert obj.engine == "rc2-fused"
    eta = spec.to_eta(spec.start) + np.random.default_rng(4).uniform(-0.5, 0.5, spec.n_free)
    r, _ = residual_in_eta(obj, eta)
    assert np.sum(r**2) == pytest.approx(obj(eta), rel=1e-10)
    assert_jacobian_matches(obj, eta)


def test_trapezoid_weights_count_only_intervals_with_both_ends_measured() -> None:
    t = np.array([0.0, 10.0, 30.0, 60.0, 100.0])
    y = np.array([[1.0], [np.nan], [1.0], [1.0], [1.0]])
    # intervals 0-1 and 1-2 touch the gap; 2-3 (30 s) and 3-4 (40 s) count
    np.testing.assert_array_equal(trapezoid_weights(t, y)[:, 0], [0.0, 0.0, 15.0, 35.0, 20.0])


def test_invalid_values_give_invalid_residuals() -> None:
    spec = make_spec(NET2, ["Cr", "Rw"])
    obj = Objective(NET2, data2(), spec, "ls")
    res = residuals(np.array([-1.0, 0.01]), obj.compiled)
    assert not res.valid and np.isnan(res.r).all()
