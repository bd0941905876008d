"""A multi-zone model from a few lines: rooms, which rooms share a wall, and the heating circuits.

A hand-written model file for four rooms is some fifty lines, each a chance for a typo. The
generator declares the same network from its description:

* every room ``r`` is the family's ``TiTe`` (Bacher & Madsen 2011): room air ``T<r>``
  (``Ci_<r>``) behind ``Rie_<r>`` from its envelope ``Te<r>`` (``Ce_<r>``), which loses heat
  through ``Rea_<r>`` to outdoors ``To``; ``mass=True`` adds an internal medium ``Tm<r>``
  (``Cm_<r>``) behind ``Rim_<r>`` (the ``TiTmTe`` of the family);
* a wall between two adjacent rooms ``a`` and ``b`` is a resistance ``Rw_<a>_<b>`` between their
  air nodes (a massless partition: its capacity is small beside the rooms', as in the RC
  networks of Lin et al. 2012 for the partitions of one floor);
* a heating circuit that serves several rooms is one heat input (W) split over them by heat
  shares: ``s_<circuit>_<r>`` for every room but the last, which takes the rest
  (``1 - s_1 - ...``, a tied parameter), so the shares add up to one by construction; a circuit
  serving one room puts all its heat there;
* ``solar=True`` adds the irradiance ``Ps`` (W/m2) into every room's air through its own
  effective aperture ``Aw_<r>`` (m2; the ``+solar`` option of the family, Bacher & Madsen 2011);
* a *boundary zone* is a neighbouring space that is not modelled but measured (a corridor, the
  flat next door): its temperature is a boundary input like ``To``, and each room that shares a
  wall with it exchanges heat through ``Rb_<r>_<zone>`` (the paper's treatment of the office's
  neighbours, Lin et al. 2012, as inputs).

Everything else (measured rooms, bounds, fixed values) is an ordinary model: the network can be
written as a model file (:func:`rczone.models.model_to_toml`, or ``rczone models generate``) and
edited like any other.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 3 (the room model TiTe).
.. [2] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, section II (rooms coupled through walls).
"""

from __future__ import annotations

import numbers
import re
from collections.abc import Mapping, Sequence

import numpy as np

from rczone import validation
from rczone.errors import ParameterError, did_you_mean
from rczone.models.library import _VALUES
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor

#: Value (SI) and bounds of a wall between two rooms (a partition of some 10 m2 at 1 to 3 W/(m2 K)).
WALL = (0.05, (1e-5, 10.0))
_ROOM_NAME = re.compile(r"[A-Za-z0-9]+")


def _check_rooms(rooms: Sequence[str]) -> tuple[str, ...]:
    rooms = tuple(str(r) for r in rooms)
    if not rooms:
        raise ParameterError("a multi-zone model needs at least one room")
    for r in rooms:
        if not _ROOM_NAME.fullmatch(r):
            raise ParameterError(
                f"room name {r!r}: use letters and digits only (it becomes part of node names)"
            )
    if len(set(rooms)) != len(rooms):
        dup = next(r for r in rooms if rooms.count(r) > 1)
        raise ParameterError(f"room {dup!r} is listed twice")
    return rooms


def _room(name: str, rooms: Sequence[str], where: str) -> str:
    if name not in rooms:
        raise ParameterError(f"{where}: unknown room {name!r}; {did_you_mean(name, rooms)}")
    return name


def _param(name: str, family_name: str) -> Parameter:
    value, bounds, text = _VALUES[family_name]
    kind = "capacitance" if family_name.startswith("C") else "resistance"
    return Parameter(name, kind, value, description=text, bounds=bounds)


