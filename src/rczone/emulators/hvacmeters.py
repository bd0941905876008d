"""The HVAC energy of one zone of an EnergyPlus prototype: its own coils and its share of its air loop.

EnergyPlus meters the whole building (``Electricity:HVAC``, ``NaturalGas:HVAC``); a closed-loop
test of one zone is scored on the energy *that zone* costs. :func:`zone_equipment` reads from the
input file, for every conditioned zone,

* its **own** equipment: the coils of its air terminal (the VAV boxes' reheat coils of the medium
  office), counted in full (``reheat``);
* its **air loop** (``AirLoopHVAC``: the branch list's components, and the fans and coils a
  unitary system or heat pump on a branch names) and the other zones that loop serves (through
  its zone splitter and their terminals). The loop's fans (``fan``), cooling coils (``cooling``)
  and heating coils (``heating``) are shared among its zones in proportion to the supply air each
  zone received over the time step (:func:`attribute`), the usual allocation of central-system
  energy to the zones it serves by air-flow share (ASHRAE Handbook [1]_). In the small office each
  zone has its own packaged unit, whose share is one.

The prototypes have no chiller, boiler or pump (DX coils and gas furnaces on the air loops), so
there is no central-plant share. Each component is read through its EnergyPlus output variables
(electric power, the fuel rate of gas coils, DX crankcase and defrost heaters); a variable the
run does not have counts zero. What the building's HVAC meters hold beyond every zone's share is
reported by the plant (``unattributed_kWh``): nothing, to rounding, in the small office (a test
checks it); about 0.45 kW all day in the medium office, outside the air side (the HVAC meter's
excess over EnergyPlus's Fans, Cooling, Heating and Pumps end-use meters, measured).

References
----------
.. [1] ASHRAE Handbook - HVAC Applications (2019), chapter 38 (building energy monitoring:
   sub-metering and the allocation of central-system energy to zones by air flow).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rczone.emulators.idf import IdfObject, ZoneHvac

#: Output variables (W) read for a component, by the start of its class name (first match wins).
VARIABLES = (
    ("Fan:", ("Fan Electricity Rate",)),
    (
        "Coil:Cooling:DX",
        ("Cooling Coil Electricity Rate", "Cooling Coil Crankcase Heater Electricity Rate"),
    ),
    (
        "Coil:Heating:DX",
        (
            "Heating Coil Electricity Rate",
            "Heating Coil Defrost Electricity Rate",
            "Heating Coil Crankcase Heater Electricity Rate",
        ),
    ),
    ("Coil:Heating:Electric", ("Heating Coil Electricity Rate",)),
    ("Coil:Heating:Fuel", ("Heating Coil NaturalGas Rate", "Heating Coil Electricity Rate")),
    ("Coil:Heating:Gas", ("Heating Coil NaturalGas Rate", "Heating Coil Electricity Rate")),
)
#: The energy parts of a zone's HVAC (as the virtual building's scores name them, plus heating).
PARTS = ("fan", "cooling", "heating", "reheat")


@dataclass(frozen=True)
class Component:
    """A fan or coil: its class, name, the part it counts to, and its output variables."""

    kind: str
    name: str
    part: str
    variables: tuple[str, ...]

    def labels(self) -> tuple[str, ...]:
        """Row labels of its variables in an emulation's readings."""
        return tuple(f"hvac:{self.name}:{v}" for v in self.variables)


@dataclass(frozen=True)
class ZoneEquipment:
    """What a zone's HVAC energy is made of (see the module notes).

    Attributes
    ----------
    zone : str
    own : tuple of Component
        Its terminal's coils, counted in full.
    loop : tuple of Component
        Its air loop's fans and coils, shared by flow.
    loop_zones : tuple of str
        Every zone that loop serves (the zone included).
    """

    zone: str
    own: tuple[Component, ...]
    loop: tuple[Component, ...]
    loop_zones: tuple[str, ...]


def _component(obj: IdfObject, *, terminal: bool) -> Component | None:
    for prefix, variables in VARIABLES:
        if obj.kind.lower().startswith(prefix.lower()):
            if terminal:
                part = "reheat"
            elif prefix == "Fan:":
                part = "fan"
            else:
                part = "cooling" if "cooling" in prefix.lower() else "heating"
            return Component(obj.kind, obj.field(0), part, variables)
    return None


def _named(objects: Sequence[IdfObject]) -> dict[str, IdfObject]:
    return {
        o.field(0).lower(): o for o in objects if o.fields and o.kind.lower().startswith(("fan:", "coil:"))
    }


