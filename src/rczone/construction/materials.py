"""Building materials, layers and constructions: per-area resistance and capacity.

The ASHRAE method (Handbook of Fundamentals, ch. 30 materials and constructions):
a layer of thickness ``d`` (m), conductivity ``k`` (W/(m K)), density ``rho`` (kg/m3) and
specific heat ``c`` (J/(kg K)) has the per-area resistance ``d / k`` (m2 K/W) and capacity
``rho c d`` (J/(m2 K)); an air space has a fixed resistance and no capacity. Surface film
resistances are added on both sides.

References
----------
.. [1] ASHRAE Handbook - Fundamentals, 2005, chapter 30, tables 19 and 22 (data transcribed by
   NREL/EnergyPlus, ``ASHRAE_2005_HOF_Materials.idf``; see ``data/PROVENANCE.md``).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import cache
from importlib import resources

from rczone.errors import ParameterError, did_you_mean

#: Still-air inside surface film resistance, m2 K/W (ASHRAE, vertical surface).
FILM_INSIDE = 0.12
#: Outside surface film resistance at 24 km/h wind, m2 K/W.
FILM_OUTSIDE = 0.03


@dataclass(frozen=True)
class Material:
    """A homogeneous layer (``fixed_r`` set for an air space: no capacity)."""

    name: str
    thickness: float = 0.0
    conductivity: float | None = None
    density: float = 0.0
    specific_heat: float = 0.0
    fixed_r: float | None = None

    def __post_init__(self) -> None:
        if self.fixed_r is None:
            if not (self.thickness > 0 and self.conductivity and self.conductivity > 0):
                raise ParameterError(
                    f"material {self.name!r}: thickness and conductivity must be > 0"
                    " (or give fixed_r for an air space)"
                )
            if self.density < 0 or self.specific_heat < 0:
                raise ParameterError(f"material {self.name!r}: density and specific heat must be >= 0")
        elif self.fixed_r <= 0:
            raise ParameterError(f"material {self.name!r}: fixed_r must be > 0")

    @property
    def r(self) -> float:
        """Resistance per area, m2 K/W."""
        return self.fixed_r if self.fixed_r is not None else self.thickness / self.conductivity  # type: ignore[operator]

    @property
    def c(self) -> float:
        """Heat capacity per area, J/(m2 K)."""
        return 0.0 if self.fixed_r is not None else self.density * self.specific_heat * self.thickness


@dataclass(frozen=True)
class Construction:
    """Layers from the far side (``outside``) to the room side, with surface films.

    Parameters
    ----------
    name : str
    layers : tuple of Material
        Far side first.
    film_out, film_in : float
        Surface film resistances on the far side and the room side, m2 K/W.
    """

    name: str
    layers: tuple[Material, ...]
    film_out: float = FILM_INSIDE
    film_in: float = FILM_INSIDE

    @property
    def r_layers(self) -> float:
        """Sum of the layer resistances, m2 K/W (no films)."""
        return sum(m.r for m in self.layers)

    @property
    def r_total(self) -> float:
        """Air-to-air resistance including both films, m2 K/W."""
        return self.film_out + self.r_layers + self.film_in

    @property
    def c_total(self) -> float:
        """Heat capacity per area, J/(m2 K)."""
        return sum(m.c for m in self.layers)

    @property
    def u_value(self) -> float:
        """Thermal transmittance, W/(m2 K)."""
        return 1.0 / self.r_total

    def with_films(self, film_out: float, film_in: float = FILM_INSIDE) -> Construction:
        """A copy with other film resistances (e.g. an exterior surface)."""
        return Construction(self.name, self.layers, film_out, film_in)


def _read_csv(name: str) -> list[dict[str, str]]:
    with resources.files("rczone.construction").joinpath("data", name).open(encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _num(s: str) -> float | None:
    return float(s) if s.strip() else None


@cache
def ashrae_materials() -> dict[str, Material]:
    """The ASHRAE ch. 30 materials shipped with rczone, by name (e.g. ``"M01 100mm brick"``)."""
    out = {}
    for row in _read_csv("materials_ch30.csv"):
        out[row["name"]] = Material(
            name=row["name"],
            thickness=_num(row["thickness_m"]) or 0.0,
            conductivity=_num(row["conductivity_W_mK"]),
            density=_num(row["density_kg_m3"]) or 0.0,
            specific_heat=_num(row["specific_heat_J_kgK"]) or 0.0,
            fixed_r=_num(row["fixed_R_m2K_W"]),
        )
    return out


@cache
def _constructions() -> dict[str, tuple[str, ...]]:
    return {
        r["construction"]: tuple(r["layers_outside_to_inside"].split("|"))
        for r in _read_csv("constructions_ch30.csv")
    }


def ashrae_construction(name: str, exterior: bool = False) -> Construction:
    """An ASHRAE ch. 30 construction by name (``"Medium Partitions"``...).

    Parameters
    ----------
    name : str
    exterior : bool
        If True, the far-side film is the outside film (wind), else the still-air film.
    """
    table = _constructions()
    if name not in table:
        raise ParameterError(f"unknown construction {name!r}; " + did_you_mean(name, table))
    mats = ashrae_materials()
    return Construction(
        name, tuple(mats[m] for m in table[name]), FILM_OUTSIDE if exterior else FILM_INSIDE, FILM_INSIDE
    )


def construction_names() -> tuple[str, ...]:
    """Names of the shipped constructions."""
    return tuple(_constructions())
