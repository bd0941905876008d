"""The Bacher & Madsen family: the structures their names say, checked by steady-state gains."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.models import FAMILY, load_model
from rczone.models.library import (
    canonical_name,
    family_bases,
    family_extensions,
    family_network,
    parse_base,
    parse_name,
)
from rczone.selection.nesting import nesting, realize


def _dc(name: str, theta: dict[str, float] | None = None):
    ss = family_network(name).state_space(theta)
    return ss, ss.lti(np.zeros(ss.n_flows)).dc_gain()[0]


@pytest.mark.parametrize(
    ("name", "states", "heat_to_ti"),
    [
        ("Ti+heater", ("Ti",), lambda v: v["Ria"]),
        ("TiTe+heater", ("Ti", "Te"), lambda v: v["Rie"] + v["Rea"]),
        ("TiTh", ("Ti", "Th"), lambda v: v["Ria"]),
        ("TiTeTh", ("Ti", "Te", "Th"), lambda v: v["Rie"] + v["Rea"]),
        ("TiTm+heater", ("Ti", "Tm"), lambda v: v["Ria"]),
    ],
)
def test_steady_state_gains_are_the_series_resistances(name, states, heat_to_ti) -> None:
    """At rest a heater's power flows to the outdoors through the resistances between Ti and To."""
    rng = np.random.default_rng(7)
    net = family_network(name)
    theta = {n: p.value * rng.uniform(0.5, 2.0) for n, p in net.parameters.items()}
    ss, g = _dc(name, theta)
    assert ss.state_names == states
    assert g[ss.input_names.index("To")] == pytest.approx(1.0, rel=1e-12)
    assert g[ss.input_names.index("Ph")] == pytest.approx(heat_to_ti(theta), rel=1e-10)


def test_options_add_their_inputs() -> None:
    net = family_network("TiTe+air+solar+gain+heater")
    assert net.name == "TiTe+heater+solar+air+gain"  # canonical order
    assert net.input_names == ("To", "Ts", "Ph", "Ps", "Q") and net.flow_names == ("m",)
    assert "Aw" in net.default_free and net.parameters["Aw"].unit == "m2"
    ss, g = _dc("TiTe+solar", {"Aw": 3.0})
    v = family_network("TiTe+solar").values({"Aw": 3.0})
    assert g[ss.input_names.index("Ps")] == pytest.approx(3.0 * (v["Rie"] + v["Rea"]), rel=1e-10)


def test_names_parse_and_errors_suggest() -> None:
    assert parse_name("TiTeTh+solar") == ("TiTeTh", ("solar",))
    assert canonical_name("TiTe+solar+heater") == "TiTe+heater+solar"
    for bad, match in (
        ("TiTx", "did you mean"),
        ("Ti+sun", "unknown option 'sun'"),
        ("Ti+solar+solar", "twice"),
    ):
        with pytest.raises(ParameterError, match=match):
            parse_name(bad)
    for base in FAMILY:
        zm = load_model(base)
        assert zm.network.outputs == ("Ti",) and zm.label == base


# --------------------------------------------------------------------- the rest of the family


@pytest.mark.parametrize(
    ("name", "states", "heat_to_ti", "solar_to_ti"),
    [
        # a direct path to outdoors beside the envelope: the two conductances add
        (
            "TiTeThRia+solar",
            ("Ti", "Te", "Th"),
            lambda v: 1.0 / (1.0 / v["Ria"] + 1.0 / (v["Rie"] + v["Rea"])),
            lambda v: v["Aw"] / (1.0 / v["Ria"] + 1.0 / (v["Rie"] + v["Rea"])),
        ),
        # solar into the envelope leaves through Rea; the room follows the envelope at rest
        (
            "TiTeAe+heater+solar",
            ("Ti", "Te"),
            lambda v: v["Rie"] + v["Rea"],
            lambda v: v["Aw"] * (v["Rie"] + v["Rea"]) + v["Ae"] * v["Rea"],
        ),
        # the sensor sits behind Ris and carries no heat at rest: it reads the room air
        (
            "TiTsnAs+heater+solar",
            ("Ti", "Tr"),
            lambda v: v["Ria"],
            lambda v: v["Aw"] * v["Ria"] + v["As"] * (v["Ris"] + v["Ria"]),
        ),
        # the medium is a dead end: no effect at rest
        (
            "TiTmTe+heater+solar",
            ("Ti", "Te", "Tm"),
            lambda v: v["Rie"] + v["Rea"],
            lambda v: v["Aw"] * (v["Rie"] + v["Rea"]),
        ),
    ],
)
def test_the_new_parts_have_the_steady_state_gains_of_their_circuits(name, states, heat_to_ti, solar_to_ti):
    """Steady-state gains worked out by hand from each circuit (series and parallel resistances)."""
    rng = np.random.default_rng(3)
    net = family_network(name)
    theta = {n: p.value * rng.uniform(0.5, 2.0) for n, p in net.parameters.items()}
    ss, g = _dc(name, theta)
    assert ss.state_names == states and net.outputs == ("Ti",)
    assert g[ss.input_names.index("To")] == pytest.approx(1.0, rel=1e-12)
    assert g[ss.input_names.index("Ph")] == pytest.approx(heat_to_ti(theta), rel=1e-10)
    assert g[ss.input_names.index("Ps")] == pytest.approx(solar_to_ti(theta), rel=1e-10)