def multizone(
    rooms: Sequence[str] | int,
    walls: Sequence[Sequence[str]] = (),
    *,
    circuits: Mapping[str, Sequence[str]] | None = None,
    mass: bool = False,
    measured: Sequence[str] | None = None,
    name: str = "multizone",
    solar: bool = False,
    boundary_zones: Mapping[str, Sequence[str]] | None = None,
) -> RCNetwork:
    """The network of ``rooms`` coupled through ``walls`` and heated by ``circuits`` (see the module notes).

    Parameters
    ----------
    rooms : sequence of str, or int
        Room names (letters and digits), or a number ``n`` for rooms ``1`` to ``n``.
    walls : sequence of (str, str)
        Pairs of rooms that share a wall (the adjacency list).
    circuits : mapping of str to sequence of str, optional
        Heat input name (a data column, W) to the rooms it serves, e.g. ``{"Ph1": ["1", "2"]}``.
        Default: one input ``Q<r>`` per room.
    mass : bool
        Give every room an internal medium node as well.
    measured : sequence of str, optional
        Rooms whose air temperature is measured (the outputs ``T<r>``); default every room.
    name : str
        Name of the model.
    solar : bool
        Solar irradiance ``Ps`` into every room through an aperture ``Aw_<r>``.
    boundary_zones : mapping of str to sequence of str, optional
        Measured neighbouring spaces (a data column each, degC) to the rooms that share a wall
        with them, e.g. ``{"Tcorr": ["1", "2"]}``.

    Returns
    -------
    RCNetwork

    Raises
    ------
    ParameterError
        For an unknown or repeated room, a wall of a room with itself or listed twice, a circuit
        without rooms, or a room heated by two circuits... (one line each, with a hint).
    """
    if isinstance(rooms, (numbers.Number, np.bool_)):  # a count: 1 to 50, not a bool or 2.5
        n = validation.integer(rooms, "rooms", low=1, high=50, besides="room names or ")
        rooms = [str(i) for i in range(1, n + 1)]
    rooms = _check_rooms(validation.name_list(rooms, "rooms"))
    nodes: list[Node] = []
    resistors: list[Resistor] = []
    params: list[Parameter] = []
    for r in rooms:
        nodes += [
            Node(f"T{r}", f"Ci_{r}", f"room {r}: air"),
            Node(f"Te{r}", f"Ce_{r}", f"room {r}: envelope"),
        ]
        resistors += [Resistor(f"T{r}", f"Te{r}", f"Rie_{r}"), Resistor(f"Te{r}", "To", f"Rea_{r}")]
        params += [_param(f"{p}_{r}", p) for p in ("Ci", "Ce", "Rie", "Rea")]
        if mass:
            nodes.append(Node(f"Tm{r}", f"Cm_{r}", f"room {r}: internal medium"))
            resistors.append(Resistor(f"T{r}", f"Tm{r}", f"Rim_{r}"))
            params += [_param(f"Cm_{r}", "Cm"), _param(f"Rim_{r}", "Rim")]
    seen: set[frozenset[str]] = set()
    for pair in walls:
        if len(pair) != 2:
            raise ParameterError(f"a wall joins two rooms, got {list(pair)!r}")
        a, b = (_room(str(x), rooms, "wall") for x in pair)
        if a == b or frozenset((a, b)) in seen:
            raise ParameterError(
                f"wall {a}-{b}: " + ("a room shares no wall with itself" if a == b else "listed twice")
            )
        seen.add(frozenset((a, b)))
        resistors.append(Resistor(f"T{a}", f"T{b}", f"Rw_{a}_{b}"))
        params.append(
            Parameter(
                f"Rw_{a}_{b}",
                "resistance",
                WALL[0],
                description=f"wall between rooms {a} and {b}",
                bounds=WALL[1],
            )
        )
    heat, shares = _circuits(rooms, circuits)
    if solar:
        heat.append(HeatInput("Ps", {f"T{r}": f"Aw_{r}" for r in rooms}, unit="W/m2"))
        params += [
            Parameter(
                f"Aw_{r}",
                "gain",
                2.0,
                unit="m2",
                description=f"solar aperture of room {r}",
                bounds=(0.0, 500.0),
            )
            for r in rooms
        ]
    zones, walls_b, params_b = _boundary_zones(rooms, boundary_zones, {n.name for n in nodes})
    measured = rooms if measured is None else tuple(_room(str(m), rooms, "measured") for m in measured)
    return RCNetwork(
        name,
        nodes,
        ["To", *zones],
        resistors + walls_b,
        params + shares + params_b,
        heat_inputs=heat,
        outputs=[f"T{r}" for r in measured],
        description=f"{len(rooms)} rooms, {len(seen)} walls between them"
        + (", internal mass in each" if mass else "")
        + (", solar gains" if solar else "")
        + (f", measured neighbours {', '.join(zones)}" if zones else ""),
    )


def _boundary_zones(
    rooms: Sequence[str], zones: Mapping[str, Sequence[str]] | None, nodes: set[str]
) -> tuple[list[str], list[Resistor], list[Parameter]]:
    """The boundary temperatures of measured neighbouring spaces, their walls and resistances."""
    names, walls, params = [], [], []
    for zone, served in (zones or {}).items():
        zone = str(zone)
        if not _ROOM_NAME.fullmatch(zone) or zone == "To" or zone in nodes:
            raise ParameterError(
                f"boundary zone {zone!r}: give the name of its temperature column (letters and digits),"
                " other than To and the rooms' nodes"
            )
        served = [_room(str(r), rooms, f"boundary zone {zone}") for r in served]
        if not served or len(set(served)) != len(served):
            raise ParameterError(f"boundary zone {zone}: give the rooms it shares a wall with, each once")
        names.append(zone)
        for r in served:
            walls.append(Resistor(f"T{r}", zone, f"Rb_{r}_{zone}"))
            params.append(
                Parameter(
                    f"Rb_{r}_{zone}",
                    "resistance",
                    WALL[0],
                    description=f"wall between room {r} and {zone} (measured)",
                    bounds=WALL[1],
                )
            )
    return names, walls, params


def _circuits(
    rooms: Sequence[str], circuits: Mapping[str, Sequence[str]] | None
) -> tuple[list[HeatInput], list[Parameter]]:
    """The heat inputs of the circuits and their share parameters (the last room's share is the rest)."""
    if circuits is None:
        return [HeatInput(f"Q{r}", {f"T{r}": 1.0}) for r in rooms], []
    heat, params = [], []
    for circuit, served in circuits.items():
        served = [_room(str(r), rooms, f"circuit {circuit}") for r in served]
        if not served or len(set(served)) != len(served):
            raise ParameterError(f"circuit {circuit}: give the rooms it serves, each once")
        if len(served) == 1:
            heat.append(HeatInput(circuit, {f"T{served[0]}": 1.0}))
            continue
        names = [f"s_{circuit}_{r}" for r in served[:-1]]
        params += [
            Parameter(
                n, "gain", 1.0 / len(served), description=f"share of {circuit} in room {r}", bounds=(0.0, 1.0)
            )
            for n, r in zip(names, served)
        ]
        last = f"s_{circuit}_{served[-1]}"
        params.append(
            Parameter(
                last,
                "gain",
                expr="1 - " + " - ".join(names),
                description=f"share of {circuit} in room {served[-1]}",
            )
        )
        heat.append(HeatInput(circuit, {f"T{r}": f"s_{circuit}_{r}" for r in served}))
    return heat, params
