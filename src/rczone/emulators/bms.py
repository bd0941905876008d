"""An EnergyPlus run as a BMS trend export: noisy, quantized points, column maps, a building file.

What a building-management system logs of a building like the prototypes, every zone time step:

* ``<zone> ZN-T``: every zone's air temperature (plenums and attics too: a BMS of a building with a
  return plenum usually logs it), degF;
* ``<node> SA-T`` and ``<node> SA-F``: discharge temperature (degF) and air flow (L/s of standard
  air, 1.2 kg/m3) of every terminal, i.e. every zone inlet node;
* ``OA-T``: outdoor temperature, degF;
* ``<zone> PWR``: the zone's sub-metered lighting and plug power, kW (people and the sun are not
  metered: they are the model's unmeasured disturbance).

Sensors, as :mod:`rczone.virtual.sensors` has them for the virtual building: temperatures carry
Gaussian noise of 0.05 K and are quantized to 0.1 F; flows carry Gaussian noise of
:data:`FLOW_NOISE_LS` L/s plus :data:`FLOW_NOISE_REL` of the reading (a VAV box's velocity-pressure
sensor), clipped at zero and quantized to 1 L/s; power carries 1 % noise and is quantized to
0.01 kW. All draws come from one seeded generator, so a seed gives the same export.

For each conditioned zone a column map (:doc:`data`) maps these points to the paper's inputs:
``Ti`` its air, ``To``, ``Ts`` and ``m`` its terminal (flows of several terminals summed, the first
one's temperature), ``Q`` its metered power, and ``Tsd`` the mean of its neighbours' air
temperatures weighted by the conductance ``UA`` of the surfaces it shares with each (a linear
combination, so it is an ``expr`` of the map).

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, section II (the inputs To, Tsd, Ts, m, Q).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.emulators.catalog import timezone_name
from rczone.emulators.energyplus import Emulation
from rczone.virtual.sensors import sense_temperature

#: Density of standard air that turns mass flows into the volume flows a VAV box reports, kg/m3.
AIR_DENSITY = 1.2
#: Flow sensor: absolute (L/s) and relative noise, resolution (L/s).
FLOW_NOISE_LS = 2.0
FLOW_NOISE_REL = 0.03
FLOW_QUANT_LS = 1.0
#: Power meter: relative noise and resolution (kW).
POWER_NOISE_REL = 0.01
POWER_QUANT_KW = 0.01
OUTDOOR = "OA-T"


def zone_point(zone: str) -> str:
    return f"{zone} ZN-T"


def supply_points(node: str) -> tuple[str, str]:
    """The discharge temperature and flow points of an inlet node."""
    return f"{node} SA-T", f"{node} SA-F"


def power_point(zone: str) -> str:
    return f"{zone} PWR"


def _f(t_c: np.ndarray) -> np.ndarray:
    return np.round(t_c * 1.8 + 32.0, 1)


def trend(run: Emulation, rng: np.random.Generator) -> pd.DataFrame:
    """The trend export of ``run`` (see the module notes), time stamps in column ``time``."""
    f = run.frame
    n = len(f)
    out = {"time": [t.isoformat() for t in f.index]}
    out[OUTDOOR] = _f(sense_temperature(f["To"].to_numpy(), rng))
    for z in run.zones:
        out[zone_point(z)] = _f(sense_temperature(f[f"Ti:{z}"].to_numpy(), rng))
    for z in run.conditioned:
        for node in run.inlets[z]:
            t_pt, m_pt = supply_points(node)
            out[t_pt] = _f(sense_temperature(f[f"Ts:{node}"].to_numpy(), rng))
            ls = f[f"m:{node}"].to_numpy() / AIR_DENSITY * 1000.0
            noisy = ls + rng.normal(0.0, 1.0, n) * (FLOW_NOISE_LS + FLOW_NOISE_REL * ls)
            out[m_pt] = np.round(np.clip(noisy, 0.0, None) / FLOW_QUANT_LS) * FLOW_QUANT_LS
        kw = f[f"Pel:{z}"].to_numpy() / 1000.0
        noisy = kw * (1.0 + POWER_NOISE_REL * rng.normal(0.0, 1.0, n))
        out[power_point(z)] = np.round(np.clip(noisy, 0.0, None) / POWER_QUANT_KW) * POWER_QUANT_KW
    for c in f.columns:
        if c.startswith("cmd:"):  # set points the test wrote, as the BMS logs its commands
            out[f"{c[4:]} SP"] = _f(f[c].to_numpy())
    return pd.DataFrame(out)


def file_stem(zone: str) -> str:
    """A zone name as a file name (characters other than letters, digits, ``_.-`` become ``_``)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", zone)


