"""Reading and editing EnergyPlus input files (IDF) as lists of objects.

An IDF file is a sequence of objects ``Class, field, field, ...;`` with ``!`` comments [1]_. The
prototypes are read into :class:`IdfObject` records, the run period, the time step and the
reports are replaced, and the file is written back for EnergyPlus to read. The zones and the
nodes through which the air of each zone's terminals enters (its *inlet nodes*, where a BMS reads
the discharge temperature and flow) are read from ``ZoneHVAC:EquipmentConnections`` and
``NodeList`` objects.

References
----------
.. [1] U.S. Department of Energy, *EnergyPlus Input Output Reference* (IDF syntax; RunPeriod,
   Timestep, ZoneHVAC:EquipmentConnections, NodeList, Output:Surfaces:List).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class IdfObject:
    """One object: its class (as written) and its fields (comments and blanks around them removed)."""

    kind: str
    fields: tuple[str, ...]

    def is_a(self, kind: str) -> bool:
        """Whether the object is of class ``kind`` (IDF class names are case-insensitive)."""
        return self.kind.lower() == kind.lower()

    def field(self, i: int) -> str:
        """Field ``i`` (0 is the name), or ``""`` when the object has fewer."""
        return self.fields[i] if i < len(self.fields) else ""


def parse_idf(text: str) -> tuple[IdfObject, ...]:
    """The objects of IDF ``text`` in order."""
    body = "\n".join(line.split("!", 1)[0] for line in text.splitlines())
    out = []
    for chunk in body.split(";"):
        parts = [p.strip() for p in chunk.split(",")]
        if parts[0]:
            out.append(IdfObject(parts[0], tuple(parts[1:])))
    return tuple(out)


def write_idf(objects: Iterable[IdfObject]) -> str:
    """IDF text of ``objects``, one field a line."""
    return "".join(",\n    ".join((o.kind, *o.fields)) + ";\n\n" for o in objects)


#: Classes dropped from a prototype before a run: its run periods, time step and reports (the
#: emulator asks for what it reads through the API; the tabular reports cost a second a run).
DROPPED = frozenset(
    c.lower()
    for c in (
        "RunPeriod",
        "Timestep",
        "Output:Table:SummaryReports",
        "Output:Table:Monthly",
        "OutputControl:Table:Style",
        "Output:SQLite",
        "Output:Variable",
        "Output:Meter",
        "Output:Meter:MeterFileOnly",
        "Output:VariableDictionary",
        "Output:Surfaces:Drawing",
        "OutputControl:Files",
    )
)


def for_run(
    objects: Sequence[IdfObject],
    start: dt.date,
    last: dt.date,
    steps_per_hour: int,
    report: Sequence[str] = (),
) -> tuple[IdfObject, ...]:
    """The prototype's objects set up for one run from ``start`` to ``last`` (whole days).

    The weather file's holidays and daylight saving period are not used (the prototype's own
    ``RunPeriodControl`` objects stay); ``Output:Surfaces:List, Details`` writes the surfaces with
    their zones, areas and U-values into ``eplusout.eio``; every name in ``report`` is written as
    an ``Output:Variable`` of every key at each time step into ``eplusout.csv`` (for checks).
    """
    kept = [o for o in objects if o.kind.lower() not in DROPPED]
    run = IdfObject(
        "RunPeriod",
        (
            "rczone",
            str(start.month),
            str(start.day),
            str(start.year),
            str(last.month),
            str(last.day),
            str(last.year),
            "",
            "No",
            "No",
            "Yes",
            "Yes",
            "Yes",
        ),
    )
    added = [
        run,
        IdfObject("Timestep", (str(steps_per_hour),)),
        IdfObject("Output:Surfaces:List", ("Details",)),
    ]
    added += [IdfObject("Output:Variable", ("*", name, "Timestep")) for name in report]
    if report:  # CSV written by EnergyPlus itself (no ReadVarsESO)
        added.append(IdfObject("OutputControl:Files", ("Yes",)))
    return (*kept, *added)


@dataclass(frozen=True)
class ZoneHvac:
    """A zone and the inlet nodes of its air terminals.

    Attributes
    ----------
    name : str
        As the input file writes it.
    inlets : tuple of str
        Nodes whose air enters the zone (empty for an unconditioned zone: a plenum, an attic).
    """

    name: str
    inlets: tuple[str, ...]


def zones(objects: Sequence[IdfObject]) -> tuple[ZoneHvac, ...]:
    """The zones in input order with their inlet nodes (resolving ``NodeList`` names)."""
    lists = {o.field(0).lower(): tuple(f for f in o.fields[1:] if f) for o in objects if o.is_a("NodeList")}
    inlets: dict[str, tuple[str, ...]] = {}
    for o in objects:
        if o.is_a("ZoneHVAC:EquipmentConnections"):
            node = o.field(2)
            inlets[o.field(0).lower()] = lists.get(node.lower(), (node,) if node else ())
    return tuple(ZoneHvac(o.field(0), inlets.get(o.field(0).lower(), ())) for o in objects if o.is_a("Zone"))
