"""The joint model of one floor, generated from ``building.toml`` (``rczone models generate --from``).

Every conditioned zone ``r`` of the floor is a room of the network, named by its letters and
digits (``Perimeter_bot_ZN_1`` -> ``PerimeterbotZN1``, as model names allow):

* its air and furnishings ``T<r>`` (``Ci_<r>``) and the mass of its constructions ``Tm<r>``
  (``Cm_<r>``) behind ``Rim_<r>``, the two capacitances of ISO 13790's simple hourly method [2]_;
* ``Rwin_<r>`` from ``T<r>`` to the outdoor air ``To`` when the zone has exterior surfaces (walls,
  windows and roof lumped, as the paper's ``Rwin`` [1]_);
* ``Rw_<a>_<b>`` between two zones of the floor that share surfaces, and ``Rb_<r>_<n>`` from
  ``T<r>`` to the measured temperature ``T<n>`` of a neighbour off the floor (a plenum, an attic,
  a zone of the next floor), which is then an input;
* its terminal's supply air ``m<r> cp (Ts<r> - T<r>)`` and its metered heat ``Q<r>``.

Prior values come from the building file where it gives them: every conductance between zones
and to outdoors is EnergyPlus's ``UA`` of the surfaces (``R = 1 / UA``), the room's capacitance
is its air volume times five (furnishings), the mass ``165 kJ/(m2 K)`` of floor area and
``Rim = 1 / (9.1 W/(m2 K) x 2.5 Af)`` (ISO 13790's medium class). Bounds are a factor 100 either
way, so a fit can move far from the prior.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, section II.
.. [2] ISO 13790:2008, *Energy performance of buildings - Calculation of energy use for space
   heating and cooling*, section 12.2 and table 12 (the 5R1C model, medium class).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping

from rczone.emulators.geometry import Zone
from rczone.errors import DataError, ParameterError, did_you_mean
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

#: Air density (kg/m3) and specific heat (J/(kg K)); furnishings as a multiple of the air.
RHO_CP = 1.2 * 1005.0
FURNISHING = 5.0
#: ISO 13790 medium class: mass per floor area, J/(m2 K); mass area per floor area; h_ms, W/(m2 K).
CM_PER_AREA = 165e3
AM_PER_AREA = 2.5
H_MS = 9.1
#: Bounds: prior divided and multiplied by this.
SPREAD = 100.0


def alias(zone: str) -> str:
    """A zone's name in a floor model: its letters and digits."""
    return re.sub(r"[^A-Za-z0-9]", "", zone)


def _number(d: Mapping, key: str, where: str, source: str) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 0:
        raise DataError(f"{source}: {where} needs {key} as a number >= 0, got {v!r}")
    return float(v)


def read_building(doc: Mapping, source: str) -> tuple[dict[str, Zone], list[tuple[str, str, float]]]:
    """The zones and the adjacency ``(a, b, ua)`` of a parsed ``building.toml``; one line if malformed."""
    zones_doc, adj_doc = doc.get("zones"), doc.get("adjacency", [])
    if not isinstance(zones_doc, list) or not zones_doc or not isinstance(adj_doc, list):
        raise DataError(
            f"{source}: not a building file of rczone emulate ([[zones]] and [[adjacency]] tables)"
        )
    zones = {}
    for i, z in enumerate(zones_doc):
        where = f"zone {i + 1}"
        if not isinstance(z, Mapping) or not isinstance(z.get("name"), str) or not z["name"]:
            raise DataError(f"{source}: {where} needs a name")
        floor = z.get("floor")
        if isinstance(floor, bool) or not isinstance(floor, int):
            raise DataError(f"{source}: zone {z['name']!r} needs floor as a whole number")
        area, volume, ext = (
            _number(z, k, f"zone {z['name']!r}", source) for k in ("floor_area", "volume", "exterior_ua")
        )
        window = _number(z, "window_area", f"zone {z['name']!r}", source) if "window_area" in z else 0.0
        zones[z["name"]] = Zone(z["name"], floor, area, volume, bool(z.get("conditioned")), ext, window)
    adjacency = []
    for i, a in enumerate(adj_doc):
        if not isinstance(a, Mapping) or a.get("a") not in zones or a.get("b") not in zones:
            raise DataError(f"{source}: adjacency {i + 1} must name two zones of [[zones]] as a and b")
        adjacency.append((a["a"], a["b"], _number(a, "ua", f"adjacency {i + 1}", source)))
    return zones, adjacency


def _p(name: str, kind: str, value: float, text: str) -> Parameter:
    return Parameter(name, kind, value, description=text, bounds=(value / SPREAD, value * SPREAD))


