"""Per-area R and C of the shipped ASHRAE constructions, and bad inputs.

Oracles: the shared file ``../shared/reference/ashrae/derived_RC_per_m2.csv`` (computed
independently from the EnergyPlus transcription of ASHRAE HOF 2005 ch. 30; rounded to 4
decimals in m2K/W and 2 in kJ/m2K) and values computed by hand here from the materials'
published numbers.
"""

import csv

import pytest

from rczone.construction import (
    FILM_INSIDE,
    FILM_OUTSIDE,
    Construction,
    Material,
    Opening,
    Surface,
    ashrae_construction,
    construction_names,
)
from rczone.errors import ParameterError
from tests.shared_data import SHARED, require

REFERENCE = SHARED / "reference" / "ashrae" / "derived_RC_per_m2.csv"
#: The reference file used the outside (wind) film only for these constructions.
EXTERIOR_IN_REFERENCE = ("Exterior Wall", "Roof/Ceiling")


def reference_rows():
    require(REFERENCE)
    with REFERENCE.open(encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_reference_covers_every_shipped_construction():
    rows = reference_rows()
    assert sorted(r["construction"] for r in rows) == sorted(construction_names())
    assert len(rows) == 13


def test_films_used_by_the_reference_are_the_ones_documented():
    """R_total - R_layers = film_out + film_in: 0.15 where the outside film was used, else 0.24."""
    for r in reference_rows():
        films = float(r["R_total_with_films_m2K_W"]) - float(r["R_layers_m2K_W"])
        exterior = r["construction"].endswith(EXTERIOR_IN_REFERENCE)
        expected = FILM_OUTSIDE + FILM_INSIDE if exterior else 2 * FILM_INSIDE
        assert films == pytest.approx(expected, abs=2e-4), r["construction"]


@pytest.mark.parametrize("name", construction_names())
def test_per_area_r_and_c_match_the_shared_reference(name):
    row = next(r for r in reference_rows() if r["construction"] == name)
    c = ashrae_construction(name, exterior=name.endswith(EXTERIOR_IN_REFERENCE))
    assert c.r_layers == pytest.approx(float(row["R_layers_m2K_W"]), abs=6e-5)
    assert c.c_total / 1e3 == pytest.approx(float(row["C_layers_kJ_m2K"]), abs=6e-3)
    assert c.r_total == pytest.approx(float(row["R_total_with_films_m2K_W"]), abs=6e-5)
    assert c.u_value == pytest.approx(float(row["U_W_m2K"]), abs=6e-4)


def test_medium_exterior_wall_by_hand():
    """100 mm brick + 50 mm insulation board + wall air space + 19 mm gypsum (ASHRAE ch. 30)."""
    r_layers = 0.1016 / 0.89 + 0.0508 / 0.03 + 0.15 + 0.019 / 0.16
    c_layers = 1920 * 790 * 0.1016 + 43 * 1210 * 0.0508 + 800 * 1090 * 0.019
    c = ashrae_construction("Medium Exterior Wall", exterior=True)
    assert c.r_layers == pytest.approx(r_layers, rel=1e-12)
    assert c.c_total == pytest.approx(c_layers, rel=1e-12)
    assert c.r_total == pytest.approx(0.03 + r_layers + 0.12, rel=1e-12)
    assert c.layers[0].name.startswith("M01")  # far side (outside) first


@pytest.mark.parametrize(
    ("material", "r", "c"),
    [
        ("M01 100mm brick", 0.1016 / 0.89, 1920 * 790 * 0.1016),
        ("M14a 100mm heavyweight concrete", 0.1016 / 1.95, 2240 * 900 * 0.1016),
        ("G01a 19mm gypsum board", 0.019 / 0.16, 800 * 1090 * 0.019),
        ("F04 Wall air space resistance", 0.15, 0.0),
    ],
)
def test_single_layers_by_hand(material, r, c):
    from rczone.construction import ashrae_materials

    m = ashrae_materials()[material]
    assert m.r == pytest.approx(r, rel=1e-12)
    assert m.c == pytest.approx(c, rel=1e-12, abs=1e-12)


def test_interior_and_exterior_films():
    inner = ashrae_construction("Medium Partitions")
    outer = ashrae_construction("Medium Partitions", exterior=True)
    assert inner.r_total - inner.r_layers == pytest.approx(0.24)
    assert outer.r_total - outer.r_layers == pytest.approx(0.15)


def test_surface_scales_by_area():
    c = ashrae_construction("Medium Floor")
    s = Surface("f", "Tf", 20.0, c)
    assert s.resistance == pytest.approx(c.r_total / 20.0)
    assert s.capacity == pytest.approx(c.c_total * 20.0)
    assert Opening("w", "To", 3.0, 2.8).resistance == pytest.approx(1 / 8.4)


def test_unknown_construction_suggests_close_names():
    with pytest.raises(
        ParameterError, match=r"unknown construction 'Medium Partition'.*did you mean 'Medium Partitions'"
    ):
        ashrae_construction("Medium Partition")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(name="x", thickness=0.0, conductivity=1.0), "thickness and conductivity must be > 0"),
        (dict(name="x", thickness=-0.1, conductivity=1.0), "thickness and conductivity must be > 0"),
        (dict(name="x", thickness=0.1, conductivity=0.0), "thickness and conductivity must be > 0"),
        (
            dict(name="x", thickness=0.1, conductivity=1.0, density=-1.0),
            "density and specific heat must be >= 0",
        ),
        (dict(name="x", fixed_r=0.0), "fixed_r must be > 0"),
    ],
)
def test_bad_materials(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Material(**kwargs)


@pytest.mark.parametrize("area", [0.0, -2.0])
def test_non_positive_surface_area(area):
    with pytest.raises(ParameterError, match="area must be > 0"):
        Surface("f", "Tf", area, Construction("c", (Material("m", 0.1, 1.0, 1000.0, 1000.0),)))
