"""The model registry, options and bad names."""

from dataclasses import replace

import pytest

from rczone.construction import office_241
from rczone.errors import ParameterError
from rczone.models import get_model, model_names
from rczone.models.elements import elements_from_values, full_scale_values, surface_elements
from rczone.network import RCNetwork

EXPECTED = {
    "full-scale": (13, 32),
    "second-order": (2, 5),
    "first-order": (1, 3),
    "second-order-paper": (2, 4),
}


def test_model_names():
    assert model_names() == tuple(EXPECTED)


@pytest.mark.parametrize(("name", "sizes"), EXPECTED.items())
def test_get_model_builds_each_model(name, sizes):
    net = get_model(name)
    assert isinstance(net, RCNetwork) and net.name == name
    assert (len(net.state_names), len(net.free_parameter_names)) == sizes
    assert net.state_names[0] == "Ti" and net.outputs == ("Ti",)
    assert net.flow_names == ("m",)
    net.state_space()  # every default value resolves


def test_get_model_uses_the_given_geometry():
    g = office_241()
    bigger = replace(g, floor_area=2 * g.floor_area)
    assert (
        get_model("first-order", bigger, capacity="room").values()["Cr"]
        > get_model("first-order", g, capacity="room").values()["Cr"]
    )


def test_options_are_passed_through():
    a = get_model("full-scale", split="symmetric").values()
    b = get_model("full-scale").values()
    assert a["Rfw1"] != b["Rfw1"]
    assert a["Rfw1"] + a["Rfw2"] + a["Rfw3"] == pytest.approx(b["Rfw1"] + b["Rfw2"] + b["Rfw3"], rel=1e-12)


def test_door_fold_scales_the_hallway_element_only():
    g = office_241()
    fold = {e.name: e.split for e in surface_elements(g, door="fold")}
    omit = {e.name: e.split for e in surface_elements(g, door="omit")}
    assert fold["n1"] == omit["n1"]
    k = fold["hw"].r1 / omit["hw"].r1
    assert 0 < k < 1
    assert (fold["hw"].r2 / omit["hw"].r2, fold["hw"].r3 / omit["hw"].r3) == pytest.approx((k, k), rel=1e-12)
    assert (fold["hw"].c1, fold["hw"].c2) == (omit["hw"].c1, omit["hw"].c2)


def test_elements_round_trip_through_values():
    g = office_241()
    vals = full_scale_values(g)
    els = elements_from_values(vals, [(s.name, s.far_side) for s in g.surfaces])
    assert els == surface_elements(g)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: get_model("second_order"), r"unknown model 'second_order'.*did you mean 'second-order'"),
        (lambda: get_model("fullscale"), r"did you mean 'full-scale'"),
        (lambda: get_model("third-order"), r"expected one of full-scale, second-order"),
        (lambda: get_model("full-scale", split="symetric"), r"did you mean 'symmetric'"),
        (lambda: get_model("full-scale", door="open"), r"unknown door option 'open'"),
        (lambda: get_model("second-order", external_capacity="some"), r"unknown external_capacity 'some'"),
        (lambda: get_model("first-order", capacity="walls"), r"unknown first-order capacity option 'walls'"),
        (
            lambda: elements_from_values({"Rfw1": 1.0}, [("f", "Tf")]),
            r"full-scale value 'Rfw2' is missing",
        ),
    ],
)
def test_bad_names_and_options(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_door_without_a_matching_surface_cannot_be_folded():
    g = office_241()
    g = replace(g, door=replace(g.door, far_side="Tlobby"))
    with pytest.raises(ParameterError, match="0 surfaces have that far side"):
        get_model("full-scale", g)
    assert len(get_model("full-scale", g, door="omit").state_names) == 13


def test_zone_without_internal_surfaces_has_no_wall():
    g = office_241()
    g = replace(g, surfaces=(g.surface("o"),), door=None)
    assert len(get_model("full-scale", g).state_names) == 3
    with pytest.raises(ParameterError, match="no internal surface to aggregate"):
        get_model("second-order", g)
