from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import make_spec
from rczone.estimation.optimize import minimize_from

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
