"""Nesting of RC models detected from their networks, and checked by simulating both models."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rczone.models import load_model
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from rczone.selection.compare import chi_bar_sf
from rczone.selection.nesting import nesting, realize

FAMILY = [
    "Ti",
    "Ti+heater",
    "Ti+heater+solar",
    "TiTe+heater",
    "TiTe+heater+solar",
    "TiTh",
    "TiTeTh",
    "TiTm+heater",
    "TiTe",
]

# (simple, rich): restriction and degrees of freedom, worked out by hand from the networks
NESTED = {
    ("Ti+heater", "TiTe+heater"): ("Ce -> 0", 2),  # envelope massless: Ria = Rie + Rea
    ("Ti+heater", "TiTh"): ("Ch -> 0", 2),  # heater massless: all its power into Ti
    ("Ti+heater", "TiTm+heater"): ("Cm -> 0", 2),  # internal mass massless: a dead end
    ("Ti+heater", "Ti+heater+solar"): ("Aw = 0", 1),  # no aperture, no solar gain
    ("TiTe+heater", "TiTeTh"): ("Ch -> 0", 2),
    ("TiTe+heater", "TiTe+heater+solar"): ("Aw = 0", 1),
    ("Ti", "TiTh"): ("Rih -> ∞", 2),  # heater node cut off: Ph no longer acts
    ("TiTh", "TiTeTh"): ("Ce -> 0", 2),
    ("Ti", "TiTe"): ("Ce -> 0", 2),
}

NOT_NESTED = [
    ("Ti", "Ti+heater"),  # the heater's gain is a constant 1: nothing to set to zero
    ("TiTe", "TiTe+heater"),
    ("TiTh", "TiTe+heater"),  # the heater sits on another node, and as many parameters
    ("TiTe+heater", "TiTm+heater"),
    ("TiTe+heater", "Ti+heater"),  # the other way round
    ("TiTe+heater", "TiTe+heater"),
]


def net(name: str) -> RCNetwork:
    return load_model(name).network


@pytest.mark.parametrize(("pair", "expected"), NESTED.items(), ids=lambda x: str(x))
def test_family_pairs_that_are_nested(pair, expected):
    found = nesting(net(pair[0]), net(pair[1]))
    assert found is not None
    assert (found.describe(), found.df) == expected


@pytest.mark.parametrize("pair", NOT_NESTED, ids=str)
def test_family_pairs_that_are_not_nested(pair):
    assert nesting(net(pair[0]), net(pair[1])) is None


def _simulate(model: str, theta: dict, t: np.ndarray, signals: dict, x0: dict) -> np.ndarray:
    zm = load_model(model).with_values(theta)
    u = np.column_stack([signals[n] for n in zm.network.input_names])
    x = np.array([x0.get(s, 0.0) for s in zm.network.state_names])
    return zm.simulate(t, u, x0=x).y[:, 0]


@pytest.mark.parametrize(
    "pair", [p for p in itertools.permutations(FAMILY, 2) if nesting(net(p[0]), net(p[1]))], ids=str
)
def test_a_nested_model_is_reproduced_by_the_restricted_richer_one(pair):
    """Every nesting the rule finds is real: the richer model at the limit simulates the simpler one."""
    simple, rich = pair
    found = nesting(net(simple), net(rich))
    rng = np.random.default_rng(1)
    za, zb = load_model(simple), load_model(rich)
    theta_a = {k: v * rng.uniform(0.5, 2.0) for k, v in za.theta.items()}
    theta_b = realize(found, theta_a, dict(zb.theta), eps=1e-8)
    t = np.arange(0.0, 2 * 86400.0, 600.0)
    signals = {
        "To": 5 + 4 * np.sin(2 * np.pi * t / 86400),
        "Ph": 800.0 * (rng.random(t.size) < 0.4),
        "Ps": np.clip(300 * np.sin(2 * np.pi * (t / 3600 - 6) / 24), 0, None),
    }
    x0 = {"Ti": 20.0, "Te": 12.0, "Tm": 18.0, "Th": 20.0}
    x0_b = {found.node_map.get(s, s): v for s, v in x0.items()}
    ya = _simulate(simple, theta_a, t, signals, x0)
    yb = _simulate(rich, theta_b, t, signals, {**x0, **x0_b})
    assert np.max(np.abs(ya - yb)) < 1e-3
    # and away from the limit the richer model is another model (the check can fail)
    other = {**theta_b, **{p: zb.theta[p] for p, _ in found.restriction}}
    assert np.max(np.abs(_simulate(rich, other, t, signals, x0) - ya)) > 0.05


def _custom(name, nodes, resistors, params, heat=(), outputs=("Ti",)):
    return RCNetwork(name, nodes, ["To"], resistors, params, heat_inputs=heat, outputs=list(outputs))


#: A room to outdoors through one resistance.
ROOM = [Parameter("C1", "capacitance", 1e6), Parameter("R1", "resistance", 0.01)]
ONE = _custom("one", [Node("Ti", "C1")], [Resistor("Ti", "To", "R1")], ROOM)


def test_node_names_do_not_matter_and_fixed_values_must_agree():
    one = ONE
    two = _custom(
        "two",
        [Node("Ti", "Ca"), Node("Twall", "Cb")],
        [Resistor("Ti", "Twall", "Ra"), Resistor("Twall", "To", "Rb")],
        [
            Parameter("Ca", "capacitance", 1e6),
            Parameter("Cb", "capacitance", 1e7),
            Parameter("Ra", "resistance", 0.002),
            Parameter("Rb", "resistance", 0.02),
        ],
    )
    found = nesting(one, two)
    assert found is not None and found.describe() == "Cb -> 0"
    assert dict(found.correspondence) == {"C1": "Ca", "R1": "(Ra + Rb)"}
    # the renamed wall: TiTe's Te is two's Twall
    found = nesting(net("TiTe"), renamed_tite())
    assert found is not None and found.node_map["Te"] == "Twall" and found.describe() == "none"
    # a value the richer model holds fixed must be the simpler model's
    assert nesting(one, two, free_rich=["Ca", "Cb", "Ra"]) is None  # Rb fixed: Ra + Rb is not free
    assert nesting(one, two, free_simple=["C1"], free_rich=["Ca", "Cb", "Ra", "Rb"]) is not None


def renamed_tite() -> RCNetwork:
    """TiTe with its envelope node called Twall, and a parameter that acts nowhere (one more free)."""
    return RCNetwork(
        "renamed",
        [Node("Ti", "Ci"), Node("Twall", "Ce")],
        ["To"],
        [Resistor("Ti", "Twall", "Rie"), Resistor("Twall", "To", "Rea")],
        [
            Parameter("Ci", "capacitance", 1e6),
            Parameter("Ce", "capacitance", 1e7),
            Parameter("Rie", "resistance", 0.002),
            Parameter("Rea", "resistance", 0.02),
            Parameter("Rx", "resistance", 1.0),
        ],
        outputs=["Ti"],
    )


def test_reductions_parallel_resistors_dangling_nodes_ties_and_noise():
    one = ONE
    # two resistors in parallel to outdoors, and a massless node hanging off the room
    par = _custom(
        "par",
        [Node("Ti", "C1"), Node("Tx")],
        [Resistor("Ti", "To", "Ra"), Resistor("Ti", "To", "Rb"), Resistor("Ti", "Tx", "Rc")],
        [
            Parameter("C1", "capacitance", 1e6),
            Parameter("Ra", "resistance", 0.02),
            Parameter("Rb", "resistance", 0.02),
            Parameter("Rc", "resistance", 0.01),
        ],
    )
    found = nesting(one, par)
    assert found is not None and found.describe() == "none"
    assert dict(found.correspondence)["R1"] == "(Ra || Rb)"
    # tied parameters are not analysed
    tied = _custom(
        "tied",
        [Node("Ti", "C1"), Node("Tw", "C2")],
        [Resistor("Ti", "Tw", "Rh"), Resistor("Tw", "To", "Rh2")],
        [
            Parameter("C1", "capacitance", 1e6),
            Parameter("C2", "capacitance", 1e7),
            Parameter("Rw", "resistance", 0.01),
            Parameter("Rh", "resistance", expr="Rw/2"),
            Parameter("Rh2", "resistance", expr="Rw/2"),
        ],
    )
    assert nesting(one, tied) is None
    # a free noise level of the simpler model needs a free counterpart
    te = net("TiTe")
    assert nesting(
        one, te, ["C1", "R1", "sigma_v", "sigma_w_Ti"], [*te.default_free, "sigma_v", "sigma_w_Ti"]
    )
    assert nesting(one, te, ["C1", "R1", "sigma_v", "sigma_w_Ti"], [*te.default_free, "sigma_v"]) is None
    # different outputs are different measurements
    other_out = _custom(
        "out",
        [Node("Ti", "C1"), Node("Tw", "C2")],
        [Resistor("Ti", "Tw", "R2"), Resistor("Tw", "To", "R1")],
        [*ROOM, Parameter("C2", "capacitance", 1e7), Parameter("R2", "resistance", 0.01)],
        outputs=("Tw",),
    )
    assert nesting(one, other_out) is None


def test_heat_into_a_cut_off_node_and_a_gain_with_zero_inside_its_bounds():
    def gained(bounds):
        return _custom(
            "g",
            [Node("Ti", "C1")],
            [Resistor("Ti", "To", "R1")],
            [*ROOM, Parameter("g", "gain", 0.5, bounds=bounds)],
            heat=[HeatInput("Q", {"Ti": "g"})],
        )

    found = nesting(ONE, gained((-1.0, 1.0)))
    assert found is not None and found.describe() == "g = 0"
    assert found.n_boundary == 0  # zero is inside the gain's domain: a regular test
    assert nesting(ONE, gained((0.1, 1.0))) is None  # zero is not a value the gain can take


def test_chi_bar_squared_mixture():
    from scipy.stats import chi2

    assert chi_bar_sf(3.0, 2, 0) == pytest.approx(chi2.sf(3.0, 2))
    assert chi_bar_sf(3.0, 1, 1) == pytest.approx(0.5 * chi2.sf(3.0, 1))
    assert chi_bar_sf(3.0, 2, 1) == pytest.approx(0.5 * chi2.sf(3.0, 1) + 0.5 * chi2.sf(3.0, 2))
    assert chi_bar_sf(0.0, 1, 1) == pytest.approx(1.0)
    # Monte Carlo: the likelihood ratio of a mean >= 0 at the boundary (Self & Liang, one parameter)
    rng = np.random.default_rng(0)
    z = rng.standard_normal(200_000)
    lr = np.maximum(z, 0.0) ** 2
    for c in (1.0, 2.7, 5.0):
        assert np.mean(lr > c) == pytest.approx(chi_bar_sf(c, 1, 1), abs=0.003)
