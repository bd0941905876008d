"""The reverse-mode gradient of the general filter (rczone.kernels.reverse) against two independent ones.

Each case compares :meth:`Objective.value_and_gradient` of a compiled likelihood (the reverse pass,
:func:`rczone.kernels.adjoint.gradient_general`) with

* 5-point differences of the value (:meth:`Objective.__call__`, the value kernel), and
* the forward sensitivities of the filter (:func:`rczone.kernels.problem.value_and_gradient`),

on: a bilinear 3-state network with two outputs, several distinct intervals and outputs missing
independently (ZOH, FOH, MAP with its log-normal prior), a chain whose covariance becomes
stationary and leaves its steady state both ways (the observed outputs change, the interval
changes), and the 8-state, 4-output four-zone problem of ``bench/problems.py``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from rczone.estimation import Dataset, Objective, make_spec
from rczone.kernels.arrays import Discretization, FilterOptions, FilterStart, Observation, Series
from rczone.kernels.discretize import rc_interval_derivatives
from rczone.kernels.problem import assembled, value_and_gradient
from rczone.kernels.reverse import contract, nll_reverse, zero_adjoints
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation import simulate
from tests.netfactory import random_network

from .test_gradient import five_point


def agree(obj: Objective, eta: np.ndarray) -> None:
    """The reverse gradient equals the forward sensitivities (1e-8) and 5-point differences (1e-6)."""
    assert obj._reverse and obj.engine == "compiled"
    j, g = obj.value_and_gradient(eta)
    theta = np.asarray(obj.spec.to_theta(eta), dtype=float)
    j_fwd, g_fwd, _ = value_and_gradient(theta, obj.compiled)
    g_fwd = g_fwd * obj.spec.jacobian(eta)
    assert j == pytest.approx(obj(eta), rel=1e-12)
    assert j == pytest.approx(j_fwd, rel=1e-12)
    np.testing.assert_allclose(g, g_fwd, rtol=0, atol=1e-8 * np.linalg.norm(g_fwd))
    ref = five_point(obj, eta, 1e-3)
    np.testing.assert_allclose(g, ref, rtol=0, atol=1e-6 * np.linalg.norm(ref))


def bilinear(seed: int) -> tuple[RCNetwork, Dataset]:
    """A random 3-state network with supply air, 2 outputs; flows and steps giving several intervals."""
    rng = np.random.default_rng(seed)
    net = random_network(rng, 3, 0, 2, 2, 1)
    N = 60
    t = np.cumsum(np.r_[0.0, rng.choice([300.0, 300.0, 900.0], N - 1)])
    m = np.round(rng.uniform(0, 0.3, (N, 1)), 1)
    u = 20 + 3 * rng.standard_normal((N, len(net.input_names)))
    y = simulate(net.state_space(), t, u, m).y + 0.05 * rng.standard_normal((N, 2))
    y[rng.integers(1, N, 6), rng.integers(0, 2, 6)] = np.nan
    y[0, 1] = y[7, 0] = y[7, 1] = np.nan  # the first sample partly, one sample wholly unobserved
    return net, Dataset(t, u, m, y, net.input_names, net.flow_names, net.outputs)


@pytest.mark.parametrize(("method", "hold", "seed"), [("ml", "zoh", 1), ("ml", "foh", 2), ("map", "zoh", 3)])
def test_reverse_gradient_of_a_bilinear_network_with_missing_outputs(
    method: str, hold: str, seed: int
) -> None:
    net, data = bilinear(seed)
    assert data.intervals[0].shape[0] > 3
    noise = ["sigma_v_" + net.outputs[1], f"sigma_w_{net.state_names[0]}", f"sigma_w_{net.state_names[2]}"]
    x0 = f"x0_{net.state_names[-1]}"
    free = [*net.free_parameter_names, *noise, x0]
    spec = make_spec(net, free, start={x0: 20.0, noise[1]: 1e-3, noise[2]: 1e-3})
    obj = Objective(net, data, spec, method, hold, likelihood_weight=0.4 if method == "map" else 1.0)
    rng = np.random.default_rng(seed)
    agree(obj, spec.to_eta(spec.start) + rng.uniform(-0.3, 0.3, spec.n_free))


def chain() -> RCNetwork:
    """Three rooms in a row (time constants of an hour), the first and the last measured."""
    return RCNetwork(
        "chain",
        [Node("T0", "C0"), Node("T1", "C1"), Node("T2", "C2")],
        ["To"],
        [
            Resistor("T0", "To", "R0"),
            Resistor("T0", "T1", "R1"),
            Resistor("T1", "T2", "R2"),
            Resistor("T2", "To", "R0"),
        ],
        [
            Parameter("C0", "capacitance", 2e5),
            Parameter("C1", "capacitance", 5e5),
            Parameter("C2", "capacitance", 3e5),
            Parameter("R0", "resistance", 0.02),
            Parameter("R1", "resistance", 0.01),
            Parameter("R2", "resistance", 0.015),
        ],
        heat_inputs=[HeatInput("Q", {"T0": 1.0})],
        supply_air=[SupplyAir("T1", "m", "Ts")],
        outputs=["T0", "T2"],
    )


def stationary_data(net: RCNetwork) -> Dataset:
    """Regular steps except two longer ones, a constant flow, output T2 missing over a stretch."""
    rng = np.random.default_rng(9)
    N = 400
    dt = np.full(N - 1, 300.0)
    dt[[250, 320]] = 900.0  # the interval changes twice after the covariance has become stationary
    t = np.r_[0.0, np.cumsum(dt)]
    m = np.full((N, 1), 0.05)
    u = np.column_stack([5 + rng.standard_normal(N), 500 + 100 * rng.standard_normal(N), np.full(N, 18.0)])
    y = simulate(net.state_space(), t, u, m).y + 0.05 * rng.standard_normal((N, 2))
    y[180:200, 1] = np.nan  # the observed outputs change, and change back, in a steady state
    return Dataset(t, u, m, y, net.input_names, net.flow_names, net.outputs)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_reverse_gradient_through_steady_states_that_end_both_ways(hold: str) -> None:
    net = chain()
    data = stationary_data(net)
    free = ["C0", "C1", "C2", "R0", "R1", "R2", "sigma_v_T0", "sigma_v_T2", "sigma_w_T0", "sigma_w_T1"]
    start = {"sigma_v_T0": 0.05, "sigma_v_T2": 0.05, "sigma_w_T0": 0.02, "sigma_w_T1": 0.02}
    spec = make_spec(net, free, start=start)
    obj = Objective(net, data, spec, "ml", hold)
    eta = spec.to_eta(spec.start) + np.random.default_rng(4).uniform(-0.2, 0.2, spec.n_free)
    # the kernel itself on prefixes of the data: the covariance is stationary before each event
    prob = obj.compiled
    theta = np.asarray(spec.to_theta(eta), dtype=float)
    mod, der, ok = assembled(theta, prob, theta.size)
    assert ok
    mats, dmats = rc_interval_derivatives(
        mod, der, Discretization(prob.data.keys, np.sqrt(mod.cap), hold == "foh", True)
    )
    n, p, ny, K = 3, mod.B0.shape[1], 2, prob.data.keys.shape[0]
    obs = Observation(
        mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, 0, n)), np.zeros((ny, 0, p)), np.zeros((ny, 0))
    )
    prior = FilterStart(mod.x0, mod.P0, np.zeros((0, n)), np.zeros((0, n, n)))
    opts = FilterOptions(hold == "foh", False, 1e-14)
    u, y, which = prob.data.u, prob.data.y, prob.data.which

    def steady_samples(end: int) -> int:
        return nll_reverse(
            mats, obs, prior, Series(u[:end], y[:end], which[: end - 1]), opts, zero_adjoints(K, n, p, ny)
        )[2]

    # before the outputs change (180), before the first interval change (250), before the second (320)
    assert 0 < steady_samples(180)
    assert steady_samples(200) < steady_samples(250) < steady_samples(320) < steady_samples(400)
    bars = zero_adjoints(K, n, p, ny)
    nll_reverse(mats, obs, prior, Series(u, y, which), opts, bars)
    grad = np.zeros(theta.size)
    contract(bars, dmats, der, hold == "foh", grad)
    _, g = obj.value_and_gradient(eta)
    # FOH: the same contraction; ZOH: the adjoints carried back through the discretization
    # (kernels/discretize_adjoint.py), another order of the same sums: equal to rounding
    rtol = 1e-12 if hold == "foh" else 1e-10
    np.testing.assert_allclose(g, grad * spec.jacobian(eta), rtol=rtol, atol=0)
    agree(obj, eta)


def four_zone_problem():
    """The four-zone benchmark problem of ``bench/problems.py`` (8 states, 4 outputs, 22 free, LTI)."""
    path = Path(__file__).resolve().parents[3] / "bench" / "problems.py"
    module_spec = importlib.util.spec_from_file_location("bench_problems", path)
    problems = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(problems)
    return problems


def test_reverse_gradient_of_the_four_zone_problem() -> None:
    problems = four_zone_problem()
    net, data = problems.four_zones(), problems.four_zone_data()
    truth = {**problems.FOUR_ZONE_TRUTH, **problems.FOUR_ZONE_NOISE}
    fixed = {k: v for k, v in problems.FOUR_ZONE_NOISE.items() if k not in problems.FOUR_ZONE_FREE}
    spec = make_spec(
        net, problems.FOUR_ZONE_FREE, start={k: truth[k] for k in problems.FOUR_ZONE_FREE}, fixed=fixed
    )
    assert spec.n_free == 22
    obj = Objective(net, data, spec, "ml")
    agree(obj, spec.to_eta(spec.start) + np.random.default_rng(24).uniform(-0.3, 0.3, spec.n_free))


def test_reverse_gradient_of_an_invalid_model_is_infinite_as_its_value() -> None:
    """No noise anywhere: the first innovation variance is zero, so the value and the gradient's value are inf."""
    net, data = bilinear(1)
    free = ["sigma_v_" + net.outputs[0]]
    fixed = {"sigma_v_" + net.outputs[1]: 0.0, **{f"sigma_x0_{s}": 0.0 for s in net.state_names}}
    spec = make_spec(net, free, start={free[0]: 0.1}, fixed=fixed)
    obj = Objective(net, data, spec, "ml")
    eta = spec.to_eta(spec.start)
    assert obj(eta) == np.inf
    j, g = obj.value_and_gradient(eta)
    assert j == np.inf and np.all(g == 0.0)
