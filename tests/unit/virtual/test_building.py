"""The virtual building's structure and its true construction versus the nominal one."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.construction.room import office_241
from rczone.errors import ParameterError
from rczone.virtual.building import ZONES, build_building, check_zone, true_geometry


def test_one_network_with_a_vav_box_and_gain_per_zone():
    bld = build_building()
    net = bld.network
    assert net.flow_names == tuple(f"m_{z}" for z in ZONES)
    assert net.input_names == ("To", *(f"Ts_{z}" for z in ZONES), *(f"Q_{z}" for z in ZONES))
    assert set(bld.air_nodes.values()) <= set(net.state_names)
    assert len(net.state_names) > 100  # far finer than the 13-state full-scale model
    assert bld.gains["target"] == 50.0  # the paper's constant Q


def test_target_surfaces_in_network_match_true_geometry():
    """The ladder of each target surface has the true surface's air-to-air resistance."""
    bld = build_building()
    tg = true_geometry()
    for s in tg.surfaces:
        chain = [
            r
            for r in bld.network.resistors
            if r.a.startswith(f"t_{s.name}_") or r.b.startswith(f"t_{s.name}_")
        ]
        assert sum(r.resistance for r in chain) == pytest.approx(s.resistance, rel=1e-12)
        caps = [n.capacity for n in bld.network.nodes if n.name.startswith(f"t_{s.name}_")]
        assert sum(caps) == pytest.approx(s.capacity, rel=1e-12)


def test_truth_deviates_realistically_from_nominal():
    nom, tru = office_241(), true_geometry()
    ratios = np.array([t.resistance / n.resistance for t, n in zip(tru.surfaces, nom.surfaces)])
    assert np.all((ratios > 0.85) & (ratios < 1.18))
    assert np.any(np.abs(ratios - 1) > 0.01)
    assert tru.room_capacity > nom.room_capacity  # more furniture than assumed
    assert 0.9 <= tru.window.u_value / nom.window.u_value <= 1.1
    assert [s.name for s in tru.surfaces] == [s.name for s in nom.surfaces]


def test_building_is_deterministic():
    a = true_geometry()
    build_building.cache_clear()
    b = true_geometry()
    assert a == b


def test_unknown_zone():
    assert check_zone("hw") == "hw"
    with pytest.raises(ParameterError, match="unknown zone 'n3'; did you mean 'n2' or 'n1'"):
        check_zone("n3")
