"""The virtual multi-zone building: one floor around the paper's office, as ONE RC network.

Six zones, each with its own air node, VAV box (supply flow ``m_<zone>``, supply
temperature ``Ts_<zone>``) and internal gain ``Q_<zone>``:

========  =====================================================  =========
zone      what                                                   air node
========  =====================================================  =========
target    the studied office (geometry of :func:`office_241`)     ``Ti``
n1, n2    the two side offices, same size as the target          ``Tn1``, ``Tn2``
hw        hallway segment 12 m x 2 m x 3 m in front of the three  ``Thw``
          offices, a door (2 m2) to each
f         the room below the target, same footprint              ``Tf``
c         the room above the target, same footprint              ``Tc``
========  =====================================================  =========

Walls are :mod:`rczone.virtual.walls` ladders (slices <= 2 cm, films and air spaces as
resistors), so the truth has 152 states and no model under test is exact. Each shared
surface (target-n1, target-hw, ...) appears once. Surfaces of the neighbours that face
spaces outside this floor section are **mirror walls**: both faces open to the same zone
(the space beyond is assumed to be an identical room under identical control, so the
wall's mid-plane is adiabatic), which keeps their heat capacity and transient exchange
without inventing further temperatures. Every zone on the facade (target, n1, n2, f, c)
has the target's external wall (9 m2 opaque) and window (3 m2) to the outdoor air ``To``;
the hallway has none. Windows and doors are massless resistors ``1/(U A)``.

The *true* constructions deviate from the nominal ASHRAE ones that :func:`office_241`
(what the modeller believes) uses: each layer's conductivity (or air-space resistance)
is scaled by U(0.85, 1.15) and its density by U(0.95, 1.05), drawn once from
``numpy.random.default_rng(BUILDING_SEED)`` in a fixed order; the window U by U(0.9, 1.1);
the target holds 20 m2 of furniture instead of the nominal 15 m2. Furniture is its own
node (25 mm wood, both faces exposed; resistance film + half thickness to the air), not
lumped with the air. :func:`true_geometry` returns the target's true
:class:`~rczone.construction.room.ZoneGeometry`, from which the "true equivalent"
low-order parameters are computed.

Internal gains (night, unoccupied; assumptions except the target's): target 50 W
constant (the paper: idle PC and printer); n1 50 W, n2 80 W (idle equipment); hallway
40 W (emergency lighting); f and c 60 W.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented
   thermal models of zones in multi-zone buildings", IEEE CDC 2012, section II (zone,
   neighbours, Q = 50 W).
.. [2] ASHRAE Handbook - Fundamentals, 2005, ch. 30 (constructions, films).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cache

import numpy as np

from rczone.construction.materials import FILM_INSIDE, Construction, ashrae_construction
from rczone.construction.room import AIR_CP, AIR_DENSITY, Opening, ZoneGeometry, office_241
from rczone.errors import ParameterError, did_you_mean
from rczone.network import HeatInput, Node, RCNetwork, Resistor, SupplyAir
from rczone.virtual.walls import MAX_SLICE, perturb_construction, wall_ladder

#: Seed of the true-construction deviations (fixed: the building is one building).
BUILDING_SEED = 241
#: Relative spread of the true layer conductivities around the ASHRAE values.
CONDUCTIVITY_SPREAD = 0.15
#: Zones in network order.
ZONES = ("target", "n1", "n2", "hw", "f", "c")
#: Air node (and data column) of each zone.
AIR_NODE = {"target": "Ti", "n1": "Tn1", "n2": "Tn2", "hw": "Thw", "f": "Tf", "c": "Tc"}
#: Night-time internal gain of each zone, W (target: the paper's 50 W).
INTERNAL_GAIN = {"target": 50.0, "n1": 50.0, "n2": 80.0, "hw": 40.0, "f": 60.0, "c": 60.0}
#: Furnishing area (25 mm wood) per zone, m2 (target: true 20 m2 vs nominal 15 m2).
FURNISHING_AREA = {"target": 20.0, "n1": 15.0, "n2": 15.0, "hw": 5.0, "f": 15.0, "c": 15.0}
#: Zone floor area (m2) and height (m).
FLOOR_AREA = {"target": 20.0, "n1": 20.0, "n2": 20.0, "hw": 24.0, "f": 20.0, "c": 20.0}
HEIGHT = 3.0


@dataclass(frozen=True)
class VirtualBuilding:
    """The assembled virtual building.

    Attributes
    ----------
    network : RCNetwork
        Whole floor; boundary ``To``; flows ``m_<zone>``; inputs ``To``, ``Ts_<zone>``, ``Q_<zone>``.
    zones : tuple of str
    air_nodes : dict
        Zone -> air node name.
    gains : dict
        Zone -> internal gain, W.
    target : ZoneGeometry
        True geometry of the target office.
    nominal : ZoneGeometry
        What the modeller believes (:func:`office_241`).
    """

    network: RCNetwork
    zones: tuple[str, ...]
    air_nodes: dict[str, str]
    gains: dict[str, float]
    target: ZoneGeometry
    nominal: ZoneGeometry

    def flow_name(self, zone: str) -> str:
        """Flow input name of ``zone``."""
        return f"m_{zone}"

    def supply_name(self, zone: str) -> str:
        """Supply-temperature input name of ``zone``."""
        return f"Ts_{zone}"

    def gain_name(self, zone: str) -> str:
        """Heat-input name of ``zone``."""
        return f"Q_{zone}"


def _furniture_resistance(c: Construction, area: float) -> float:
    """Air to mid-plane resistance of a slab exposed on both faces, K/W."""
    return (FILM_INSIDE + c.r_layers / 2) / (2 * area)


def true_geometry() -> ZoneGeometry:
    """The target office's true geometry and constructions (deviating from :func:`office_241`)."""
    return build_building().target


