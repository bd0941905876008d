"""Exact gradients of the identification costs against finite differences and the complex step.

:meth:`rczone.estimation.costs.Objective.value_and_gradient` (forward sensitivities through
the compiled discretization and filter, or simulation for least squares) is compared with

* central finite differences of the same cost (``h = 1e-6`` in eta), and
* the complex step [1]_ through an independent computation written here: the network's
  matrices assembled in complex arithmetic, the matrix-exponential discretization of
  :mod:`rczone.simulation.discretize`, and the NumPy twin of the filter
  (``tests/oracles.py``) or the NumPy simulation loop.
  The complex step has no subtraction, so it is exact to rounding.

Models are random RC networks: with no massless node the problem packs into arrays (the
``"compiled"`` gradient engine), with massless nodes it takes the ``"general"`` one (outputs
at massless nodes have a ``D`` term and parameter-dependent ``C``). The free parameters are a
random mix of resistances, capacities, noise levels (per output and per state) and initial
states.

References
----------
.. [1] J. R. R. A. Martins, P. Sturdza, J. J. Alonso, "The complex-step derivative
   approximation", ACM Trans. Math. Software 29(3), 2003.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rczone.estimation import Dataset, Objective, make_spec, noise_parameter_names
from rczone.estimation.engines import measured_states
from rczone.estimation.kalman import FilterProblem, stochastic_matrices
from rczone.network import BilinearStateSpace
from rczone.network.parameters import evaluate_ties
from rczone.simulation import simulate
from rczone.simulation.simulate import transition_matrices
from tests.netfactory import random_network
from tests.oracles import kalman_filter_reference, objective_reference_cost, propagate_reference

H_CS = 1e-30
SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def complex_state_space(net, base: dict) -> BilinearStateSpace:
    """The state space of complex base parameter values (ties evaluated in complex arithmetic)."""
    vals = evaluate_ties(net.parameters, base, net._tie_order)
    built = net._assemble(vals, complex)
    return BilinearStateSpace(
        built.A,
        built.N,
        built.B,
        built.M,
        built.C,
        built.D,
        net.state_names,
        net.input_names,
        net.flow_names,
        net.outputs,
        built.capacities.real,
    )


def complex_initial_state(ss: BilinearStateSpace, values: dict, data: Dataset) -> np.ndarray:
    """x0 values where given; else measured states at y0 and the rest at the steady state given them."""
    n = ss.n_states
    x = np.zeros(n, complex)
    names = [f"x0_{s}" for s in ss.state_names]
    if not all(nm in values for nm in names):
        A = ss.A + np.tensordot(data.m[0], ss.N, axes=1)
        B = ss.B + np.tensordot(data.m[0], ss.M, axes=1)
        meas = {
            i: j
            for i, j in measured_states(
                BilinearStateSpace(
                    *(np.real(a) for a in (ss.A, ss.N, ss.B, ss.M, ss.C, ss.D)),
                    ss.state_names,
                    ss.input_names,
                    ss.flow_names,
                    ss.output_names,
                    ss.capacities,
                )
            ).items()
            if math.isfinite(data.y[0, j])
        }
        for i, j in meas.items():
            x[i] = data.y[0, j]
        free = [i for i in range(n) if i not in meas]
        fixed = sorted(meas)
        if free:
            rhs = -(B[free] @ data.u[0]) - A[np.ix_(free, fixed)] @ x[fixed]
            x[free] = np.linalg.solve(A[np.ix_(free, free)], rhs)
    for i, nm in enumerate(names):
        if nm in values:
            x[i] = values[nm]
    return x


def complex_cost(obj: Objective, values: dict) -> complex:
    """The objective's cost at (complex) parameter values, by the plain computation of the module notes."""
    net, data = obj.network, obj.data
    base = {k: values.get(k, v) for k, v in net.values().items() if not net.parameters[k].is_tied}
    ss = complex_state_space(net, base)
    x0 = complex_initial_state(ss, values, data)
    if obj.method == "ls":
        Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, obj.hold)
        x = propagate_reference(Phi, G0, G1, which, data.u, x0)
        e = data.y - (x @ ss.C.T + data.u @ ss.D.T)
        ok = np.isfinite(e.real[:-1]) & np.isfinite(e.real[1:])
        seg = 0.5 * (np.where(ok, e[:-1], 0) ** 2 + np.where(ok, e[1:], 0) ** 2) * np.diff(data.t)[:, None]
        return seg.sum()
    sw = np.array([values[f"sigma_w_{s}"] for s in ss.state_names])
    sx = np.array([values[f"sigma_x0_{s}"] for s in ss.state_names])
    sv = np.array([values[n] for n in noise_parameter_names(net)[: len(net.outputs)]])
    Phi, G0, G1, Qd, which = stochastic_matrices(ss, data.t, data.m, np.diag(sw**2), obj.hold)
    nll = kalman_filter_reference(
        FilterProblem(Phi, G0, G1, Qd, which, data.u, data.y, x0, np.diag(sx**2), ss.C, ss.D, np.diag(sv**2))
    ).nll
    if obj.method == "map":
        spec = obj.spec
        pen = 0.0
        for name, kind, c in zip(spec.names, spec.kinds, spec.construction):
            if kind in ("resistance", "capacitance") and np.isfinite(c):
                pen = pen + 0.5 * ((np.log(values[name]) - np.log(c)) / obj.prior_spread) ** 2
        nll = obj.likelihood_weight * nll + pen
    return nll


