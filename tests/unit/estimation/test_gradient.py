"""The central-difference gradient of J_ML in eta against a higher-accuracy reference.

Reference: the 5-point (4th-order) stencil at a 10x larger step, whose truncation error
is O(h^4); both must agree to 1e-6 relative to the gradient norm. And an analytic case.
"""

from __future__ import annotations

import numpy as np
import pytest

from rczone.estimation import Objective, make_spec
from rczone.estimation.optimize import central_gradient

from .nets import NET2, data2


def five_point(f, x: np.ndarray, h: float) -> np.ndarray:
    g = np.empty_like(x)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h * max(1.0, abs(x[i]))
        g[i] = (f(x - 2 * e) - 8 * f(x - e) + 8 * f(x + e) - f(x + 2 * e)) / (12 * e[i])
    return g


def test_central_gradient_exact_on_a_quadratic() -> None:
    Q = np.array([[3.0, 1.0], [1.0, 2.0]])

    def f(x: np.ndarray) -> float:
        return float(0.5 * x @ Q @ x + x[0])

    x = np.array([0.3, -1.2])
    g, n = central_gradient(f, x)
    np.testing.assert_allclose(g, Q @ x + [1.0, 0.0], rtol=1e-9)
    assert n == 4


@pytest.mark.parametrize("method", ["ml", "ls"])
def test_central_gradient_matches_fourth_order_reference(method: str) -> None:
    data = data2(noise=0.05, rng=np.random.default_rng(7))
    free = ["Cr", "Rw", "Rwin"] + (["sigma_v", "sigma_w_Ti", "x0_Tw"] if method == "ml" else [])
    spec = make_spec(NET2, free, start={"x0_Tw": 21.0} if method == "ml" else None)
    obj = Objective(NET2, data, spec, method)
    eta = spec.to_eta(spec.start) + 0.1  # away from any optimum
    g, _ = central_gradient(obj, eta)
    ref = five_point(obj, eta, 1e-3)
    np.testing.assert_allclose(g, ref, rtol=0, atol=1e-6 * np.linalg.norm(ref))


@pytest.mark.parametrize(("method", "hold"), [("ml", "zoh"), ("ml", "foh"), ("map", "zoh")])
def test_adjoint_gradient_of_the_two_state_likelihood_equals_forward_sensitivities_and_differences(
    method: str, hold: str
) -> None:
    """The backward pass (rczone.kernels.adjoint) against the forward sensitivities and 5-point differences.

    Data with two flow levels and missing samples; every kind of parameter free (R, C, noise,
    initial state and its spread).
    """
    from rczone.estimation import Dataset
    from rczone.kernels.problem import value_and_gradient

    data = data2(noise=0.05, rng=np.random.default_rng(24))
    y = data.y.copy()
    y[[0, 17, 18, 90]] = np.nan
    data = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v", "sigma_w_Ti", "sigma_w_Tw", "x0_Tw", "sigma_x0_Ti"]
    spec = make_spec(NET2, free, start={"x0_Tw": 21.0, "sigma_w_Tw": 1e-4})
    obj = Objective(NET2, data, spec, method, hold)
    assert obj.engine == "rc2-fused" and obj._adjoint
    rng = np.random.default_rng(5)
    for _ in range(2):
        eta = spec.to_eta(spec.start) + rng.uniform(-0.3, 0.3, spec.n_free)
        j, g = obj.value_and_gradient(eta)
        j_fwd, g_fwd, _ = value_and_gradient(np.asarray(spec.to_theta(eta), dtype=float), obj.compiled)
        g_fwd = g_fwd * spec.jacobian(eta)
        assert j == pytest.approx(obj(eta), rel=1e-12)
        assert j == pytest.approx(j_fwd, rel=1e-12)
        np.testing.assert_allclose(g, g_fwd, rtol=0, atol=1e-9 * np.linalg.norm(g_fwd))
        ref = five_point(obj, eta, 1e-3)
        np.testing.assert_allclose(g, ref, rtol=0, atol=1e-6 * np.linalg.norm(ref))


