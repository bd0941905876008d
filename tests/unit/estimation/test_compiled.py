"""The compiled estimation path against the Python one it replaces.

The Python path (:class:`rczone.estimation.costs.Objective` driven by SciPy's Nelder–Mead)
is the reference: the compiled cost must equal it to rounding at random points, and the
compiled search must end where SciPy's ends, on the same problems.
"""

from __future__ import annotations

import numpy as np
import pytest

import rczone.estimation.compiled as compiled_module
from rczone.estimation import Dataset, fit, make_spec
from rczone.estimation.compiled import compiled_cost, compiled_problem
from rczone.estimation.costs import Objective
from rczone.estimation.optimize import minimize_from
from rczone.kernels.neldermead import nelder_mead
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from tests.oracles import objective_reference_cost

from .nets import NET1, NET2, data1, data2

FREE = {"ls": ["Cr", "Rw"], "ml": ["Cr", "Rw", "sigma_v", "sigma_w_Ti"], "map": ["Cr", "Rw", "sigma_v"]}


def noisy_data(seed: int = 3, quantize: bool = True) -> Dataset:
    d = data2(noise=0.05, rng=np.random.default_rng(seed))
    y = d.y.copy()
    y[[7, 40, 41, 100]] = np.nan  # missing samples (never the first)
    m = np.round(d.m, 2) if quantize else d.m + 1e-4 * np.arange(d.n_samples)[:, None]
    return Dataset(d.t, d.u, m, y, d.input_names, d.flow_names, d.output_names)


@pytest.mark.parametrize("method", ["ls", "ml", "map"])
@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize("quantize", [True, False])
def test_compiled_cost_equals_the_python_objective_at_random_points(method, hold, quantize) -> None:
    data = noisy_data(quantize=quantize)
    assert (data.interval_groups is not None) == quantize  # both kernel variants are exercised
    spec = make_spec(NET2, FREE[method], fixed={"sigma_x0_Tw": 0.7})
    obj = Objective(NET2, data, spec, method, hold, likelihood_weight=0.3 if method == "map" else 1.0)
    problem = compiled_problem(obj)
    assert problem is not None
    rng = np.random.default_rng(11)
    lo, hi = spec.eta_lower, spec.eta_upper
    for _ in range(6):
        eta = lo + (hi - lo) * rng.uniform(0.3, 0.7, spec.n_free)
        assert compiled_cost(problem, eta) == pytest.approx(
            objective_reference_cost(obj, spec.to_theta(eta)), rel=1e-12
        )
        assert obj(eta) == pytest.approx(objective_reference_cost(obj, spec.to_theta(eta)), rel=1e-12)


@pytest.mark.parametrize("method", ["ml", "ls"])
def test_the_bound_value_kernel_takes_any_theta_and_problem(method) -> None:
    """``value_kernel`` calls its problem's specialization directly (no per-call typing of the
    named tuple) only for a contiguous float64 ``theta`` and that same problem; a strided or
    integer ``theta`` and another problem give the oracle's values through the dispatcher."""
    from rczone.kernels.problem import value_kernel

    data = noisy_data()
    spec = make_spec(NET2, FREE[method], fixed={"sigma_x0_Tw": 0.7})
    obj = Objective(NET2, data, spec, method)
    other = Objective(NET2, noisy_data(seed=4), spec, method)
    value = value_kernel(obj._packed)
    theta = np.asarray(spec.start, dtype=np.float64)
    want = objective_reference_cost(obj, theta)
    assert value(theta, obj._packed) == pytest.approx(want, rel=1e-12)
    strided = np.repeat(theta, 2)[::2]
    assert not strided.flags.c_contiguous
    assert value(strided, obj._packed) == pytest.approx(want, rel=1e-12)
    assert value(theta, other._packed) == pytest.approx(objective_reference_cost(other, theta), rel=1e-12)
    assert value(theta, other._packed) != pytest.approx(want, rel=1e-6)


def test_problems_the_compiled_path_cannot_take_go_the_general_way() -> None:
    d2 = noisy_data()
    # a tie that is a sum of parameters; a massless node
    summed = NET2.replace_parameters([Parameter("R2", "resistance", expr="Rw/2 + Rwin")])
    tie = Objective(summed, d2, make_spec(summed, ["Cr", "Rw"]), "ls")
    assert compiled_problem(tie) is None and tie.engine == "general"
    # but one state, free initial states and a missing first sample are compiled now
    one = Objective(NET1, data1(), make_spec(NET1, ["Cr", "R"]), "ls")
    x0 = Objective(NET2, d2, make_spec(NET2, ["Cr", "x0_Tw"], start={"x0_Tw": 20.0}), "ml")
    missing_first = Dataset(
        d2.t, d2.u, d2.m, np.r_[[[np.nan]], d2.y[1:]], d2.input_names, d2.flow_names, d2.output_names
    )
    first = Objective(NET2, missing_first, make_spec(NET2, ["Cr", "Rw"]), "ls")
    assert (one.engine, x0.engine, first.engine) == ("compiled", "rc2-fused", "rc2-fused")
    for obj in (one, x0, first):
        theta = obj.spec.start * 1.1
        assert obj(obj.spec.to_eta(theta)) == pytest.approx(objective_reference_cost(obj, theta), rel=1e-12)
    # and a chain of proportional ties is compiled
    chain = NET2.replace_parameters(
        [Parameter("Rh", "resistance", expr="Rw/2"), Parameter("R1", "resistance", expr="-(-Rh) * 1")]
    )
    obj = Objective(chain, d2, make_spec(chain, ["Cr", "Rw"]), "ls")
    problem = compiled_problem(obj)
    assert problem is not None
    eta = np.log([1e6, 0.02])
    assert compiled_cost(problem, eta) == pytest.approx(objective_reference_cost(obj, np.exp(eta)), rel=1e-12)