def _equipment_of(obj: IdfObject, named: Mapping[str, IdfObject], *, terminal: bool) -> list[Component]:
    """The fans and coils ``obj`` is, or names in its fields (a unitary system, a terminal)."""
    own = obj.kind.lower().startswith(("fan:", "coil:"))
    found = []
    for f in (obj.field(0),) if own else obj.fields[1:]:
        o = named.get(f.lower())
        if o is not None and (c := _component(o, terminal=terminal)) is not None:
            found.append(c)
    return found


def zone_equipment(objects: Sequence[IdfObject], zones: Sequence[ZoneHvac]) -> dict[str, ZoneEquipment]:
    """Every conditioned zone's equipment read from the input file's objects (see the module notes)."""
    named = _named(objects)
    by_name = {o.field(0).lower(): o for o in objects if o.fields}
    inlet_zone = {n.lower(): z.name for z in zones for n in z.inlets}
    terminals = [o for o in objects if o.kind.lower().startswith("airterminal:")]
    # terminal -> zone (its outlet is a zone inlet) and terminal inlet node -> zone
    term_zone, term_inlet_zone = {}, {}
    for t in terminals:
        z = next((inlet_zone[f.lower()] for f in t.fields if f.lower() in inlet_zone), None)
        if z is not None:
            term_zone[t.field(0).lower()] = z
            for f in t.fields[1:]:
                if f.lower() not in inlet_zone:
                    term_inlet_zone[f.lower()] = z
    own: dict[str, list[Component]] = {z.name: [] for z in zones if z.inlets}
    for t in terminals:
        z = term_zone.get(t.field(0).lower())
        if z is not None:
            own[z] += _equipment_of(t, named, terminal=True)
    loop_of: dict[str, tuple[list[Component], list[str]]] = {}
    splitters = [o for o in objects if o.is_a("AirLoopHVAC:ZoneSplitter")]
    lists = {o.field(0).lower(): o.fields[1:] for o in objects if o.is_a("NodeList")}
    for loop in (o for o in objects if o.is_a("AirLoopHVAC")):
        demand = {n.lower() for f in (loop.field(8),) for n in lists.get(f.lower(), (f,))}
        outlets = [f.lower() for s in splitters if s.field(1).lower() in demand for f in s.fields[2:]]
        served = list(dict.fromkeys(term_inlet_zone[n] for n in outlets if n in term_inlet_zone))
        comps: list[Component] = []
        blist = by_name.get(loop.field(4).lower())
        for bname in blist.fields[1:] if blist is not None else ():
            branch = by_name.get(bname.lower())
            if branch is None or not branch.is_a("Branch"):
                continue
            for i in range(2, len(branch.fields), 4):
                obj = by_name.get(branch.field(i + 1).lower())
                if obj is not None:
                    comps += _equipment_of(obj, named, terminal=False)
        for z in served:
            loop_of[z] = (comps, served)
    out = {}
    for z, c in own.items():
        comps, served = loop_of.get(z, ([], [z]))
        out[z] = ZoneEquipment(z, tuple(c), tuple(comps), tuple(served))
    return out


def requested(equipment: Mapping[str, ZoneEquipment]) -> dict[str, tuple[str, str]]:
    """Every (variable, key) the zones' equipment needs, by row label."""
    out = {}
    for eq in equipment.values():
        for c in (*eq.own, *eq.loop):
            for label, var in zip(c.labels(), c.variables, strict=True):
                out[label] = (var, c.name)
    return out


def _power(rows: Sequence[Mapping[str, float]], c: Component) -> np.ndarray:
    return np.array([sum(r.get(lb, 0.0) for lb in c.labels()) for r in rows])


def attribute(
    rows: Sequence[Mapping[str, float]], eq: ZoneEquipment, inlets: Mapping[str, Sequence[str]]
) -> dict[str, np.ndarray]:
    """A zone's HVAC power per time step by part (W, each of shape (N,)), see the module notes.

    Parameters
    ----------
    rows : sequence of mapping
        The readings of each step (``hvac:<component>:<variable>`` and ``m:<node>``).
    eq : ZoneEquipment
    inlets : mapping of str to sequence of str
        Each zone's inlet nodes (for the flow shares).
    """
    n = len(rows)

    def flow(z: str) -> np.ndarray:
        return np.array([sum(r.get(f"m:{nd}", 0.0) for nd in inlets.get(z, ())) for r in rows])

    mine = flow(eq.zone)
    total = sum((flow(z) for z in eq.loop_zones), np.zeros(n))
    share = np.where(total > 0, mine / np.where(total > 0, total, 1.0), 1.0 / max(1, len(eq.loop_zones)))
    parts = {p: np.zeros(n) for p in PARTS}
    for c in eq.own:
        parts[c.part] += _power(rows, c)
    for c in eq.loop:
        parts[c.part] += share * _power(rows, c)
    return parts