def complex_step_gradient(obj: Objective, eta: np.ndarray) -> np.ndarray:
    """d cost / d eta by the complex step: theta_j = exp(eta_j + i h) for log parameters."""
    spec = obj.spec
    theta = spec.to_theta(eta)
    g = np.empty(spec.n_free)
    for j, name in enumerate(spec.names):
        values = {k: complex(v) for k, v in spec.values(theta).items()}
        values[name] = (
            theta[j] * complex(math.cos(H_CS), math.sin(H_CS)) if spec.log[j] else theta[j] + 1j * H_CS
        )
        g[j] = complex_cost(obj, values).imag / H_CS
    return g


def central_difference(obj: Objective, eta: np.ndarray, h: float = 1e-4) -> np.ndarray:
    """Central differences; ``h`` balances the O(h^2) truncation against the cost's rounding
    (up to about 1e-11 relative on these problems), which ``h = 1e-6`` amplified 100-fold."""
    g = np.empty(eta.size)
    for j in range(eta.size):
        e = np.zeros(eta.size)
        e[j] = h
        g[j] = (obj(eta + e) - obj(eta - e)) / (2 * h)
    return g


def problem(
    seed: int, n_cap: int, n_massless: int, n_outputs: int, method: str, hold: str, n_flows: int = 1
) -> tuple:
    rng = np.random.default_rng(seed)
    net = random_network(rng, n_cap, n_massless, 2, min(n_outputs, n_cap + n_massless), n_flows)
    ss = net.state_space()
    N = 40
    t = np.cumsum(np.r_[0.0, rng.choice([300.0, 300.0, 900.0], N - 1)])
    m = np.round(rng.uniform(0, 0.3, (N, n_flows)), 1)
    u = 20 + 3 * rng.standard_normal((N, ss.n_inputs))
    y = simulate(ss, t, u, m).y + 0.05 * rng.standard_normal((N, len(net.outputs)))
    y[rng.integers(1, N, 4), rng.integers(0, len(net.outputs), 4)] = np.nan
    data = Dataset(t, u, m, y, net.input_names, net.flow_names, net.outputs)
    network = list(net.free_parameter_names)
    noise = [n for n in noise_parameter_names(net) if not n.startswith("x0_")] if method != "ls" else []
    pool = network + noise
    free = [str(x) for x in rng.choice(pool, min(len(pool), rng.integers(2, 7)), replace=False)]
    x0 = f"x0_{net.state_names[-1]}"
    if rng.random() < 0.5:
        free.append(x0)
    spec = make_spec(net, free, start={x0: 20.0} if x0 in free else None)
    obj = Objective(net, data, spec, method, hold, likelihood_weight=0.4 if method == "map" else 1.0)
    eta = spec.to_eta(spec.start) + rng.uniform(-0.3, 0.3, spec.n_free)
    return obj, eta


@SETTINGS
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 4),
    st.integers(0, 1),
    st.integers(1, 3),
    st.sampled_from(["ls", "ml", "map"]),
    st.sampled_from(["zoh", "foh"]),
)
def test_gradient_equals_complex_step_and_finite_differences(
    seed, n_cap, n_massless, n_outputs, method, hold
):
    obj, eta = problem(seed, n_cap, n_massless, n_outputs, method, hold)
    assert obj.gradient_engine == ("general" if n_massless else "compiled")
    value, grad = obj.value_and_gradient(eta)
    # the value path may discretize by the eigen-decomposition, the gradient path by expm: exact both
    assert abs(value - obj(eta)) <= 1e-10 * abs(value)
    cs = complex_step_gradient(obj, eta)
    scale = max(np.abs(cs).max(), 1e-12)
    np.testing.assert_allclose(grad, cs, rtol=0, atol=1e-7 * scale)
    fd = central_difference(obj, eta)
    # truncation O(h^2) plus the cost's own rounding divided by h
    np.testing.assert_allclose(grad, fd, rtol=0, atol=1e-5 * scale + 1e-7 * abs(value))


def test_the_complex_step_oracle_is_the_reference_cost():
    # the independent computation above is the NumPy reference engine at real values
    obj, eta = problem(3, 3, 1, 2, "ml", "foh")
    theta = obj.spec.to_theta(eta)
    values = {k: complex(v) for k, v in obj.spec.values(theta).items()}
    ref = objective_reference_cost(obj, theta)
    assert abs(complex_cost(obj, values).real - ref) <= 1e-10 * abs(ref)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1), st.integers(2, 4), st.integers(0, 1), st.sampled_from(["zoh", "foh"]))
def test_gradient_with_two_flows_equals_complex_step(seed, n_cap, n_massless, hold):
    """Two supply-air flows (many distinct ``(dt, m1, m2)``): the spectral derivatives of every interval."""
    obj, eta = problem(seed, n_cap, n_massless, 2, "ml", hold, n_flows=2)
    assert obj.data.intervals[0].shape[0] > 10
    _, grad = obj.value_and_gradient(eta)
    cs = complex_step_gradient(obj, eta)
    np.testing.assert_allclose(grad, cs, rtol=0, atol=1e-7 * max(np.abs(cs).max(), 1e-12))
