"""Zones and interzone adjacency from eplusout.eio: each shared surface counted once."""

from __future__ import annotations

import pytest

from rczone.emulators.geometry import read_eio
from rczone.errors import EmulatorError


def zone_line(name, min_z, area, volume, part="Yes"):
    f = ["Zone Information", name, *["0"] * 14, str(min_z), "3", "3", str(volume), "T", "T", str(area)]
    f += ["0"] * 6 + [part]
    return ",".join(f)


def surface(name, cls, u, area, bc):
    return ",".join(
        ["HeatTransfer Surface", name, cls, "", "CTF", "C", "1", str(u), "", str(area), *["0"] * 7, bc]
    )


EIO = "\n".join(
    [
        zone_line("A", 0, 100, 300),
        zone_line("B", 0, 50, 150),
        zone_line("P", 3, 150, 100, part="No"),
        zone_line("C", 4, 100, 300),
        "Zone Surfaces,A,3",
        surface("A_W", "Wall", 2.0, 10, "B_W"),
        surface("A_W2", "Wall", 2.0, 5, "B_W2"),
        surface("A_EXT", "Wall", 0.5, 30, "ExternalEnvironment"),
        surface("A_WIN", "Window", 2.0, 6, "ExternalEnvironment"),
        surface("A_FLOOR", "Floor", 0.3, 100, "A_FLOOR"),
        "Zone Surfaces,B,2",
        surface("B_W", "Wall", 2.0, 10, "A_W"),
        surface("B_W2", "Wall", 2.0, 5, "A_W2"),
        "Zone Surfaces,P,1",
        surface("P_FLOOR", "Floor", 1.5, 100, "A_CEIL"),
        "Zone Surfaces,C,0",
    ]
)


def test_adjacency_sums_the_shared_surfaces_once():
    g = read_eio(EIO, names=["A", "B", "P", "C"])
    (ab,) = [a for a in g.adjacency if {a.a, a.b} == {"A", "B"}]
    assert (
        ab.area == pytest.approx(15.0) and ab.ua == pytest.approx(30.0) and ab.u_value == pytest.approx(2.0)
    )
    assert g.neighbours("B") == {"A": pytest.approx(30.0)}
    a = g.zone("a")
    assert a.exterior_ua == pytest.approx(0.5 * 30 + 2.0 * 6) and a.window_area == pytest.approx(6)
    assert (a.floor_area, a.volume, a.conditioned) == (100.0, 300.0, True)


def test_floors_count_conditioned_levels_and_plenums_join_the_floor_below():
    g = read_eio(EIO)
    assert {z.name: z.floor for z in g.zones} == {"A": 1, "B": 1, "P": 1, "C": 2}


def test_no_zone_information_is_an_error():
    with pytest.raises(EmulatorError, match="no zone information"):
        read_eio("Program Version, EnergyPlus")
