from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import make_spec
from rczone.estimation.optimize import latin_hypercube_starts, minimize_from

from .nets import NET2


def test_latin_hypercube_starts_are_stratified_inside_the_box_and_reproducible() -> None:
    spec = make_spec(NET2, ["Cr", "Rw", "g"], bounds={"Rw": (1e-3, 0.05)})
    a = latin_hypercube_starts(spec, 9, np.random.default_rng(5), spread=10.0)
    b = latin_hypercube_starts(spec, 9, np.random.default_rng(5), spread=10.0)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a[0], spec.start)
    cr = a[1:, 0]
    assert np.all((cr > 8e4) & (cr < 8e6))  # factor 10 around construction, in log space
    rw = a[1:, 1]
    assert np.all((rw > 1e-3) & (rw < 0.05))  # clipped box: bounds are tighter than x10
    # one start per stratum of log(Cr) (Latin hypercube)
    strata = np.floor((np.log(cr) - np.log(8e4)) / (np.log(8e6) - np.log(8e4)) * 8).astype(int)
    assert sorted(strata) == list(range(8))


@pytest.mark.parametrize(
    ("n", "spread", "match"), [(0, 10.0, "n_starts must be >= 1"), (3, 1.0, "spread must be > 1")]
)
def test_bad_multistart_arguments(n: int, spread: float, match: str) -> None:
    spec = make_spec(NET2, ["Cr"])
    with pytest.raises(ParameterError, match=match):
        latin_hypercube_starts(spec, n, np.random.default_rng(0), spread)


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
