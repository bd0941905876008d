from __future__ import annotations

import math

import numpy as np
import pytest

from rczone.estimation import Dataset, Objective, ls_cost, make_spec, ml_cost
from rczone.estimation.costs import (
    auto_initial_state,
    filter_arrays,
    log_prior_penalty,
    run_filter,
    trapezoid_sse,
)
from rczone.estimation.kalman import kalman_innovations_fast

from .nets import NET1, NET2, data2


def test_trapezoid_skips_intervals_touching_a_gap() -> None:
    t = np.array([0.0, 10.0, 25.0, 30.0, 70.0, 100.0])
    e = np.full((6, 1), 2.0)
    assert trapezoid_sse(t, e) == pytest.approx(4.0 * 100.0)
    e[3] = np.nan  # removes [25, 30] and [30, 70]
    assert trapezoid_sse(t, e) == pytest.approx(4.0 * (100.0 - 45.0))


def test_ls_cost_matches_analytic_integral_of_a_decaying_error() -> None:
    # 1-state model at rest at 10 degC, model started 3 K too warm: e(t) = 3 exp(-t / tau)
    R, C = 0.01, 1e6
    tau = R * C
    n = 2001
    t = np.linspace(0.0, 3 * tau, n)
    u = np.column_stack([np.full(n, 10.0), np.zeros(n)])
    data = Dataset(t, u, np.zeros((n, 0)), np.full((n, 1), 10.0), NET1.input_names, (), NET1.outputs)
    J = ls_cost(NET1, {"R": R, "Cr": C, "x0_Ti": 13.0}, data)
    exact = 9.0 * tau / 2 * (1 - math.exp(-6.0))
    assert J == pytest.approx(exact, rel=1e-5)


def test_ls_cost_is_zero_at_truth_and_positive_elsewhere() -> None:
    data = data2()
    assert ls_cost(NET2, {}, data) < 1e-18
    assert ls_cost(NET2, {"Rw": 0.02}, data) > 1e-2


def test_auto_initial_state_puts_wall_at_steady_state_given_measured_room() -> None:
    ss = NET2.state_space()
    u0 = np.array([30.0, 20.0, 14.0, 0.0])
    x0 = auto_initial_state(ss, u0, np.array([0.0]), np.array([24.0]))
    R1 = R2 = 0.005
    assert x0[0] == 24.0
    assert x0[1] == pytest.approx((24.0 / R1 + 20.0 / R2) / (1 / R1 + 1 / R2), rel=1e-12)
    # without a first measurement: the full steady state, where dx/dt = 0
    x0 = auto_initial_state(ss, u0, np.array([0.05]), np.array([np.nan]))
    A, B = ss.matrices([0.05])
    np.testing.assert_allclose(A @ x0 + B @ u0, 0.0, atol=1e-12)


def test_map_adds_log_normal_prior_on_free_r_and_c_only() -> None:
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    spec = make_spec(NET2, ["Cr", "Rw", "sigma_v"])
    theta = np.array([2 * 8e5, 0.01 / 4, 0.07])
    s = 0.5
    expect = 0.5 * (math.log(2) / s) ** 2 + 0.5 * (math.log(4) / s) ** 2
    assert log_prior_penalty(spec, theta, s) == pytest.approx(expect, rel=1e-12)
    ml = Objective(NET2, data, spec, "ml")
    mp = Objective(NET2, data, spec, "map", prior_spread=s)
    eta = spec.to_eta(theta)
    assert mp(eta) - ml(eta) == pytest.approx(expect, rel=1e-9)
    assert ml(eta) == pytest.approx(ml_cost(NET2, spec.values(theta), data), rel=1e-12)


def test_objective_never_mutates_network_or_data() -> None:
    data = data2()
    before = {k: (p.value, p.expr) for k, p in NET2.parameters.items()}
    y_before = data.y.copy()
    spec = make_spec(NET2, ["Cr", "Rw"])
    Objective(NET2, data, spec, "ml")(np.log([1e5, 0.5]))
    Objective(NET2, data, spec, "ls")(np.log([1e5, 0.5]))
    assert {k: (p.value, p.expr) for k, p in NET2.parameters.items()} == before
    np.testing.assert_array_equal(data.y, y_before)


