"""Ties as affine maps of base parameters (what the compiled costs hold instead of an expression).

Each affine tie is checked against the expression's own evaluation (:func:`resolve`) at random
base values: ``constant + sum k * base`` must reproduce it, so the coefficients cannot be right
by construction of the test.
"""

from __future__ import annotations

import numpy as np
import pytest

from rczone.network.parameters import AffineTie, Parameter, affine_tie, resolve

BASES = [Parameter("s1", "gain", 0.3), Parameter("s2", "gain", 0.2), Parameter("Rw", "resistance", 0.01)]
AFFINE = {
    "last": "1 - s1 - s2",
    "chain": "2 * last / 4 + s1",  # through another tie, with a product and a quotient by numbers
    "signs": "-(s2 - 3) + -s1 * 0.5",
    "cancel": "s1 - s1 + 2",  # a base that drops out
    "number": "2.5 * 2",
}
NOT_AFFINE = {"product": "s1 * s2", "power": "s1 ** 2", "inverse": "1 / s1", "zero": "s1 / (1 - 1)"}


def _params(ties: dict[str, str] | None = None) -> dict[str, Parameter]:
    ties = {**AFFINE, **NOT_AFFINE} if ties is None else ties
    return {p.name: p for p in BASES + [Parameter(n, "gain", expr=e) for n, e in ties.items()]}


def test_an_affine_tie_reproduces_its_expression_at_random_values() -> None:
    params = _params(AFFINE)
    rng = np.random.default_rng(2)
    for _ in range(5):
        base = {"s1": rng.uniform(-2, 2), "s2": rng.uniform(-2, 2), "Rw": rng.uniform(0.01, 1)}
        values = resolve(params, base)
        for name in AFFINE:
            tie = affine_tie(params, name)
            assert tie is not None, name
            assert tie.constant + sum(k * base[b] for b, k in tie.terms) == pytest.approx(
                values[name], rel=1e-12
            )


def test_the_terms_name_each_base_once_and_drop_zeros() -> None:
    params = _params()
    assert affine_tie(params, "last") == AffineTie(1.0, (("s1", -1.0), ("s2", -1.0)))
    assert affine_tie(params, "cancel") == AffineTie(2.0, ())
    assert affine_tie(params, "number") == AffineTie(5.0, ())
    assert affine_tie(params, "s1") == AffineTie(0.0, (("s1", 1.0),))


@pytest.mark.parametrize("name", sorted(NOT_AFFINE))
def test_anything_but_an_affine_map_is_none(name) -> None:
    assert affine_tie(_params(), name) is None


def test_an_overflowing_coefficient_is_none() -> None:
    params = {p.name: p for p in [BASES[0], Parameter("big", "gain", expr="1e300 * 1e300 * s1")]}
    assert affine_tie(params, "big") is None