@pytest.mark.parametrize("fused", [True, False])
def test_the_bound_gradient_kernel_takes_any_theta_and_problem(fused: bool) -> None:
    """``gradient_kernel`` calls its problem's specialization directly only for a contiguous float64
    ``theta`` and that same problem; a strided ``theta`` and another problem go through the
    dispatcher. Every answer is checked against the forward sensitivities of that problem."""
    from rczone.kernels.adjoint import gradient_kernel
    from rczone.kernels.problem import _SPECIALIZATIONS, value_and_gradient

    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v", "sigma_w_Ti"]
    spec = make_spec(NET2, free)
    engine = "rc2-fused" if fused else "compiled"
    objs = [
        Objective(NET2, data2(noise=0.05, rng=np.random.default_rng(s)), spec, "ml", engine=engine)
        for s in (3, 4)
    ]
    prob, other = objs[0]._packed, objs[1]._packed
    gradient = gradient_kernel(prob, fused=fused)
    theta = np.asarray(spec.start, dtype=np.float64) * np.linspace(0.8, 1.2, spec.n_free)
    strided = np.repeat(theta, 2)[::2]
    assert not strided.flags.c_contiguous
    for th, pr in ((theta, prob), (strided, prob), (theta, other)):
        j, g = gradient(th, pr)
        j_fwd, g_fwd, _ = value_and_gradient(np.ascontiguousarray(th), pr)
        assert j == pytest.approx(j_fwd, rel=1e-10)
        np.testing.assert_allclose(g, g_fwd, rtol=0, atol=1e-8 * np.linalg.norm(g_fwd))
    assert gradient(theta, other)[0] != pytest.approx(gradient(theta, prob)[0], rel=1e-6)
    # a problem of the same structure finds the specialization again (no typing in Python)
    known = len(_SPECIALIZATIONS)
    j, g = gradient_kernel(other, fused=fused)(theta, other)
    assert len(_SPECIALIZATIONS) == known
    j_fwd, g_fwd, _ = value_and_gradient(theta, other)
    assert j == pytest.approx(j_fwd, rel=1e-10)
    np.testing.assert_allclose(g, g_fwd, rtol=0, atol=1e-8 * np.linalg.norm(g_fwd))


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_the_rc_discretization_derivatives_equal_the_matrix_exponentials(hold: str) -> None:
    """The spectral route the adjoint compiles alone (rc_interval_derivatives) against the other
    route of interval_derivatives: block matrix exponentials and their Frechet derivatives."""
    from rczone.kernels.arrays import Discretization
    from rczone.kernels.discretize import interval_derivatives, rc_interval_derivatives
    from rczone.kernels.problem import LS, assembled

    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v", "sigma_w_Ti", "sigma_w_Tw"]
    spec = make_spec(NET2, free, start={"sigma_w_Tw": 1e-4})
    obj = Objective(NET2, data2(), spec, "ml", hold)
    prob = obj.compiled
    theta = np.asarray(spec.start, dtype=float)
    mod, der, ok = assembled(theta, prob, theta.shape[0])
    assert ok and prob.data.keys.shape[0] > 1
    how = Discretization(prob.data.keys, np.sqrt(mod.cap), hold == "foh", prob.kind != LS)
    ours = rc_interval_derivatives(mod, der, how)
    expm = interval_derivatives(mod, der, how._replace(scale=np.empty(0)))
    for a, b in zip((*ours[0], *ours[1]), (*expm[0], *expm[1])):
        np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-9 * np.abs(b).max())


@pytest.mark.parametrize(("method", "hold"), [("ml", "zoh"), ("map", "foh")])
def test_fit_rmse_from_the_adjoint_filter_equals_the_general_filters(method: str, hold: str) -> None:
    """A 2-state likelihood fit takes its one-step RMSE from the adjoint kernel's forward pass: the same
    errors as the general compiled filter over the discrete matrices (missing samples, estimated x0)."""
    from rczone.estimation import Dataset, fit
    from rczone.estimation.minimize import rmse_of

    data = data2(noise=0.05, rng=np.random.default_rng(3))
    y = data.y.copy()
    y[[0, 17, 18, 90]] = np.nan
    data = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    free = ["Cr", "Cw", "Rw", "Rwin", "sigma_v", "sigma_w_Ti", "x0_Tw"]
    res = fit(
        NET2, data, free, method=method, hold=hold, n_starts=1, start={"x0_Tw": 21.0}, uncertainty=False
    )
    assert res.engine == "rc2-fused"
    general = rmse_of(NET2, {**res.estimates, **res.fixed}, data, method, hold)
    assert res.rmse_K == pytest.approx(general, rel=1e-10)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_least_squares_fit_rmse_from_the_fused_kernel_equals_the_simulations(hold: str) -> None:
    """A 2-state least-squares fit takes its open-loop RMSE from the fused value kernel's errors: the
    same as the general simulation's (missing samples, estimated x0)."""
    from rczone.estimation import Dataset, fit
    from rczone.estimation.minimize import rmse_of

    data = data2(noise=0.05, rng=np.random.default_rng(4))
    y = data.y.copy()
    y[[0, 17, 18, 90]] = np.nan
    data = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    free = ["Cr", "Cw", "Rw", "Rwin", "x0_Tw"]
    res = fit(NET2, data, free, method="ls", hold=hold, n_starts=1, start={"x0_Tw": 21.0}, uncertainty=False)
    assert res.engine == "rc2-fused" and res.optimizer == "gauss-newton"
    general = rmse_of(NET2, {**res.estimates, **res.fixed}, data, "ls", hold)
    assert res.rmse_K == pytest.approx(general, rel=1e-10)
