"""The multi-zone generator: the 4-room model it writes is the one a person builds by hand."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.errors import ParameterError
from rczone.models import read_model_file
from rczone.models.multizone import multizone
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor

WALLS = [("1", "2"), ("2", "3"), ("3", "4")]
CIRCUITS = {"Ph1": ["1", "2"], "Ph2": ["3", "4"]}


def hand_built() -> RCNetwork:
    """Four rooms in a row written out element by element, two circuits of two rooms each."""
    nodes = [
        Node("T1", "Ci_1"), Node("Te1", "Ce_1"), Node("T2", "Ci_2"), Node("Te2", "Ce_2"),
        Node("T3", "Ci_3"), Node("Te3", "Ce_3"), Node("T4", "Ci_4"), Node("Te4", "Ce_4"),
    ]  # fmt: skip
    resistors = [
        Resistor("T1", "Te1", "Rie_1"), Resistor("Te1", "To", "Rea_1"),
        Resistor("T2", "Te2", "Rie_2"), Resistor("Te2", "To", "Rea_2"),
        Resistor("T3", "Te3", "Rie_3"), Resistor("Te3", "To", "Rea_3"),
        Resistor("T4", "Te4", "Rie_4"), Resistor("Te4", "To", "Rea_4"),
        Resistor("T1", "T2", "Rw_1_2"), Resistor("T2", "T3", "Rw_2_3"), Resistor("T3", "T4", "Rw_3_4"),
    ]  # fmt: skip
    params = [Parameter(f"C{k}_{r}", "capacitance", 1e6) for k in "ie" for r in "1234"]
    params += [Parameter(f"R{k}_{r}", "resistance", 0.01) for k in ("ie", "ea") for r in "1234"]
    params += [Parameter(f"Rw_{a}_{b}", "resistance", 0.05) for a, b in WALLS]
    params += [Parameter("s_Ph1_1", "gain", 0.5), Parameter("s_Ph2_3", "gain", 0.5)]
    heat = [
        HeatInput("Ph1", {"T1": "s_Ph1_1", "T2": "s_Ph1_2"}),
        HeatInput("Ph2", {"T3": "s_Ph2_3", "T4": "s_Ph2_4"}),
    ]
    params += [
        Parameter("s_Ph1_2", "gain", expr="1 - s_Ph1_1"),
        Parameter("s_Ph2_4", "gain", expr="1 - s_Ph2_3"),
    ]
    return RCNetwork(
        "hand", nodes, ["To"], resistors, params, heat_inputs=heat, outputs=["T1", "T2", "T3", "T4"]
    )


def _random_theta(net: RCNetwork, seed: int = 4) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    theta = {}
    for n, p in sorted(net.parameters.items()):
        if p.is_tied:
            continue
        theta[n] = rng.uniform(0.1, 0.9) if p.kind == "gain" else p.value * rng.uniform(0.3, 3.0)
    return theta


def _same_state_space(a: RCNetwork, b: RCNetwork, theta: dict[str, float]) -> None:
    sa, sb = a.state_space(theta), b.state_space(theta)
    assert sa.state_names == sb.state_names and sa.input_names == sb.input_names
    assert sa.output_names == sb.output_names
    for m in ("A", "B", "C", "D"):
        np.testing.assert_allclose(getattr(sa, m), getattr(sb, m), rtol=1e-12, atol=0)


def test_the_generated_four_room_model_is_the_hand_built_one() -> None:
    gen = multizone(4, WALLS, circuits=CIRCUITS)
    hand = hand_built()
    assert set(gen.parameters) == set(hand.parameters)
    _same_state_space(gen, hand, _random_theta(hand))


def test_a_circuits_shares_add_up_to_one() -> None:
    """At rest every watt of a circuit leaves to outdoors: the shares split it, and lose none."""
    net = multizone(["a", "b", "c"], [("a", "b")], circuits={"Ph": ["a", "b", "c"]})
    theta = _random_theta(net)
    ss = net.state_space(theta)
    b = ss.B[:, ss.input_names.index("Ph")] * ss.capacities
    assert b.sum() == pytest.approx(1.0, rel=1e-12)
    assert b[ss.state_names.index("Ta")] == pytest.approx(theta["s_Ph_a"], rel=1e-12)


def test_per_room_mass_and_measured_rooms() -> None:
    net = multizone(2, [("1", "2")], mass=True, measured=["2"])
    assert net.state_names == ("T1", "Te1", "Tm1", "T2", "Te2", "Tm2") and net.outputs == ("T2",)
    assert net.input_names == ("To", "Q1", "Q2")


def test_rczone_models_generate_writes_a_file_that_loads_back_to_the_same_network(tmp_path, capsys) -> None:
    out = tmp_path / "four.toml"
    args = ["models", "generate", "--rooms", "4", "--wall", "1-2", "--wall", "2-3", "--wall", "3-4"]
    rc = main([*args, "--circuit", "Ph1=1,2", "--circuit", "Ph2=3,4", "-o", str(out)])
    assert rc == 0, capsys.readouterr()
    zm = read_model_file(out)
    _same_state_space(zm.network, hand_built(), _random_theta(hand_built(), seed=9))
    assert zm.network.parameters["s_Ph1_2"].expr == "1 - s_Ph1_1"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--rooms", "3", "--wall", "1-4"], "unknown room '4'"),
        (["--rooms", "3", "--wall", "1-1"], "no wall with itself"),
        (["--rooms", "3", "--wall", "1-2", "--wall", "2-1"], "listed twice"),
        (["--rooms", "3", "--wall", "12"], "two rooms joined by a dash"),
        (["--rooms", "3", "--circuit", "Ph=1,1"], "each once"),
        (["--rooms", "a,b,a"], "listed twice"),
        (["--rooms", "a b"], "letters and digits"),
        (["--rooms", "0"], "1 to 50"),
    ],
)
def test_mistakes_are_one_line_and_exit_2(args, message, capsys) -> None:
    assert main(["models", "generate", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_the_python_api_rejects_what_the_cli_rejects() -> None:
    with pytest.raises(ParameterError, match="a wall joins two rooms"):
        multizone(2, [("1", "2", "3")])


def test_solar_and_a_measured_neighbour_are_the_hand_built_elements(tmp_path, capsys) -> None:
    """Two rooms, the sun through Aw_1 and Aw_2, and a corridor Tc (measured) behind room 2."""
    out = tmp_path / "two.toml"
    args = [
        "models",
        "generate",
        "--rooms",
        "2",
        "--wall",
        "1-2",
        "--solar",
        "--boundary",
        "Tc=2",
        "-o",
        str(out),
    ]
    assert main(args) == 0, capsys.readouterr()
    gen = read_model_file(out).network
    nodes = [Node("T1", "Ci_1"), Node("Te1", "Ce_1"), Node("T2", "Ci_2"), Node("Te2", "Ce_2")]
    resistors = [
        Resistor("T1", "Te1", "Rie_1"), Resistor("Te1", "To", "Rea_1"),
        Resistor("T2", "Te2", "Rie_2"), Resistor("Te2", "To", "Rea_2"),
        Resistor("T1", "T2", "Rw_1_2"), Resistor("T2", "Tc", "Rb_2_Tc"),
    ]  # fmt: skip
    params = [Parameter(f"C{k}_{r}", "capacitance", 1e6) for k in "ie" for r in "12"]
    params += [Parameter(f"R{k}_{r}", "resistance", 0.01) for k in ("ie", "ea") for r in "12"]
    params += [Parameter("Rw_1_2", "resistance", 0.05), Parameter("Rb_2_Tc", "resistance", 0.05)]
    params += [Parameter(f"Aw_{r}", "gain", 2.0, unit="m2") for r in "12"]
    heat = [
        HeatInput("Q1", {"T1": 1.0}),
        HeatInput("Q2", {"T2": 1.0}),
        HeatInput("Ps", {"T1": "Aw_1", "T2": "Aw_2"}, unit="W/m2"),
    ]
    hand = RCNetwork("hand", nodes, ["To", "Tc"], resistors, params, heat_inputs=heat, outputs=["T1", "T2"])
    assert set(gen.parameters) == set(hand.parameters) and set(gen.input_names) == {
        "To",
        "Tc",
        "Q1",
        "Q2",
        "Ps",
    }
    theta = _random_theta(hand)
    sa, sb = gen.state_space(theta), hand.state_space(theta)
    order = [sa.input_names.index(n) for n in sb.input_names]
    np.testing.assert_allclose(sa.A, sb.A, rtol=1e-12)
    np.testing.assert_allclose(sa.B[:, order], sb.B, rtol=1e-12)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--rooms", "2", "--boundary", "T1=2"], "boundary zone 'T1'"),
        (["--rooms", "2", "--boundary", "Tc=3"], "unknown room '3'"),
        (["--rooms", "2", "--boundary", "Tc"], "give NAME=ROOM,ROOM"),
    ],
)
def test_boundary_zone_mistakes_are_one_line(args, message, capsys) -> None:
    assert main(["models", "generate", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
