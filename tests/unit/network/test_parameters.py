import math

import pytest

from rczone.errors import ParameterError
from rczone.network.parameters import (
    Parameter,
    check_declarations,
    expression_names,
    proportional_base,
    resolve,
)


def _params(*ps):
    return {p.name: p for p in ps}


def test_tied_parameters_follow_their_base():
    ps = _params(
        Parameter("Rw", "resistance", 0.01),
        Parameter("R1", "resistance", expr="Rw/2"),
        Parameter("R2", "resistance", expr="R1 * 1"),
    )
    vals = resolve(ps, {"Rw": 0.03})
    assert vals == {"Rw": 0.03, "R1": 0.015, "R2": 0.015}
    assert resolve(ps)["R2"] == 0.005


def test_resolve_does_not_mutate_inputs():
    ps = _params(Parameter("Rw", "resistance", 0.01))
    theta = {"Rw": 0.5}
    resolve(ps, theta)
    assert theta == {"Rw": 0.5} and ps["Rw"].value == 0.01


def test_expression_names():
    assert expression_names("(a + b) / 2 - a**2") == ("a", "b")


@pytest.mark.parametrize(
    ("build", "theta", "match"),
    [
        (lambda: _params(Parameter("Rw", "resistance", 0.01)), {"Rx": 1.0}, r"unknown parameter 'Rx'.*'Rw'"),
        (lambda: _params(Parameter("Rw", "resistance", 0.01)), {"Rw": -1.0}, r"'Rw' = -1.*must be > 0"),
        (lambda: _params(Parameter("Cr", "capacitance", 1.0)), {"Cr": 0.0}, r"must be > 0"),
        (lambda: _params(Parameter("Rw", "resistance", 0.01)), {"Rw": math.nan}, r"not finite"),
        (lambda: _params(Parameter("Rw", "resistance")), {}, r"'Rw' has no value"),
        (
            lambda: _params(Parameter("Rw", "resistance", 1.0), Parameter("R1", "resistance", expr="Rw/2")),
            {"R1": 1.0},
            r"'R1' is tied",
        ),
        (
            lambda: _params(Parameter("a", "resistance", 1.0), Parameter("R1", "resistance", expr="a - 2")),
            {},
            r"'R1' = -1.*must be > 0",
        ),
        (
            lambda: _params(Parameter("a", "other", 0.0), Parameter("g", "other", expr="1/a")),
            {},
            r"divides by zero",
        ),
    ],
)
def test_bad_values(build, theta, match):
    with pytest.raises(ParameterError, match=match):
        resolve(build(), theta)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Parameter("R w", "resistance", 1.0), "not a valid identifier"),
        (lambda: Parameter("Rw", "resistor", 1.0), "kind 'resistor'"),
        (lambda: Parameter("Rw", "resistance", 1.0, expr="a"), "both a value and an expression"),
        (lambda: Parameter("Rw", "resistance", expr="__import__('os')"), "only numbers"),
        (lambda: Parameter("Rw", "resistance", expr="Rx +"), "invalid parameter expression"),
        (lambda: Parameter("Rw", "resistance", expr="'a' * 2"), "non-number"),
        (lambda: Parameter("Rw", "resistance", -0.1), "must be > 0"),
    ],
)
def test_bad_declarations(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_cycles_and_unknown_names_in_ties():
    with pytest.raises(ParameterError, match="cycle"):
        check_declarations(_params(Parameter("a", expr="b"), Parameter("b", expr="a")))
    with pytest.raises(ParameterError, match=r"unknown parameter 'Rww'.*'Rw'"):
        check_declarations(_params(Parameter("Rw", "resistance", 1.0), Parameter("R1", expr="Rww/2")))


def test_proportional_base_follows_ties_and_refuses_anything_nonlinear() -> None:
    params = {
        p.name: p
        for p in [
            Parameter("Rw", "resistance", 0.01),
            Parameter("Ra", "resistance", 0.02),
            Parameter("R1", "resistance", expr="Rw/2"),
            Parameter("R2", "resistance", expr="3 * R1 / 4"),
            Parameter("R3", "resistance", expr="-(-R2)"),
            Parameter("R4", "resistance", expr="2.5 * 2"),
            Parameter("S", "resistance", expr="Rw + Ra"),
            Parameter("P", "resistance", expr="Rw * Ra"),
            Parameter("Q", "resistance", expr="Rw ** 2"),
            Parameter("D", "resistance", expr="2 / Rw"),
            Parameter("Z", "resistance", expr="Rw / (1 - 1)"),
            Parameter("T", "resistance", expr="S / 2"),
        ]
    }
    assert proportional_base(params, "Rw") == (1.0, "Rw")
    assert proportional_base(params, "R1") == (0.5, "Rw")
    assert proportional_base(params, "R2") == pytest.approx((0.375, "Rw"))
    assert proportional_base(params, "R3") == pytest.approx((0.375, "Rw"))
    assert proportional_base(params, "R4") == (5.0, None)
    for name in ("S", "P", "Q", "D", "Z", "T"):
        assert proportional_base(params, name) is None
