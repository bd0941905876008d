"""Multi-zone forced-response nights of the virtual building: several zones excited at once.

A joint model of two adjacent zones can tell their shared wall apart from everything else only
if the two air temperatures move *independently*: with one zone forced and its neighbour under a
thermostat, the neighbour is an almost constant boundary and the partition is seen from one side.
:func:`generate_multizone_night` forces every zone in ``excited`` with its own
:func:`~rczone.virtual.scenarios.forced_schedule` (own random stream, block lengths 60-150 min,
and a different starting phase of the cold / hot / min cycle, so that no two zones are heated or
cooled in step), while the other zones stay under their thermostats. Everything else (weather,
controllers of the other zones, AHU drift, sensors, warm-up) is as in
:func:`~rczone.virtual.scenarios.generate_night`.

Output columns (temperatures degC, one row per minute): ``time`` (s from 6 pm), the air
temperatures of all six zones ``Ti``, ``Tn1``, ``Tn2``, ``Thw``, ``Tf``, ``Tc``, the outdoor
``To``, then per excited zone its supply temperature, flow (kg/s) and internal gain (W, the
building's constant night gain, not measured but known): ``Ts``, ``m``, ``Q`` for the target and
``Ts_<zone>``, ``m_<zone>``, ``Q_<zone>`` for the others. ``Ts`` and ``m`` of row k are held over
``[time[k], time[k] + 60 s)``; temperatures are sensed at ``time[k]``.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, section III (the forced-response test
   of one zone, with its neighbours as measured inputs).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rczone.errors import ParameterError
from rczone.virtual.building import AIR_NODE, ZONES, build_building, check_zone
from rczone.virtual.control import SEASONS
from rczone.virtual.emulator import run
from rczone.virtual.scenarios import NIGHT, SAMPLE, forced_schedule
from rczone.virtual.sensors import sense_flow, sense_temperature
from rczone.virtual.weather import check_season

#: Air-temperature columns, in zone order.
AIR_COLUMNS = tuple(AIR_NODE[z] for z in ZONES)
#: Zones excited by default: the target and its side neighbour n1 (one shared partition).
DEFAULT_EXCITED = ("target", "n1")


def column_names(zone: str) -> tuple[str, str, str]:
    """Data columns ``(supply temperature, flow, gain)`` of ``zone``: the target's are ``Ts, m, Q``."""
    check_zone(zone)
    return ("Ts", "m", "Q") if zone == "target" else (f"Ts_{zone}", f"m_{zone}", f"Q_{zone}")


def generate_multizone_night(
    season: str = "autumn",
    seed: int = 0,
    excited: tuple[str, ...] = DEFAULT_EXCITED,
    warmup: float = 6 * 3600.0,
    duration: float = NIGHT,
) -> pd.DataFrame:
    """Generate one night in which the zones ``excited`` follow independent forced-response schedules.

    Parameters
    ----------
    season : {"summer", "winter", "autumn"}
    seed : int
        Seed of ``numpy.random.default_rng``; same seed, same output.
    excited : tuple of str
        Zones of :data:`~rczone.virtual.building.ZONES` that are forced (at least one, no repeats).
    warmup : float
        Simulated time before 6 pm under the thermostats, s (multiple of 60 s).
    duration : float
        Length of the record from 6 pm, s (multiple of 60 s; default 12 h).

    Returns
    -------
    pandas.DataFrame
        ``duration / 60`` rows; columns ``time``, :data:`AIR_COLUMNS`, ``To``, then
        :func:`column_names` of each excited zone. ``df.attrs`` holds the season, seed, the
        excited zones, their command schedules (``(start s, m kg/s, reheat K)``), the true
        internal gains and the AHU supply temperature.
    """
    check_season(season)
    if not isinstance(excited, tuple | list) or not excited:
        raise ParameterError(f"excited must be a non-empty tuple of zone names, got {excited!r}")
    for z in excited:
        check_zone(z)
    if len(set(excited)) != len(excited):
        raise ParameterError(f"excited lists a zone twice: {tuple(excited)!r}")
    if not warmup >= 0 or warmup % SAMPLE:
        raise ParameterError(f"warmup must be a non-negative multiple of 60 s, got {warmup!r}")
    if not duration >= SAMPLE or duration % SAMPLE:
        raise ParameterError(f"duration must be a positive multiple of 60 s, got {duration!r}")
    excited = tuple(z for z in ZONES if z in excited)  # network order: independent of how listed
    bld = build_building()
    g_run, g_meas, g_sched = np.random.default_rng(seed).spawn(3)
    forced = {
        z: forced_schedule(g, duration, phase=j)
        for j, (z, g) in enumerate(zip(excited, g_sched.spawn(len(excited)), strict=True))
    }
    sense = sense_temperature
    r = run(bld, season, g_run, duration=duration, warmup=warmup, forced=forced, sense=sense)
    n = round(duration / SAMPLE)
    k0 = round(warmup / SAMPLE)
    sl = slice(k0, k0 + n)
    data: dict[str, np.ndarray] = {"time": r.t[sl] - r.t[k0]}
    for z in ZONES:
        data[AIR_NODE[z]] = r.sensed[z][sl]
    data["To"] = sense(r.input("To")[sl], g_meas)
    for z in excited:
        ts, m, q = column_names(z)
        data[ts] = sense(r.input(bld.supply_name(z))[sl], g_meas)
        data[m] = sense_flow(r.flow(bld.flow_name(z))[sl], g_meas)
        data[q] = np.full(n, bld.gains[z])
    df = pd.DataFrame(data)
    df.attrs.update(
        {
            "source": "rczone virtual building (multi-zone forced test)",
            "season": season,
            "seed": int(seed),
            "excited": list(excited),
            "start": "18:00",
            "units": {"time": "s", "flows": "kg/s", "gains": "W", "temperatures": "degC"},
            "ahu_supply_degC": SEASONS[season].t_ahu,
            "true_gains_W": {z: bld.gains[z] for z in excited},
            "forced_schedules": {z: [(c.start, c.m, c.reheat) for c in forced[z]] for z in excited},
            "n_discretizations": r.n_discretizations,
        }
    )
    return df
