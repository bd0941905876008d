"""Zone geometry: the surfaces of a room, what lies beyond each, and their constructions.

:func:`office_241` describes the office the paper studies (Pugh Hall room 241: one external
wall with a window, two side offices, a hallway with a door, a room below and one above).
The paper gives no dimensions; the values below are a typical single office and are the
documented assumptions behind every construction value rczone derives for it.
"""

from __future__ import annotations

from dataclasses import dataclass

from rczone.construction.materials import Construction, ashrae_construction
from rczone.errors import ParameterError

#: Density of room air, kg/m3 (20 degC, sea level).
AIR_DENSITY = 1.2
#: Specific heat of air, J/(kg K).
AIR_CP = 1005.0


@dataclass(frozen=True)
class Surface:
    """One opaque surface of the zone.

    Parameters
    ----------
    name : str
        Short name used in parameter names (``"o"``, ``"f"``, ``"c"``, ``"n1"``, ``"n2"``, ``"hw"``).
    far_side : str
        Input name of the temperature beyond the surface (``"To"``, ``"Tf"``, ...).
    area : float
        Net area, m2 (window and door excluded).
    construction : Construction
        Layers from the far side to the room.
    """

    name: str
    far_side: str
    area: float
    construction: Construction

    def __post_init__(self) -> None:
        if not self.area > 0:
            raise ParameterError(f"surface {self.name!r}: area must be > 0 m2, got {self.area!r}")

    @property
    def resistance(self) -> float:
        """Air-to-air resistance including films, K/W."""
        return self.construction.r_total / self.area

    @property
    def capacity(self) -> float:
        """Heat capacity, J/K."""
        return self.construction.c_total * self.area


@dataclass(frozen=True)
class Opening:
    """A window or door: a massless element between the room and ``far_side``.

    Parameters
    ----------
    u_value : float
        Air-to-air transmittance including films, W/(m2 K).
    """

    name: str
    far_side: str
    area: float
    u_value: float

    @property
    def resistance(self) -> float:
        """K/W."""
        return 1.0 / (self.u_value * self.area)


@dataclass(frozen=True)
class ZoneGeometry:
    """A zone: floor area, height, surfaces, openings and furnishing.

    Parameters
    ----------
    furnishing_area : float
        Area of furnishings exchanging heat quickly with the air (desks, shelves), m2 of
        the ``furnishing`` construction; their capacity is lumped with the air into ``Cr``.
    """

    name: str
    floor_area: float
    height: float
    surfaces: tuple[Surface, ...]
    window: Opening
    door: Opening | None
    furnishing: Construction
    furnishing_area: float

    @property
    def air_capacity(self) -> float:
        """Heat capacity of the room air, J/K."""
        return self.floor_area * self.height * AIR_DENSITY * AIR_CP

    @property
    def room_capacity(self) -> float:
        """Air plus furnishings: the construction value of ``Cr``, J/K."""
        return self.air_capacity + self.furnishing.c_total * self.furnishing_area

    def surface(self, name: str) -> Surface:
        """The surface called ``name``."""
        for s in self.surfaces:
            if s.name == name:
                return s
        raise ParameterError(
            f"zone {self.name!r} has no surface {name!r}; known: {[s.name for s in self.surfaces]}"
        )


def office_241() -> ZoneGeometry:
    """The paper's office (Pugh Hall room 241, University of Florida), as rczone assumes it.

    Assumptions (the paper gives none of these numbers):

    * 4 m wide (external wall and hallway side) x 5 m deep x 3 m high: 20 m2, 60 m3.
    * External wall 12 m2 gross with a 3 m2 double-glazed window, U = 2.8 W/(m2 K)
      (typical ASHRAE value for double glazing in an aluminium frame); opaque part
      "Medium Exterior Wall" (brick, insulation, air space, gypsum) with outside film.
    * Side walls to the two neighbouring offices, 15 m2 each, "Medium Partitions".
    * Hallway wall 12 m2 gross with a 2 m2 door of 25 mm wood (U from the layer plus two
      still-air films), opaque part "Medium Partitions".
    * Floor (room below) and ceiling (room above) 20 m2, "Medium Floor" and
      "Medium Roof/Ceiling" with still-air films on both sides.
    * Furnishings: 15 m2 of 25 mm wood ("Furnishings (all)").

    With these, the aggregated wall resistance is about 0.008 K/W and ``Cr`` about
    4.5e5 J/K, the same order as the paper's forced-response estimates (Table II).
    """
    door_c = ashrae_construction("Furnishings (all)")
    return ZoneGeometry(
        name="office 241",
        floor_area=20.0,
        height=3.0,
        surfaces=(
            Surface("o", "To", 9.0, ashrae_construction("Medium Exterior Wall", exterior=True)),
            Surface("f", "Tf", 20.0, ashrae_construction("Medium Floor")),
            Surface("c", "Tc", 20.0, ashrae_construction("Medium Roof/Ceiling")),
            Surface("n1", "Tn1", 15.0, ashrae_construction("Medium Partitions")),
            Surface("n2", "Tn2", 15.0, ashrae_construction("Medium Partitions")),
            Surface("hw", "Thw", 10.0, ashrae_construction("Medium Partitions")),
        ),
        window=Opening("window", "To", 3.0, 2.8),
        door=Opening("door", "Thw", 2.0, door_c.u_value),
        furnishing=door_c,
        furnishing_area=15.0,
    )
