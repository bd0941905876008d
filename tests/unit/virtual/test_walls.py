"""Fine RC walls: slicing, DC conductance and capacity against hand computations from the ASHRAE table."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.construction.materials import Construction, Material, ashrae_construction
from rczone.errors import ParameterError
from rczone.virtual.walls import perturb_construction, wall_ladder, wall_network

# ASHRAE HOF 2005 ch. 30 values, typed in by hand (thickness m, k W/(m K), rho, c):
# M01 brick 0.1016 0.89 1920 790; I02 insulation 0.0508 0.03 43 1210; F04 air space R = 0.15;
# G01a gypsum 0.019 0.16 800 1090; outside film 0.03, inside film 0.12.
R_EXT_HAND = 0.03 + 0.1016 / 0.89 + 0.0508 / 0.03 + 0.15 + 0.019 / 0.16 + 0.12
C_EXT_HAND = 1920 * 790 * 0.1016 + 43 * 1210 * 0.0508 + 800 * 1090 * 0.019
AREA = 9.0


def _steady(net, ta: float, tb: float) -> np.ndarray:
    ss = net.state_space()
    return -np.linalg.solve(ss.A, ss.B @ np.array([ta, tb]))


def test_dc_conductance_equals_area_over_r_total_by_hand():
    net = wall_network(ashrae_construction("Medium Exterior Wall", exterior=True), AREA)
    x = _steady(net, 1.0, 0.0)
    first = next(r for r in net.resistors if "Ta" in (r.a, r.b))
    last = next(r for r in net.resistors if "Tb" in (r.a, r.b))
    q_in = (1.0 - x[0]) / first.resistance
    q_out = x[-1] / last.resistance
    assert q_in == pytest.approx(AREA / R_EXT_HAND, rel=1e-10)
    assert q_out == pytest.approx(AREA / R_EXT_HAND, rel=1e-10)
    assert sum(r.resistance for r in net.resistors) == pytest.approx(R_EXT_HAND / AREA, rel=1e-12)


def test_steady_profile_is_piecewise_linear_in_resistance():
    """Node temperatures lie on the analytic steady profile 1 - r(x)/R_total (first brick slices)."""
    net = wall_network(ashrae_construction("Medium Exterior Wall", exterior=True), AREA)
    x = _steady(net, 1.0, 0.0)
    r_slice = 0.1016 / 6 / 0.89  # brick in 6 slices of 1.69 cm
    for i in range(6):
        r_centre = 0.03 + (i + 0.5) * r_slice
        assert x[i] == pytest.approx(1.0 - r_centre / R_EXT_HAND, abs=1e-12)


def test_slices_at_most_2cm_and_capacity_conserved():
    c = ashrae_construction("Medium Exterior Wall", exterior=True)
    lad = wall_ladder("w", c, AREA, "To", "Ti")
    # brick 10.16 cm -> 6, insulation 5.08 cm -> 3, gypsum 1.9 cm -> 1
    assert len(lad.nodes) == 10
    assert sum(n.capacity for n in lad.nodes) == pytest.approx(C_EXT_HAND * AREA, rel=1e-12)
    assert len(lad.resistors) == 11


def test_finer_slicing_keeps_dc_and_capacity():
    c = ashrae_construction("Medium Floor")
    a = wall_ladder("w", c, 20.0, "Ta", "Tb", max_slice=0.02)
    b = wall_ladder("w", c, 20.0, "Ta", "Tb", max_slice=0.005)
    assert len(b.nodes) > len(a.nodes)
    for lad in (a, b):
        assert sum(r.resistance for r in lad.resistors) == pytest.approx(c.r_total / 20.0, rel=1e-12)
        assert sum(n.capacity for n in lad.nodes) == pytest.approx(c.c_total * 20.0, rel=1e-12)


def test_perturbation_is_bounded_and_seeded():
    c = ashrae_construction("Medium Exterior Wall", exterior=True)
    p1 = perturb_construction(c, np.random.default_rng(3), 0.15)
    p2 = perturb_construction(c, np.random.default_rng(3), 0.15)
    assert p1 == p2
    for nom, tru in zip(c.layers, p1.layers):
        assert 0.85 / 1.0001 <= nom.r / tru.r <= 1.15 * 1.0001
    assert p1.r_total != c.r_total


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"area": 0.0}, "area must be > 0"),
        ({"area": -1.0}, "area must be > 0"),
        ({"area": 1.0, "max_slice": 0.0}, "max_slice must be > 0"),
    ],
)
def test_bad_wall_inputs(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        wall_ladder("w", ashrae_construction("Medium Partitions"), a="Ta", b="Tb", **kwargs)


def test_massless_construction_rejected():
    air = Construction("air only", (Material("gap", fixed_r=0.15),))
    with pytest.raises(ParameterError, match="no massive layer"):
        wall_ladder("w", air, 1.0, "Ta", "Tb")
