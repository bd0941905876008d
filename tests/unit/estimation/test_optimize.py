from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import make_spec
from rczone.estimation.optimize import Remembered, minimize_from, remembered

from .nets import NET2


@pytest.mark.parametrize("optimizer", ["nelder-mead", "powell", "lbfgs"])
def test_optimizers_find_a_known_minimum_inside_bounds(optimizer: str) -> None:
    spec = make_spec(NET2, ["Cr", "Rw"], bounds={"Cr": (1e5, 1e7), "Rw": (1e-3, 1.0)})
    target = np.log([2.5e6, 0.02])

    def cost(eta: np.ndarray) -> float:
        d = eta - target
        return float(d[0] ** 2 + 3 * d[1] ** 2 + d[0] * d[1] + 5.0)

    out = minimize_from(cost, spec, spec.start, optimizer)
    assert out.converged
    np.testing.assert_allclose(out.end, [2.5e6, 0.02], rtol=1e-6)
    assert out.cost == pytest.approx(5.0)
    np.testing.assert_array_equal(out.start, spec.start)


def test_unknown_optimizer_and_infinite_start() -> None:
    spec = make_spec(NET2, ["Cr"])
    with pytest.raises(ParameterError, match="optimizer must be one of"):
        minimize_from(lambda e: 0.0, spec, spec.start, "newton")
    with pytest.raises(ParameterError, match="not finite at the start"):
        minimize_from(lambda e: float("inf"), spec, spec.start)


class _Quadratic:
    """A cost with its exact gradient that counts how often each is computed."""

    def __init__(self) -> None:
        self.target = np.log([2.5e6, 0.02])
        self.calls = 0

    def __call__(self, eta: np.ndarray) -> float:
        d = eta - self.target
        return float(d[0] ** 2 + 3 * d[1] ** 2 + d[0] * d[1] + 5.0)

    def value_and_gradient(self, eta: np.ndarray) -> tuple[float, np.ndarray]:
        self.calls += 1
        d = eta - self.target
        return self(eta), np.array([2 * d[0] + d[1], 6 * d[1] + d[0]])


def test_a_gradient_search_computes_each_point_once() -> None:
    spec = make_spec(NET2, ["Cr", "Rw"], bounds={"Cr": (1e5, 1e7), "Rw": (1e-3, 1.0)})
    seen: list[bytes] = []

    class Recording(_Quadratic):
        def value_and_gradient(self, eta):
            seen.append(np.asarray(eta, dtype=float).tobytes())
            return super().value_and_gradient(eta)

    out = minimize_from(Recording(), spec, spec.start, "lbfgs")
    # the start is asked for three times (its value, the curvature scaling, the end's cost)
    assert len(seen) == len(set(seen))
    np.testing.assert_allclose(out.end, [2.5e6, 0.02], rtol=1e-6)


def test_remembered_keeps_the_latest_points_and_hands_out_copies() -> None:
    q = _Quadratic()
    memo = Remembered(q, size=2)
    a, b, c = np.zeros(2), np.ones(2), np.full(2, 2.0)
    fa, ga = memo.value_and_gradient(a)
    assert memo.value_and_gradient(a)[0] == fa and q.calls == 1
    ga[:] = 99.0  # the caller's copy: the remembered gradient is untouched
    np.testing.assert_array_equal(memo.value_and_gradient(a)[1], q.value_and_gradient(a)[1])
    q.calls = 0
    memo.value_and_gradient(b)
    memo.value_and_gradient(c)  # a is the oldest of three: forgotten
    memo.value_and_gradient(a)
    assert q.calls == 3
    memo.value_and_gradient(c)
    assert q.calls == 3
    assert memo(a) == q(a) and memo.target is q.target  # the rest is the cost's
    value_only = q.__call__  # no gradient: nothing to remember
    assert remembered(memo) is memo and remembered(value_only) is value_only