def test_the_family_grows_one_part_at_a_time() -> None:
    bases = family_bases()
    # Tm, Th free; Te with or without Ae and Ria; Tsn with or without As: 2 * 2 * (1 + 4) * (1 + 2)
    assert len(bases) == len(set(bases)) == 60 and bases[0] == "Ti"
    assert set(FAMILY) <= set(bases) and "TiTmTeThTsnAeAsRia" in bases
    assert all("Ti" + "".join(parse_base(b)) == b for b in bases)
    assert set(family_extensions("TiTeTh+heater+solar")) == {
        "TiTmTeTh+heater+solar",
        "TiTeThTsn+heater+solar",
        "TiTeThAe+heater+solar",
        "TiTeThRia+heater+solar",
    }
    assert family_extensions("Ti") == ("TiTm", "TiTe", "TiTh", "TiTsn")  # no solar parts without +solar
    assert canonical_name("TiRiaThTe+solar") == "TiTeThRia+solar"


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        ("TiAe+solar", "needs part Te"),
        ("TiRia", "needs part Te"),
        ("TiTeAs+solar", "needs part Tsn"),
        ("TiTeAe", r"add the option \+solar"),
        ("TiTeTe", "twice"),
        ("TiTs", "unknown model"),  # the sensor is Tsn: Ts is the supply-air temperature
        ("TeTi", "unknown model"),
    ],
)
def test_invalid_names_say_what_part_is_missing(bad, match) -> None:
    with pytest.raises(ParameterError, match=match):
        load_model(bad)


@pytest.mark.parametrize(
    ("simple", "rich", "restriction"),
    [
        ("TiTeTh+solar", "TiTeThRia+solar", "Ria -> ∞"),
        ("TiTeTh+solar", "TiTeThAe+solar", "Ae = 0"),
        ("TiTeTh+solar", "TiTeThTsn+solar", "Ris -> 0"),
        ("TiTeThRia+solar", "TiTmTeThRia+solar", "Cm -> 0"),
        ("TiTmTeThRia+solar", "TiTmTeThAeRia+solar", "Ae = 0"),
        ("TiTsn+solar", "TiTsnAs+solar", "As = 0"),
    ],
)
def test_each_step_nests_the_model_it_extends(simple, rich, restriction) -> None:
    """The restricted richer model simulates the simpler one (and, away from the limit, does not)."""
    found = nesting(family_network(simple), family_network(rich))
    assert found is not None and found.describe() == restriction
    rng = np.random.default_rng(5)
    za, zb = load_model(simple), load_model(rich)
    theta_a = {k: v * rng.uniform(0.5, 2.0) for k, v in za.theta.items()}
    theta_b = realize(found, theta_a, dict(zb.theta), eps=1e-9)
    t = np.arange(0.0, 2 * 86400.0, 600.0)
    signals = {
        "To": 5 + 4 * np.sin(2 * np.pi * t / 86400),
        "Ph": 800.0 * (rng.random(t.size) < 0.4),
        "Ps": np.clip(300 * np.sin(2 * np.pi * (t / 3600 - 6) / 24), 0, None),
    }

    def run(zm, theta):
        zm = zm.with_values(theta)
        u = np.column_stack([signals[n] for n in zm.network.input_names])
        x0 = np.array([12.0 if s == "Te" else 20.0 for s in zm.network.state_names])
        return zm.simulate(t, u, x0=x0).y[:, 0]

    ya = run(za, theta_a)
    assert np.max(np.abs(run(zb, theta_b) - ya)) < 1e-3
    other = {**theta_b, **{p: zb.theta[p] for p, _ in found.restriction}}
    assert np.max(np.abs(run(zb, other) - ya)) > 0.05