def _room(z: Zone) -> tuple[list[Node], list[Resistor], list[Parameter]]:
    r = alias(z.name)
    nodes = [
        Node(f"T{r}", f"Ci_{r}", f"{z.name}: air and furnishings"),
        Node(f"Tm{r}", f"Cm_{r}", f"{z.name}: mass"),
    ]
    res = [Resistor(f"T{r}", f"Tm{r}", f"Rim_{r}")]
    params = [
        _p(f"Ci_{r}", "capacitance", RHO_CP * z.volume * FURNISHING, f"{z.name}: air x {FURNISHING:g}"),
        _p(f"Cm_{r}", "capacitance", CM_PER_AREA * z.floor_area, f"{z.name}: ISO 13790 medium mass"),
        _p(f"Rim_{r}", "resistance", 1.0 / (H_MS * AM_PER_AREA * z.floor_area), f"{z.name}: air to mass"),
    ]
    if z.exterior_ua > 0:
        res.append(Resistor(f"T{r}", "To", f"Rwin_{r}"))
        params.append(_p(f"Rwin_{r}", "resistance", 1.0 / z.exterior_ua, f"{z.name}: to outdoors (1/UA)"))
    return nodes, res, params


def floor_model(
    doc: Mapping, floor: int, *, source: str = "building.toml", name: str | None = None
) -> RCNetwork:
    """The joint network of the conditioned zones of ``floor`` (see the module notes).

    Parameters
    ----------
    doc : mapping
        The parsed ``building.toml`` of ``rczone emulate``.
    floor : int
        1 for the lowest floor.
    source : str
        The file's name, for messages.
    name : str, optional
        Name of the model (default ``<building>-floor<N>``).

    Returns
    -------
    RCNetwork

    Raises
    ------
    DataError
        A malformed building file.
    ParameterError
        A floor with no conditioned zone (naming the floors that have some).
    """
    zones, adjacency = read_building(doc, source)
    rooms = [z for z in zones.values() if z.floor == floor and z.conditioned]
    if not rooms:
        floors = sorted({str(z.floor) for z in zones.values() if z.conditioned})
        raise ParameterError(
            f"--floor {floor}: {source} has no conditioned zone there; {did_you_mean(str(floor), floors)}"
        )
    if len({alias(z.name) for z in rooms}) != len(rooms):
        raise DataError(f"{source}: two zones of floor {floor} have the same letters and digits")
    on_floor = {z.name for z in rooms}
    nodes, resistors, params, boundaries = [], [], [], ["To"]
    for z in rooms:
        n, r, p = _room(z)
        nodes, resistors, params = nodes + n, resistors + r, params + p
    for a, b, ua in adjacency:
        if ua <= 0 or not ({a, b} & on_floor):
            continue
        if {a, b} <= on_floor:
            x, y = alias(a), alias(b)
            resistors.append(Resistor(f"T{x}", f"T{y}", f"Rw_{x}_{y}"))
            params.append(_p(f"Rw_{x}_{y}", "resistance", 1.0 / ua, f"between {a} and {b} (1/UA)"))
            continue
        inside, other = (zones[a], zones[b]) if a in on_floor else (zones[b], zones[a])
        x, y = alias(inside.name), alias(other.name)
        if f"T{y}" not in boundaries:
            boundaries.append(f"T{y}")
        resistors.append(Resistor(f"T{x}", f"T{y}", f"Rb_{x}_{y}"))
        params.append(_p(f"Rb_{x}_{y}", "resistance", 1.0 / ua, f"{inside.name} to {other.name} (1/UA)"))
    label = name or f"{doc.get('building', 'building')}-floor{floor}"
    return RCNetwork(
        label,
        nodes,
        boundaries,
        resistors,
        params,
        heat_inputs=[HeatInput(f"Q{alias(z.name)}", {f"T{alias(z.name)}": 1.0}) for z in rooms],
        supply_air=[
            SupplyAir(f"T{alias(z.name)}", flow=f"m{alias(z.name)}", temperature=f"Ts{alias(z.name)}")
            for z in rooms
        ],
        outputs=[f"T{alias(z.name)}" for z in rooms],
        description=f"floor {floor} of {doc.get('building', 'a building')}: {len(rooms)} zones, from {source}",
    )


def floor_model_file(path: str | os.PathLike, floor: int) -> RCNetwork:
    """:func:`floor_model` of the building file at ``path``."""
    from rczone.files.text import read_toml

    return floor_model(read_toml(path, "building file"), floor, source=os.fspath(path))