def test_compiled_innovations_equal_the_reference_filter() -> None:
    rng = np.random.default_rng(3)
    data = data2(noise=0.05, rng=rng)
    y = data.y.copy()
    y[[5, 40, 41]] = np.nan  # missing samples skip the update and stay NaN
    data = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    values = {**NET2.values(), "sigma_v": 0.05, "sigma_w_Ti": 1e-3, "sigma_w_Tw": 1e-4}
    values |= {"sigma_x0_Ti": 0.1, "sigma_x0_Tw": 1.0}
    ref = run_filter(NET2, values, data).innovations
    got = kalman_innovations_fast(filter_arrays(NET2, values, data))
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)
    assert np.isnan(got[[5, 40, 41]]).all() and np.isfinite(got[:5]).all()


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_ls_cost_fast_path_equals_the_open_loop_simulation(hold) -> None:
    from rczone.estimation.costs import simulate_output

    data = data2(noise=0.05, rng=np.random.default_rng(8))
    y = data.y.copy()
    y[[3, 70]] = np.nan
    data = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    values = {**NET2.values(), "Rw": 0.013}
    _, yhat = simulate_output(NET2, values, data, hold)  # general path: expm-free spectral + propagation
    assert ls_cost(NET2, values, data, hold) == pytest.approx(trapezoid_sse(data.t, data.y - yhat), rel=1e-12)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_ml_cost_from_parameter_values_equals_the_reference_filter(hold) -> None:
    """The general engine (Python assembly, compiled discretization and filter) vs the NumPy reference."""
    from rczone.models import get_model
    from tests.oracles import reference_cost

    rng = np.random.default_rng(11)
    for net in (NET2, get_model("second-order-paper")):
        data = data2(noise=0.05, rng=rng) if net is NET2 else None
        if data is None:
            from rczone import datasets
            from rczone.calibration import dataset

            data = dataset(net, datasets.load("C").iloc[:200], {"Q": 50.0})
        for _ in range(3):
            base = {n: net.values()[n] * np.exp(rng.uniform(-0.5, 0.5)) for n in net.free_parameter_names}
            values = {**base, "sigma_v": 0.05, "sigma_w_Ti": 2e-3, "sigma_w_Tw": 1e-4, "sigma_x0_Ti": 0.1}
            values["sigma_x0_Tw"] = 1.0
            ref = reference_cost(net, values, data, hold, "ml")
            assert ml_cost(net, values, data, hold) == pytest.approx(ref, rel=1e-10)
            assert run_filter(net, values, data, hold).nll == pytest.approx(ref, rel=1e-10)


def test_public_costs_with_new_values_on_the_same_problem_stay_exact_and_refuse_invalid_values() -> None:
    """ml_cost/ls_cost reuse the compiled problem of the first call: later values are still the reference's."""
    from rczone.errors import ParameterError
    from tests.oracles import reference_cost

    rng = np.random.default_rng(24)
    data = data2(noise=0.05, rng=rng)
    noise = {"sigma_v": 0.05, "sigma_w_Ti": 2e-3, "sigma_w_Tw": 1e-4, "sigma_x0_Ti": 0.1, "sigma_x0_Tw": 1.0}
    for _ in range(3):
        values = {
            "Rw": 0.01 * np.exp(rng.uniform(-0.5, 0.5)),
            "Cr": 8e5 * np.exp(rng.uniform(-0.5, 0.5)),
            **noise,
        }
        assert ml_cost(NET2, values, data) == pytest.approx(
            reference_cost(NET2, values, data, "zoh", "ml"), rel=1e-10
        )
        ls_values = {"Rw": values["Rw"], "Cr": values["Cr"], "x0_Tw": 21.0 + rng.uniform()}
        assert ls_cost(NET2, ls_values, data) == pytest.approx(
            reference_cost(NET2, ls_values, data, "zoh", "ls"), rel=1e-10
        )
    with pytest.raises(ParameterError, match="sigma_v"):
        ml_cost(NET2, {**values, "sigma_v": -0.1}, data)
    with pytest.raises(ParameterError):
        ml_cost(NET2, {**values, "Rw": -0.01}, data)
