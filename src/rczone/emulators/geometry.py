"""The zones of an EnergyPlus building and the thermal adjacency read from its surfaces.

EnergyPlus writes what it made of the geometry into ``eplusout.eio`` [1]_: one ``Zone
Information`` line per zone (floor area, volume, height) and, with ``Output:Surfaces:List,
Details``, one ``HeatTransfer Surface`` line per surface under its zone's ``Zone Surfaces`` line:
its construction, the nominal U-value with film coefficients, the net area and the outside
boundary condition (the name of the surface it faces in another zone, for an interzone surface).
Each interzone pair is listed from both sides; it is counted once here, from the side listed
first, so that the conductance ``UA`` between two zones is the sum over the walls, floors and
ceilings they share.

Floors are numbered from the lowest level of the conditioned zones (1) up; a zone belongs to the
highest floor whose level is at or below its own lowest point (a return plenum to the floor it
serves, an attic to the top floor).

References
----------
.. [1] U.S. Department of Energy, *EnergyPlus Output Details and Examples* (eplusout.eio: Zone
   Information, Zone Surfaces, HeatTransfer Surface).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from rczone.errors import EmulatorError

#: Levels closer than this are one floor, m.
LEVEL_TOLERANCE = 0.3


@dataclass(frozen=True)
class Zone:
    """A zone as EnergyPlus sized it.

    Attributes
    ----------
    name : str
    floor : int
        1 for the lowest conditioned level.
    floor_area : float
        m2.
    volume : float
        m3.
    conditioned : bool
        Part of the building's conditioned area (EnergyPlus's "Part of Total Building Area").
    exterior_ua : float
        Conductance of its surfaces to the outdoor air (walls, windows, doors, roofs), W/K.
    window_area : float
        m2.
    """

    name: str
    floor: int
    floor_area: float
    volume: float
    conditioned: bool
    exterior_ua: float
    window_area: float


@dataclass(frozen=True)
class Adjacency:
    """The surfaces two zones share.

    Attributes
    ----------
    a, b : str
        The zones (``a`` is the side listed first).
    area : float
        Net area of the shared surfaces, m2.
    ua : float
        Their conductance with film coefficients, W/K (``U = ua / area``).
    surfaces : tuple of str
        The surfaces on ``a``'s side.
    """

    a: str
    b: str
    area: float
    ua: float
    surfaces: tuple[str, ...]

    @property
    def u_value(self) -> float:
        """Area-weighted U-value, W/(m2 K)."""
        return self.ua / self.area


@dataclass(frozen=True)
class Geometry:
    """Zones and adjacency of a building."""

    zones: tuple[Zone, ...]
    adjacency: tuple[Adjacency, ...]

    def zone(self, name: str) -> Zone:
        """The zone named ``name`` (case-insensitive)."""
        for z in self.zones:
            if z.name.lower() == name.lower():
                return z
        raise KeyError(name)

    def neighbours(self, name: str) -> dict[str, float]:
        """The zones around ``name`` and the conductance to each, W/K."""
        out: dict[str, float] = {}
        for adj in self.adjacency:
            if name in (adj.a, adj.b):
                other = adj.b if adj.a == name else adj.a
                out[other] = out.get(other, 0.0) + adj.ua
        return out


def _rows(text: str, kind: str) -> list[list[str]]:
    return [
        [f.strip() for f in row]
        for row in csv.reader(io.StringIO(text))
        if row and row[0].strip() in (kind, "Zone Surfaces")
    ]


def _floors(levels: Mapping[str, float], conditioned: Sequence[str]) -> dict[str, int]:
    bases: list[float] = []
    for z in sorted(conditioned, key=levels.__getitem__):
        if not bases or levels[z] - bases[-1] > LEVEL_TOLERANCE:
            bases.append(levels[z])
    return {z: max(1, sum(b <= lv + LEVEL_TOLERANCE for b in bases)) for z, lv in levels.items()}


def read_eio(text: str, names: Sequence[str] = ()) -> Geometry:
    """Zones and adjacency from ``eplusout.eio`` text (see the module notes).

    Parameters
    ----------
    text : str
        The eio file.
    names : sequence of str
        The zones' names as the input file spells them (EnergyPlus writes them in capitals).
    """
    spell = {n.upper(): n for n in names}
    info = {}
    for row in _rows(text, "Zone Information"):
        if row[0] == "Zone Information" and len(row) >= 30:
            info[spell.get(row[1], row[1])] = row
    if not info:
        raise EmulatorError("EnergyPlus wrote no zone information into eplusout.eio")
    owner: dict[str, str] = {}
    surfaces = []
    zone = None
    for row in _rows(text, "HeatTransfer Surface"):
        if row[0] == "Zone Surfaces":
            zone = spell.get(row[1], row[1])
        elif zone is not None and len(row) >= 18:
            owner[row[1]] = zone
            surfaces.append((zone, row))
    ext = {z: 0.0 for z in info}
    win = {z: 0.0 for z in info}
    pairs: dict[frozenset, list] = {}
    seen: set[frozenset] = set()
    for zone, row in surfaces:
        name, cls, u, area, bc = row[1], row[2], row[7], float(row[9]), row[17]
        if cls == "Window":
            win[zone] += area
        if bc == "ExternalEnvironment":
            ext[zone] += float(u) * area
        elif bc in owner and bc != name and owner[bc] != zone:
            key = frozenset((name, bc))
            if key in seen:
                continue
            seen.add(key)
            zones_key = frozenset((zone, owner[bc]))
            entry = pairs.setdefault(zones_key, [zone, owner[bc], 0.0, 0.0, []])
            entry[2] += area
            entry[3] += float(u) * area
            entry[4].append(name)
    levels = {z: float(r[16]) for z, r in info.items()}
    conditioned = [z for z, r in info.items() if r[29].lower() == "yes"]
    floor = _floors(levels, conditioned or list(info))
    zones = tuple(
        Zone(z, floor[z], float(r[22]), float(r[19]), z in conditioned, ext[z], win[z])
        for z, r in info.items()
    )
    adjacency = tuple(Adjacency(a, b, area, ua, tuple(s)) for a, b, area, ua, s in pairs.values())
    return Geometry(zones, adjacency)
