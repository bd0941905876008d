"""Construction data: materials, layered constructions and zone geometry (ASHRAE method)."""

from rczone.construction.materials import (
    FILM_INSIDE,
    FILM_OUTSIDE,
    Construction,
    Material,
    ashrae_construction,
    ashrae_materials,
    construction_names,
)
from rczone.construction.room import AIR_CP, AIR_DENSITY, Opening, Surface, ZoneGeometry, office_241

__all__ = [
    "AIR_CP",
    "AIR_DENSITY",
    "FILM_INSIDE",
    "FILM_OUTSIDE",
    "Construction",
    "Material",
    "Opening",
    "Surface",
    "ZoneGeometry",
    "ashrae_construction",
    "ashrae_materials",
    "construction_names",
    "office_241",
]
