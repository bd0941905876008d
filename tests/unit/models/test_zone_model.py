import json

import numpy as np
import pytest
from scipy.linalg import expm

from rczone.control import ZoneModel
from rczone.errors import ModelFileError, NetworkError, ParameterError
from rczone.models import get_model
from rczone.network.serialize import network_from_dict, network_to_dict
from tests.netfactory import thirteen_state


@pytest.mark.parametrize("name", ["full-scale", "second-order", "first-order", "second-order-paper"])
def test_network_round_trip_preserves_matrices(name):
    net = get_model(name)
    back = network_from_dict(json.loads(json.dumps(network_to_dict(net))))
    a, b = net.state_space(), back.state_space()
    for x, y in ((a.A, b.A), (a.B, b.B), (a.N, b.N), (a.M, b.M), (a.C, b.C), (a.D, b.D)):
        np.testing.assert_array_equal(x, y)
    assert back.input_names == net.input_names and back.parameters.keys() == net.parameters.keys()


def test_saved_model_loads_and_simulates_identically(tmp_path):
    rng = np.random.default_rng(4)
    net = thirteen_state(rng)
    zm = ZoneModel(net, {"Cr": 3.3e5, "Rwin": 0.2}, {"method": "ml", "data": "C"})
    path = zm.save(tmp_path / "model.json")
    back = ZoneModel.load(path)
    assert back.provenance == {"method": "ml", "data": "C"}
    t = np.arange(0, 7200.0, 60)
    u = 20 + rng.standard_normal((t.size, 8))
    m = rng.uniform(0, 0.12, (t.size, 1))
    np.testing.assert_array_equal(zm.simulate(t, u, m).y, back.simulate(t, u, m).y)


def test_discrete_matrices_are_the_exact_exponential():
    zm = ZoneModel(get_model("second-order-paper"), {"Rw": 0.01})
    d = zm.discrete(300.0, m=0.12)
    c = zm.continuous(0.12)
    np.testing.assert_allclose(d.Ad, expm(c.A * 300.0), rtol=1e-12)
    # ZOH input matrix: A^{-1} (Ad - I) B for an invertible A
    np.testing.assert_allclose(d.Bd, np.linalg.solve(c.A, (d.Ad - np.eye(2)) @ c.B), rtol=1e-9, atol=1e-15)
    arr = zm.arrays(0.12)
    np.testing.assert_allclose(arr["A"], c.A)
    assert d.input_names == ("To", "Tsd", "Ts", "Q")
    # FOH from the block exponential of [[A, B, 0], [0, 0, I/dt], [0, 0, 0]] dt
    f = zm.discrete(300.0, m=0.12, hold="foh")
    n, p = c.B.shape
    blk = np.zeros((n + 2 * p, n + 2 * p))
    blk[:n, :n], blk[:n, n : n + p], blk[n : n + p, n + p :] = c.A * 300.0, c.B * 300.0, np.eye(p)
    E = expm(blk)
    np.testing.assert_allclose(f.Bd1, E[:n, n + p :], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(f.Bd, E[:n, n : n + p] - E[:n, n + p :], rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda p: ZoneModel.load(p / "missing.json"), ModelFileError, "does not exist"),
        (lambda p: ZoneModel.load(_write(p, "{not json")), ModelFileError, "not valid JSON"),
        (
            lambda p: ZoneModel.load(_write(p, '{"format": "other"}')),
            ModelFileError,
            "not an rczone model file",
        ),
        (
            lambda p: network_from_dict({"format": "rczone-network/1", "name": "x"}),
            NetworkError,
            "has no .nodes.",
        ),
        (lambda p: ZoneModel(get_model("first-order"), {"Rww": 1.0}), ParameterError, "did you mean 'Rw'"),
    ],
)
def test_bad_model_files(tmp_path, call, exc, match):
    with pytest.raises(exc, match=match):
        call(tmp_path)


def _write(folder, text):
    p = folder / "m.json"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("dt", "m", "match"),
    [
        (float("inf"), 0.1, "finite and > 0"),
        (float("nan"), 0.1, "finite and > 0"),
        (-60.0, 0.1, "finite and > 0"),
        ("x", 0.1, "number of seconds"),
        (60.0, float("nan"), "finite and >= 0"),
        (60.0, -0.1, "finite and >= 0"),
        (60.0, [0.1, 0.2], "1 value"),
    ],
)
def test_discrete_refuses_unusable_sample_times_and_flows(dt, m, match):
    from rczone.errors import InputShapeError

    zm = ZoneModel(get_model("second-order-paper"))
    with pytest.raises(InputShapeError, match=match):
        zm.discrete(dt, m)


def test_a_model_with_a_non_finite_element_is_refused():
    from rczone.network import HeatInput, Parameter, RCNetwork

    net = get_model("first-order")
    bad = RCNetwork(
        net.name,
        net.nodes,
        net.boundaries,
        net.resistors,
        [*net.parameters.values(), Parameter("g", "gain", 1.0)],
        [HeatInput("Q", {"Ti": "g"})],
        net.supply_air,
    )
    assert np.all(np.isfinite(ZoneModel(bad).discrete(60.0, 0.1).Ad))
    with pytest.raises(ParameterError, match="not finite"):
        ZoneModel(bad, {"g": float("nan")})


def test_a_model_with_supply_air_needs_its_operating_flow_and_one_without_does_not():
    from rczone.errors import InputShapeError
    from rczone.models import load_model

    paper = load_model("second-order-paper")  # a supply-air element m cp (Ts - Ti)
    for call in (paper.continuous, lambda: paper.discrete(300.0), paper.to_control):
        with pytest.raises(InputShapeError, match="give the operating flow m in kg/s"):
            call()
    # with the flow, the matrices are those at that flow: A changes by -m cp / Cr on the room's diagonal
    a0, a1 = paper.continuous(0.0).A, paper.continuous(0.1).A
    i = list(paper.network.state_names).index("Ti")
    assert a1[i, i] - a0[i, i] == pytest.approx(-0.1 * 1005.0 / paper.theta["Cr"], rel=1e-9)
    heated = load_model("TiTe+heater")  # no flow: nothing to give
    assert heated.discrete(300.0).Ad.shape == (2, 2)
