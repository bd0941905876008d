"""``rczone emulate --list``: the prototype buildings, their zones and the weather files."""

from __future__ import annotations

from rczone.emulators import catalog, idf


def building_zones(name: str) -> tuple[idf.ZoneHvac, ...]:
    """The zones of prototype ``name`` with their inlet nodes, read from its input file."""
    path = catalog.building_file(name)
    return idf.zones(idf.parse_idf(path.read_text(encoding="latin-1")))


def listing(building: str | None = None) -> str:
    """Text listing every building (or the zones of ``building``) and every weather file."""
    lines = []
    if building is None:
        lines.append("buildings (--building), ASHRAE 90.1-2019 prototypes:")
        for name in catalog.buildings():
            zones = building_zones(name)
            n_cond = sum(bool(z.inlets) for z in zones)
            lines.append(f"  {name}: {len(zones)} zones ({n_cond} with air terminals)")
        lines.append("  (--building NAME --list shows its zones)")
    else:
        lines.append(f"zones of {building} (* no air terminal: plenum, attic):")
        for z in building_zones(building):
            lines.append(f"  {z.name}{'' if z.inlets else ' *'}")
    lines.append("weather files (--weather), TMY3:")
    for name, path in catalog.weather_files().items():
        h = catalog.read_header(path)
        lines.append(f"  {name}: {h.city}, UTC{h.utc_offset_h:+g} h, {h.first:%m-%d} to {h.last:%m-%d}")
    return "\n".join(lines) + "\n"
