"""The Bacher & Madsen family: the structures their names say, checked by steady-state gains."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.models import FAMILY, load_model
from rczone.models.library import canonical_name, family_network, parse_name


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