def _s(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)  # a TOML basic string


def _q(column: str) -> str:
    return f"`{column}`"


def surroundings(run: Emulation, zone: str) -> dict[str, float]:
    """The zones around ``zone`` and their weights in ``Tsd`` (UA shares, summing to one)."""
    ua = run.geometry.neighbours(zone)
    total = sum(ua.values())
    return {z: v / total for z, v in ua.items()} if total > 0 else {}


def _supply(run: Emulation, zone: str, ts: str, m: str) -> list[str]:
    """Column-map lines of a zone's supply: the first terminal's temperature, the flows summed."""
    nodes = run.inlets[zone]
    flows = [supply_points(n)[1] for n in nodes]
    flow = f"column = {_s(flows[0])}" if len(flows) == 1 else f"expr = {_s(' + '.join(_q(c) for c in flows))}"
    return [
        f'{ts} = {{ column = {_s(supply_points(nodes[0])[0])}, unit = "degF" }}',
        f'{m} = {{ {flow}, unit = "L/s" }}',
    ]


def column_map(run: Emulation, zone: str) -> str:
    """The column map (TOML) of conditioned ``zone`` for ``rczone fit`` (see the module notes)."""
    header = timezone_name(run.utc_offset_h)
    weights = surroundings(run, zone)
    lines = [
        f"# Column map of zone {zone} of the EnergyPlus {run.building} (weather {run.weather}),",
        "# written by `rczone emulate`: the paper's inputs from the BMS points of trend.csv.",
        f"# Tsd: the neighbours' air temperatures weighted by the conductance (UA) shared with {zone}.",
        f"name = {_s(f'{run.building} {zone}')}",
        f"air_density = {AIR_DENSITY}",
        "",
        "[time]",
        'column = "time"',
        'format = "iso"',
        f"timezone = {_s(header)}",
        "",
        "[columns]",
        f'Ti = {{ column = {_s(zone_point(zone))}, unit = "degF" }}',
        f'To = {{ column = {_s(OUTDOOR)}, unit = "degF" }}',
        *_supply(run, zone, "Ts", "m"),
        f'Q = {{ column = {_s(power_point(zone))}, unit = "kW" }}',
    ]
    if weights:
        shown = [round(w, 4) for w in weights.values()]
        shown[-1] = round(1.0 - sum(shown[:-1]), 4)  # the weights add up to one as written
        expr = " + ".join(f"{w:.4f} * {_q(zone_point(z))}" for z, w in zip(weights, shown))
        lines.append(f'Tsd = {{ expr = {_s(expr)}, unit = "degF" }}')
    else:  # no interzone surface: the surroundings are outdoors
        lines.append(f'Tsd = {{ expr = {_s("1 * " + _q(OUTDOOR))}, unit = "degF" }}')
    return "\n".join(lines) + "\n"