@pytest.mark.parametrize("method", ["ls", "ml", "map"])
def test_compiled_search_ends_where_scipy_ends(method, monkeypatch) -> None:
    data = noisy_data(seed=5)
    kw = {"options": {"correlation_time_s": 3000.0}} if method == "map" else {}
    compiled = fit(NET2, data, FREE[method], method=method, **kw)
    monkeypatch.setattr(compiled_module, "compiled_problem", lambda objective: None)  # the general engine
    python = fit(NET2, data, FREE[method], method=method, **kw)
    assert compiled.converged and python.converged
    for n in compiled.names:
        assert compiled.estimates[n] == pytest.approx(python.estimates[n], rel=2e-5)
    assert compiled.objective_value == pytest.approx(python.objective_value, rel=1e-10, abs=1e-10)
    # a few hundred evaluations, like SciPy's (rounding makes the paths differ slightly)
    assert abs(compiled.n_evals - python.n_evals) <= 0.2 * python.n_evals


def test_compiled_search_respects_the_budget_and_reports_it() -> None:
    data = noisy_data()
    spec = make_spec(NET2, FREE["ml"])
    obj = Objective(NET2, data, spec, "ml")
    out = minimize_from(obj, spec, spec.start, "nelder-mead", max_evals=40)
    assert not out.converged and "Maximum number of function evaluations" in out.message
    assert out.n_evals <= 42  # the budget, plus the start and the end value
    assert out.cost < obj(spec.to_eta(spec.start))  # it went downhill meanwhile


def test_compiled_nelder_mead_minimizes_and_stays_inside_the_bounds() -> None:
    # recover known parameters from noise-free data, starting a factor 3 away
    data = data2()
    spec = make_spec(NET2, ["Cr", "Rw"], start={"Cr": 8e5 * 3, "Rw": 0.01 / 3}, bounds={"Rw": (1e-3, 0.05)})
    obj = Objective(NET2, data, spec, "ls")
    problem = compiled_problem(obj)
    z0 = spec.to_z(spec.to_eta(spec.start))
    sim = z0 + np.vstack([np.zeros(2), 0.5 * np.eye(2)])
    scale = obj(spec.to_eta(spec.start))
    z, f, n, status = nelder_mead(sim, problem, scale, 1e-10, 1e-30, 4000)
    theta = spec.to_theta(spec.from_z(z))
    assert status == 0 and n < 4000
    np.testing.assert_allclose(theta, [8e5, 0.01], rtol=1e-6)
    assert f * scale < 1e-12 * scale


def _other_kind_network(resistor: str, capacity: str) -> RCNetwork:
    return RCNetwork(
        "other",
        nodes=[Node("Ti", capacity), Node("Tw", "Cw")],
        boundaries=["To"],
        resistors=[Resistor("Ti", "To", resistor), Resistor("Ti", "Tw", "R2")],
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        parameters=[
            Parameter("a", "other", 0.02),
            Parameter("b", "other", 1e6),
            Parameter("Cr", "capacitance", expr="b * 1"),
            Parameter("Cw", "capacitance", 5e6),
            Parameter("R1", "resistance", 0.02),
            Parameter("R2", "resistance", 0.01),
        ],
    )


@pytest.mark.parametrize(
    ("resistor", "capacity", "free", "bad"), [("a", "Cr", "a", -0.01), ("R1", "b", "b", -1e5)]
)
@pytest.mark.parametrize("method", ["ls", "ml"])
def test_element_values_that_can_turn_negative_stay_on_the_python_path(resistor, capacity, free, bad, method):
    # a resistor or capacity set by a parameter of kind "other" (not log-transformed): the
    # Python path returns inf where it is <= 0 (never an error mid-search), and the compiled
    # path, which checks only what it uses, refuses the problem
    net = _other_kind_network(resistor, capacity)
    t = np.arange(50) * 600.0
    u = np.column_stack([10 + np.sin(t / 3600), 100 + 0 * t])
    y = 15 + 0.01 * np.arange(50)[:, None]
    data = Dataset(t, u, np.zeros((50, 0)), y, net.input_names, (), net.outputs)
    obj = Objective(net, data, make_spec(net, [free]), method)
    assert compiled_problem(obj) is None
    assert obj(np.array([bad])) == objective_reference_cost(obj, np.array([bad])) == np.inf
    assert np.isfinite(obj(np.array([-bad])))


def test_a_tie_no_element_uses_is_still_checked() -> None:
    # Rx = Rw - 0.005 is used by no element but is a resistance that the Python path checks
    # (inf for Rw < 0.005): a problem the compiled cost could not reproduce is refused
    net = NET2.replace_parameters([Parameter("Rx", "resistance", expr="Rw - 0.005")])
    obj = Objective(net, noisy_data(), make_spec(net, ["Cr", "Rw"]), "ls")
    assert compiled_problem(obj) is None
    assert obj(np.log([8e5, 0.004])) == objective_reference_cost(obj, np.array([8e5, 0.004])) == np.inf
    negative = NET2.replace_parameters([Parameter("Rx", "resistance", expr="-Rw")])
    assert (
        compiled_problem(Objective(negative, noisy_data(), make_spec(negative, ["Cr", "Rw"]), "ls")) is None
    )
