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
