"""IDF objects: read, edited for a run, written back; zones and their inlet nodes."""

from __future__ import annotations

import datetime as dt

from rczone.emulators.idf import IdfObject, for_run, parse_idf, write_idf, zones

TEXT = """
! a comment
Version, 25.2;
Zone, Core, 0;  ! trailing comment
Zone, Plenum;
RunPeriod, old, 1, 1, , 12, 31;
Timestep, 4;
NodeList, Core Inlets, Node A, Node B;
ZoneHVAC:EquipmentConnections, Core, Core Eq, Core Inlets, , Core Air Node, Core Return;
"""


def test_objects_are_read_in_order_without_comments():
    objs = parse_idf(TEXT)
    assert [o.kind for o in objs][:3] == ["Version", "Zone", "Zone"]
    assert objs[1].fields == ("Core", "0")
    assert parse_idf(write_idf(objs)) == objs


def test_zones_resolve_their_node_lists():
    found = zones(parse_idf(TEXT))
    assert [(z.name, z.inlets) for z in found] == [("Core", ("Node A", "Node B")), ("Plenum", ())]


def test_a_run_replaces_the_run_period_and_the_time_step():
    objs = for_run(
        parse_idf(TEXT), dt.date(2017, 3, 4), dt.date(2017, 3, 5), 12, report=["Zone Mean Air Temperature"]
    )
    periods = [o for o in objs if o.is_a("RunPeriod")]
    assert len(periods) == 1 and periods[0].fields[1:7] == ("3", "4", "2017", "3", "5", "2017")
    assert [o.fields for o in objs if o.is_a("Timestep")] == [("12",)]
    assert IdfObject("Output:Variable", ("*", "Zone Mean Air Temperature", "Timestep")) in objs