def floor_column_map(run: Emulation, floor: int) -> str:
    """The column map (TOML) of the joint model of ``floor`` (``rczone models generate --from``)."""
    from rczone.emulators.floor import alias

    rooms = [z for z in run.conditioned if run.geometry.zone(z).floor == floor]
    around = {n for z in rooms for n in run.geometry.neighbours(z)} - set(rooms)
    lines = [
        f"# Column map of floor {floor} of the EnergyPlus {run.building} for its joint model",
        f"# (rczone models generate --from building.toml --floor {floor}), written by `rczone emulate`.",
        f"name = {_s(f'{run.building} floor {floor}')}",
        f"air_density = {AIR_DENSITY}",
        "",
        "[time]",
        'column = "time"',
        'format = "iso"',
        f"timezone = {_s(timezone_name(run.utc_offset_h))}",
        "",
        "[columns]",
        f'To = {{ column = {_s(OUTDOOR)}, unit = "degF" }}',
    ]
    for z in sorted(around):
        lines.append(f'T{alias(z)} = {{ column = {_s(zone_point(z))}, unit = "degF" }}')
    for z in rooms:
        r = alias(z)
        lines += [
            f'T{r} = {{ column = {_s(zone_point(z))}, unit = "degF" }}',
            *_supply(run, z, f"Ts{r}", f"m{r}"),
            f'Q{r} = {{ column = {_s(power_point(z))}, unit = "kW" }}',
        ]
    return "\n".join(lines) + "\n"


def building_file(run: Emulation, seed: int, test: str) -> str:
    """``building.toml``: the zones, their floors, sizes and files, and the interzone adjacency."""
    g = run.geometry
    lines = [
        "# The building behind trend.csv, written by `rczone emulate` from EnergyPlus's own geometry",
        "# (eplusout.eio). U-values include the film coefficients; ua = u_value * area, W/K.",
        'emulator = "energyplus"',
        f"building = {_s(run.building)}",
        f"weather = {_s(run.weather)}",
        f'start = "{run.start:%m-%d}"',
        f"days = {run.days}",
        f"step_s = {run.step_s:g}",
        f"seed = {seed}",
        f"test = {_s(test)}",
        'trend = "trend.csv"',
    ]
    for z in run.zones:
        geo = g.zone(z)
        lines += [
            "",
            "[[zones]]",
            f"name = {_s(z)}",
            f"floor = {geo.floor}",
            f"floor_area = {geo.floor_area:.2f}",
            f"volume = {geo.volume:.2f}",
            f"conditioned = {'true' if run.inlets[z] else 'false'}",
            f"exterior_ua = {geo.exterior_ua:.2f}",
            f"window_area = {geo.window_area:.2f}",
            f"temperature = {_s(zone_point(z))}",
            f"inlets = [{', '.join(_s(n) for n in run.inlets[z])}]",
        ]
        if run.inlets[z]:
            lines.append(f"columns = {_s(file_stem(z) + '.columns.toml')}")
    for a in g.adjacency:
        lines += [
            "",
            "[[adjacency]]",
            f"a = {_s(a.a)}",
            f"b = {_s(a.b)}",
            f"area = {a.area:.2f}",
            f"u_value = {a.u_value:.4f}",
            f"ua = {a.ua:.2f}",
            f"surfaces = [{', '.join(_s(s) for s in a.surfaces)}]",
        ]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class TrendExport:
    """The files of one export, by name: ``trend.csv``, ``<zone>.columns.toml``, ``building.toml``."""

    files: dict[str, str]


def export(run: Emulation, *, seed: int, test: str = "normal") -> TrendExport:
    """Every file of the export of ``run`` (text by file name), noise drawn with ``seed``."""
    rng = np.random.default_rng(seed)
    files = {"trend.csv": trend(run, rng).to_csv(index=False, float_format="%.6g")}
    for z in run.conditioned:
        files[f"{file_stem(z)}.columns.toml"] = column_map(run, z)
    for floor in sorted({run.geometry.zone(z).floor for z in run.conditioned}):
        files[f"floor{floor}.columns.toml"] = floor_column_map(run, floor)
    files["building.toml"] = building_file(run, seed, test)
    return TrendExport(files)
