"""A zone's HVAC energy: its own coils and its flow share of its air loop, read from the input file."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyenergyplus")

from rczone.emulators import catalog, idf
from rczone.emulators.hvacmeters import attribute, zone_equipment


def _equipment(building):
    objects = idf.parse_idf(catalog.building_file(building).read_text(encoding="latin-1"))
    zones = idf.zones(objects)
    return zone_equipment(objects, zones), {z.name: z.inlets for z in zones}


def test_the_medium_office_zones_share_their_floor_air_handler_and_own_their_reheat_coil():
    eq, _ = _equipment("office_medium")
    assert len(eq) == 15
    z = eq["Perimeter_mid_ZN_1"]
    assert [c.part for c in z.own] == ["reheat"] and "Perimeter_mid_ZN_1" in z.own[0].name
    assert sorted(c.part for c in z.loop) == ["cooling", "fan", "heating"]
    assert len(z.loop_zones) == 5 and all("_mid" in n for n in z.loop_zones)


def test_each_small_office_zone_has_its_own_packaged_unit():
    eq, _ = _equipment("office_small")
    loops = {tuple(c.name for c in e.loop) for e in eq.values()}
    assert len(eq) == 5 and len(loops) == 5
    assert all(e.loop_zones == (z,) and not e.own for z, e in eq.items())


def test_the_shares_of_a_loop_add_up_to_its_components_and_follow_the_flows():
    eq, inlets = _equipment("office_medium")
    floor = eq["Perimeter_mid_ZN_1"].loop_zones
    rng = np.random.default_rng(0)
    rows = []
    for k in range(20):
        r = {f"m:{n}": (0.0 if k == 3 else rng.uniform(0.1, 1.0)) for z in floor for n in inlets[z]}
        for c in (*eq[floor[0]].loop, *(c for z in floor for c in eq[z].own)):
            r.update({lb: rng.uniform(0, 1000) for lb in c.labels()})
        rows.append(r)
    parts = {z: attribute(rows, eq[z], inlets) for z in floor}
    loop_total = np.array([sum(r[lb] for c in eq[floor[0]].loop for lb in c.labels()) for r in rows])
    own_total = np.array([sum(r[lb] for z in floor for c in eq[z].own for lb in c.labels()) for r in rows])
    np.testing.assert_allclose(sum(sum(p.values()) for p in parts.values()), loop_total + own_total)
    z0 = floor[0]
    flow = np.array([sum(r[f"m:{n}"] for n in inlets[z0]) for r in rows])
    total = np.array([sum(r[f"m:{n}"] for z in floor for n in inlets[z]) for r in rows])
    fan = np.array([sum(r[lb] for c in eq[z0].loop if c.part == "fan" for lb in c.labels()) for r in rows])
    expect = np.where(total > 0, flow / np.where(total > 0, total, 1), 1 / 5) * fan
    np.testing.assert_allclose(parts[z0]["fan"], expect)