@cache
def build_building(max_slice: float = MAX_SLICE) -> VirtualBuilding:
    """Assemble the virtual building (cached: it is immutable).

    Parameters
    ----------
    max_slice : float
        Largest wall slice, m.

    Returns
    -------
    VirtualBuilding
    """
    rng = np.random.default_rng(BUILDING_SEED)
    nominal = office_241()

    def true(c: Construction) -> Construction:
        return perturb_construction(c, rng, CONDUCTIVITY_SPREAD)

    # True target surfaces (fixed order of draws).
    t_surf = tuple(replace(s, construction=true(s.construction)) for s in nominal.surfaces)
    win_u = nominal.window.u_value * float(rng.uniform(0.9, 1.1))
    door_u = nominal.door.u_value * float(rng.uniform(0.9, 1.1)) if nominal.door else 2.0
    furn = true(nominal.furnishing)
    target = ZoneGeometry(
        name="office 241 (virtual building, true)",
        floor_area=FLOOR_AREA["target"],
        height=HEIGHT,
        surfaces=t_surf,
        window=Opening("window", "To", nominal.window.area, win_u),
        door=Opening("door", "Thw", nominal.door.area if nominal.door else 2.0, door_u),
        furnishing=furn,
        furnishing_area=FURNISHING_AREA["target"],
    )

    nodes: list[Node] = []
    resistors: list[Resistor] = []

    def add_wall(prefix: str, c: Construction, area: float, a: str, b: str) -> None:
        lad = wall_ladder(prefix, c, area, a, b, max_slice)
        nodes.extend(lad.nodes)
        resistors.extend(lad.resistors)

    for z in ZONES:
        vol = FLOOR_AREA[z] * HEIGHT
        nodes.insert(ZONES.index(z), Node(AIR_NODE[z], vol * AIR_DENSITY * AIR_CP, f"air of zone {z}"))
    # Target: its six surfaces, window, door.
    node_of = {"To": "To", "Tf": "Tf", "Tc": "Tc", "Tn1": "Tn1", "Tn2": "Tn2", "Thw": "Thw"}
    for s in t_surf:
        add_wall(f"t_{s.name}", s.construction, s.area, node_of[s.far_side], "Ti")
    resistors.append(Resistor("Ti", "To", 1.0 / (win_u * target.window.area)))
    resistors.append(Resistor("Ti", "Thw", 1.0 / (door_u * target.door.area)))  # type: ignore[union-attr]

    ext = ashrae_construction("Medium Exterior Wall", exterior=True)
    part = ashrae_construction("Medium Partitions")
    floor = ashrae_construction("Medium Floor")
    ceil = ashrae_construction("Medium Roof/Ceiling")
    ext_area = nominal.surface("o").area
    win_area = nominal.window.area
    # Facade zones other than the target: external wall and window.
    for z in ("n1", "n2", "f", "c"):
        air = AIR_NODE[z]
        add_wall(f"{z}_o", true(ext), ext_area, "To", air)
        resistors.append(
            Resistor(air, "To", 1.0 / (nominal.window.u_value * float(rng.uniform(0.9, 1.1)) * win_area))
        )
    # Side offices: hallway wall + door, far side wall, floor and ceiling mirrored.
    for z in ("n1", "n2"):
        air = AIR_NODE[z]
        add_wall(f"{z}_hw", true(part), 10.0, "Thw", air)
        resistors.append(Resistor(air, "Thw", 1.0 / (door_u * 2.0)))
        add_wall(f"{z}_side", true(part), 15.0, air, air)
        add_wall(f"{z}_fl", true(floor), 20.0, air, air)
        add_wall(f"{z}_ce", true(ceil), 20.0, air, air)
    # Room below: its floor and three inner walls mirrored; room above: its ceiling and walls.
    add_wall("f_fl", true(floor), 20.0, "Tf", "Tf")
    add_wall("c_ce", true(ceil), 20.0, "Tc", "Tc")
    for z in ("f", "c"):
        air = AIR_NODE[z]
        add_wall(f"{z}_in", true(part), 40.0, air, air)
    # Hallway: opposite wall, floor and ceiling mirrored.
    add_wall("hw_opp", true(part), 36.0, "Thw", "Thw")
    add_wall("hw_fl", true(floor), 24.0, "Thw", "Thw")
    add_wall("hw_ce", true(ceil), 24.0, "Thw", "Thw")
    # Furniture nodes.
    for z in ZONES:
        fc = furn if z == "target" else true(nominal.furnishing)
        a = FURNISHING_AREA[z]
        nodes.append(Node(f"{z}_furn", fc.c_total * a, f"furniture of zone {z}"))
        resistors.append(Resistor(AIR_NODE[z], f"{z}_furn", _furniture_resistance(fc, a)))

    net = RCNetwork(
        "virtual building",
        nodes=nodes,
        boundaries=("To",),
        resistors=resistors,
        heat_inputs=[HeatInput(f"Q_{z}", {AIR_NODE[z]: 1.0}) for z in ZONES],
        supply_air=[SupplyAir(AIR_NODE[z], f"m_{z}", f"Ts_{z}", AIR_CP) for z in ZONES],
        outputs=[AIR_NODE[z] for z in ZONES],
        description="fine-resolution truth of the rczone virtual building",
    )
    return VirtualBuilding(net, ZONES, dict(AIR_NODE), dict(INTERNAL_GAIN), target, nominal)


def check_zone(zone: str) -> str:
    """Validate a zone name."""
    if zone not in ZONES:
        raise ParameterError(f"unknown zone {zone!r}; " + did_you_mean(zone, ZONES))
    return zone
