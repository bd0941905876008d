"""Band-matched reduction: its closed-form responses against the declared networks, and what it keeps.

Oracles: :func:`rczone.simulation.frequency.frequency_response` of the networks that
:mod:`rczone.models.paper` declares (the core builds their state space from the RC graph,
independently of the transmission-matrix and closed-form responses in the reduction module), and
the parallel aggregation's DC gains.
"""

import numpy as np
import pytest

from rczone.construction import office_241
from rczone.errors import ParameterError
from rczone.models import get_model, surface_elements
from rczone.models.aggregation import reduced_values
from rczone.models.comparison import compare_frequency
from rczone.models.reduction import (
    PAPER_DU_K,
    band_matched,
    band_matched_model,
    full_response,
    low_order_response,
)
from rczone.simulation.frequency import frequency_response

F = np.logspace(-5, -3, 25)
SURR = ("Tf", "Tc", "Tn1", "Tn2", "Thw")


def _net_response(net, m):
    fr = frequency_response(net.state_space().lti(m), F)
    if "Tsd" in fr.input_names:
        return {i: fr.to_input(i) for i in ("Ts", "Tsd", "To")}
    return {"Ts": fr.to_input("Ts"), "Tsd": sum(fr.to_input(s) for s in SURR), "To": fr.to_input("To")}


@pytest.mark.parametrize("m", [0.0, 0.05, 0.12])
@pytest.mark.parametrize("split", ["matched", "symmetric"])
def test_full_response_equals_the_13_state_network(m, split):
    g = office_241()
    got = full_response(g.room_capacity, g.window.resistance, surface_elements(g, split), F, m)
    ref = _net_response(get_model("full-scale", split=split), m)
    for i in ref:
        np.testing.assert_allclose(got[i], ref[i], rtol=1e-9, atol=1e-13)


@pytest.mark.parametrize("name", ["second-order", "second-order-paper", "first-order"])
def test_low_order_closed_forms_equal_the_declared_networks(name):
    net = get_model(name)
    got = low_order_response(name, net.values(), F, 0.12)
    ref = _net_response(net, 0.12)
    for i in ref:
        np.testing.assert_allclose(got[i], ref[i], rtol=1e-9, atol=1e-13)


@pytest.mark.parametrize("name", ["second-order", "second-order-paper", "first-order"])
def test_band_matching_keeps_every_dc_gain_and_never_does_worse(name):
    full = get_model("full-scale").state_space().lti(0.12).dc_gain()[0]
    ref = dict(zip(get_model("full-scale").input_names, full, strict=True))
    net = band_matched_model(name)
    low = dict(zip(net.input_names, net.state_space().lti(0.12).dc_gain()[0], strict=True))
    assert low["Tsd"] == pytest.approx(sum(ref[s] for s in SURR), rel=1e-10)
    for i in ("To", "Ts", "Q"):
        assert low[i] == pytest.approx(ref[i], rel=1e-10)
    g = office_241()
    fit = band_matched(g.room_capacity, g.window.resistance, surface_elements(g), name)
    assert max(fit.max_error_K.values()) <= max(fit.parallel_max_error_K.values())


def test_second_order_band_values_meet_the_papers_1F_at_its_weights():
    """The paper's finding for the 2nd-order model holds with matched values, not with parallel ones."""
    models = {
        "full": get_model("full-scale"),
        "parallel": get_model("second-order"),
        "band": band_matched_model("second-order"),
    }
    e = compare_frequency(models, "full", PAPER_DU_K, m=0.12).max_errors()
    assert max(e["band"].values()) * 1.8 <= 1.0
    assert e["parallel"]["Ts"] * 1.8 > 3.0


def test_without_dc_constraint_the_reduced_model_matches_better_but_moves_the_steady_state():
    g = office_241()
    el = surface_elements(g)
    kept = band_matched(g.room_capacity, g.window.resistance, el, "second-order-paper")
    free = band_matched(g.room_capacity, g.window.resistance, el, "second-order-paper", keep_dc=False)
    assert max(free.max_error_K.values()) < max(kept.max_error_K.values())
    assert free.values["Rwin"] != pytest.approx(kept.values["Rwin"], rel=1e-3)
    assert kept.values["Rw"] == pytest.approx(reduced_values(g.room_capacity, g.window.resistance, el)["Rw"])


def test_reduced_values_rule_band_is_the_band_fit():
    g = office_241()
    el = surface_elements(g)
    band = reduced_values(g.room_capacity, g.window.resistance, el, rule="band")
    assert band == band_matched(g.room_capacity, g.window.resistance, el, "second-order-paper").values


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"structure": "second-order-papr"}, "did you mean 'second-order-paper'"),
        ({"du": {"Ts": 1.0}}, "du lacks"),
        ({"du": {"Ts": 1.0, "Tsd": -1.0, "To": 1.0}}, ">= 0 K"),
        ({"band_hz": (1e-3, 1e-5)}, "0 < low < high"),
        ({"flows": ()}, "non-empty"),
        ({"n_freq": 1}, "n_freq"),
    ],
)
def test_bad_arguments(kwargs, match):
    g = office_241()
    with pytest.raises(ParameterError, match=match):
        band_matched(g.room_capacity, g.window.resistance, surface_elements(g), **kwargs)


def test_unknown_rule():
    g = office_241()
    with pytest.raises(ParameterError, match="did you mean 'band'"):
        reduced_values(g.room_capacity, g.window.resistance, surface_elements(g), rule="bnd")