@pytest.mark.parametrize(
    ("start", "maxfun", "ftol"),
    [
        ((-1.2, 1.0, 0.5, 2.0), 15000, 1e-12),
        ((-1.2, 1.0, 0.5, 2.0), 12, 1e-12),
        ((0.3, 0.3, 0.3, 0.3), 200, 1e-15),
    ],
)
def test_the_lbfgsb_loop_takes_scipys_steps(start, maxfun: int, ftol: float, monkeypatch) -> None:
    """``optimize.lbfgsb`` against ``scipy.optimize.minimize(method="L-BFGS-B")`` on a 4-dimensional
    Rosenbrock function whose box holds the first coordinate off the global minimum (an active bound)
    or that ends in its local minimum:
    the same end point bit for bit, evaluations, message and verdict, also when stopped by ``maxfun``."""
    from scipy.optimize import minimize

    from rczone.estimation import optimize
    from rczone.estimation.optimize import lbfgsb

    def fun(x: np.ndarray) -> tuple[float, np.ndarray]:
        a, b = x[:-1], x[1:]
        f = float(np.sum(100.0 * (b - a**2) ** 2 + (1.0 - a) ** 2))
        g = np.zeros_like(x)
        g[:-1] += -400.0 * a * (b - a**2) - 2.0 * (1.0 - a)
        g[1:] += 200.0 * (b - a**2)
        return f, g

    lo, hi = np.array([-2.0, -2.0, -2.0, -2.0]), np.array([0.8, 2.0, 2.0, 2.0])
    opts = {"maxfun": maxfun, "ftol": ftol, "gtol": 1e-9, "maxiter": 15000}
    want = minimize(fun, np.array(start), jac=True, method="L-BFGS-B", bounds=list(zip(lo, hi)), options=opts)
    got = lbfgsb(fun, np.array(start), lo, hi, **opts)
    np.testing.assert_array_equal(got.x, want.x)
    assert (got.fun, got.nfev, got.success, got.message) == (want.fun, want.nfev, want.success, want.message)
    # a SciPy whose setulb lbfgsb does not know: minimize itself, the same answer
    monkeypatch.setattr(optimize, "_setulb", lambda: None)
    again = lbfgsb(fun, np.array(start), lo, hi, **opts)
    np.testing.assert_array_equal(again.x, want.x)
    assert (again.fun, again.nfev, again.success, again.message) == (
        got.fun,
        got.nfev,
        got.success,
        got.message,
    )
    if ftol == 1e-15:  # from there it goes to the bound, not to the local minimum near x0 = -0.78
        assert got.success and got.x[0] == 0.8


def test_the_decrement_is_what_a_diagonal_quadratic_has_left_to_fall() -> None:
    from rczone.estimation.optimize import decrement

    c = np.array([2.0, 6.0, 0.5])  # the curvature of J = 5 + sum(c (eta - t)^2 / 2)
    t = np.array([0.3, -1.0, 2.0])
    eta = np.array([1.0, 0.5, -0.5])
    size = 7.0  # J at the search's start
    g = c * (eta - t)  # dJ/deta
    left = float(np.sum(c * (eta - t) ** 2) / 2)  # J(eta) - min J
    # the phase's variables xi = eta sqrt(c) and cost J / size, as _lbfgs scales them
    g_xi = g / np.sqrt(c) / size
    lo, hi = np.full(3, -10.0), np.full(3, 10.0)
    assert decrement(g_xi, eta * np.sqrt(c), lo, hi, size) * size == pytest.approx(left, rel=1e-12)
    # a component pushing out of the box at its bound cannot be followed: it is not counted
    at = eta * np.sqrt(c)
    lo_at = lo.copy()
    lo_at[1] = at[1]  # g_xi[1] > 0: the cost falls towards the lower bound the point sits on
    assert g_xi[1] > 0
    want = (left - c[1] * (eta[1] - t[1]) ** 2 / 2) / size
    assert decrement(g_xi, at, lo_at, hi, size) == pytest.approx(want, rel=1e-12)
    # pulling inside from a bound, it is
    assert decrement(-g_xi, at, lo_at, hi, size) * size == pytest.approx(left, rel=1e-12)


class _Curved(_Quadratic):
    """The quadratic with the diagonal curvature an Objective offers, to scale L-BFGS's phases."""

    def curvature(self, eta: np.ndarray) -> np.ndarray:
        return np.array([2.0, 6.0])


def test_a_false_convergence_of_lbfgsb_is_not_taken(monkeypatch) -> None:
    """L-BFGS-B can stop on its relative-reduction test with the gradient far from zero (seen on
    the five-zone floor: a restart 900 in -log L above its optimum); such an end starts a new phase."""
    import rczone.estimation.optimize as optimize

    real = optimize.lbfgsb
    calls: list[str] = []

    def lazy_then_real(fun, x0, lower, upper, **kw):
        if not calls:  # the first phase stops at once, claiming convergence
            calls.append("false")
            return optimize.LbfgsbResult(x0, fun(x0)[0], 1, True, "CONVERGENCE: REL_REDUCTION_OF_F")
        calls.append("real")
        return real(fun, x0, lower, upper, **kw)

    monkeypatch.setattr(optimize, "lbfgsb", lazy_then_real)
    spec = make_spec(NET2, ["Cr", "Rw"], bounds={"Cr": (1e5, 1e7), "Rw": (1e-3, 1.0)})
    out = minimize_from(_Curved(), spec, spec.start, "lbfgs")
    assert calls[0] == "false" and "real" in calls
    assert out.converged
    np.testing.assert_allclose(out.end, [2.5e6, 0.02], rtol=1e-6)

    # claims that never reach a minimum end as not converged, and say why
    monkeypatch.setattr(
        optimize,
        "lbfgsb",
        lambda fun, x0, lower, upper, **kw: optimize.LbfgsbResult(x0, fun(x0)[0], 1, True, "CONVERGENCE: X"),
    )
    out = minimize_from(_Curved(), spec, spec.start, "lbfgs")
    assert not out.converged
    assert "far from zero" in out.message
    # at a true minimum the same claim is taken
    out = minimize_from(_Curved(), spec, np.array([2.5e6, 0.02]), "lbfgs")
    assert out.converged
