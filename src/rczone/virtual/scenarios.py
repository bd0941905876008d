"""Nights of the virtual building in the shape of the paper's data sets.

The paper's data (Pugh Hall room 241, 6 pm to 6 am) are:

* **A**: summer night (Aug 2-3 2011), normal closed-loop control;
* **B**: winter night (Dec 5-6 2011), normal closed-loop control;
* **C**: autumn night (Oct 24-25 2011), forced-response test: the target's inputs follow
  commands.

:data:`SCENARIOS` reproduces these situations; :func:`generate_night` generates any number
of further nights (deterministic for a seed). In the forced mode the target's VAV box
follows a piecewise-constant command schedule (blocks of 60-150 min, rounded to 10 min,
cycling "cold" = 0.12 kg/s at the AHU supply temperature (~13 degC), "hot" = 0.12 kg/s
with full reheat (~35 degC) and "min" = 0.02 kg/s unheated), which drives the room
several K (3-4 K at most, 19-25 degC overall, like the paper's 65-80 F) away from its
neighbours, while the neighbours stay under their thermostats. Before 6 pm the target's
thermostat is in charge.

Output columns (rczone's default CSV columns; temperatures in degC, one row per minute):
``time`` (s from 6 pm), ``Ti``, ``To``, ``Ts``, ``m`` (kg/s), ``Q`` (W: the constant 50 W
of the paper, which is not measured), ``Tf``, ``Tc``, ``Tn1``, ``Tn2``, ``Thw`` and
``Tsd`` (mean of the five). ``Ts`` and ``m`` in row k are held over
``[time[k], time[k] + 60 s)``; temperatures are sensed at ``time[k]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np
import pandas as pd

from rczone.errors import ParameterError, did_you_mean
from rczone.virtual.building import build_building
from rczone.virtual.control import FLOW_LEVELS, SEASONS
from rczone.virtual.emulator import Command, run
from rczone.virtual.operation import Operation
from rczone.virtual.sensors import sense_flow, sense_temperature
from rczone.virtual.weather import check_season

#: Night length, s (6 pm to 6 am) and sample time, s.
NIGHT = 12 * 3600.0
SAMPLE = 60.0
#: Output columns, in order.
COLUMNS = ("time", "Ti", "To", "Ts", "m", "Q", "Tf", "Tc", "Tn1", "Tn2", "Thw", "Tsd")
#: Surroundings of the target: data column -> zone.
SURROUNDINGS = {"Tf": "f", "Tc": "c", "Tn1": "n1", "Tn2": "n2", "Thw": "hw"}
MODES = ("closed-loop", "forced")
#: Forced-response command levels: (flow kg/s, discharge temperature above AHU supply, K).
FORCED_LEVELS = {"cold": (FLOW_LEVELS[-1], 0.0), "hot": (FLOW_LEVELS[-1], 22.0), "min": (FLOW_LEVELS[0], 0.0)}
#: Order in which the forced test cycles through the levels.
FORCED_CYCLE = ("cold", "hot", "min")


@dataclass(frozen=True)
class Scenario:
    """A named data set: season, mode and seed."""

    name: str
    season: str
    mode: str
    seed: int
    description: str


#: The three shipped data sets (stand-ins for the paper's A, B, C).
SCENARIOS = {
    "A": Scenario("A", "summer", "closed-loop", 20110802, "summer night, normal closed-loop control"),
    "B": Scenario("B", "winter", "closed-loop", 20111205, "winter night, normal closed-loop control"),
    "C": Scenario("C", "autumn", "forced", 20111024, "autumn night, forced-response test of the target room"),
}


def forced_schedule(rng: np.random.Generator, duration: float = NIGHT, phase: int = 0) -> tuple[Command, ...]:
    """A forced-response command schedule: blocks of 60-150 min cycling cold / hot / min.

    ``phase`` is the position in :data:`FORCED_CYCLE` of the first block (0: "cold"), so that
    several zones forced at once do not start in step.
    """
    out: list[Command] = []
    t, i = 0.0, phase
    while t < duration:
        m, reheat = FORCED_LEVELS[FORCED_CYCLE[i % len(FORCED_CYCLE)]]
        out.append(Command(t, m, reheat))
        t += 600.0 * int(rng.integers(6, 16))
        i += 1
    return tuple(out)


def generate_night(
    season: str,
    mode: str = "closed-loop",
    seed: int = 0,
    zone: str = "target",
    warmup: float = 6 * 3600.0,
    commands: tuple[Command, ...] | None = None,
    operation: Operation | None = None,
) -> pd.DataFrame:
    """Generate one 6 pm to 6 am night of BMS data for the target office.

    Parameters
    ----------
    season : {"summer", "winter", "autumn"}
    mode : {"closed-loop", "forced"}
        Normal thermostat control, or the target follows a forced-response schedule.
    seed : int
        Seed of ``numpy.random.default_rng``; same seed, same output.
    zone : str
        Zone whose data are reported; only ``"target"`` (the office with five modelled
        surroundings) is supported.
    warmup : float
        Simulated time before 6 pm, s.
    commands : tuple of Command, optional
        Forced mode only: the target's command schedule instead of the seeded
        :func:`forced_schedule` (used by :func:`rczone.virtual.playback.play_schedule`). The
        weather, the neighbours' controllers and the sensor noise depend on ``seed`` alone,
        so the same seed with and without ``commands`` gives a paired comparison.
    operation : Operation, optional
        How the building is run and logged (:mod:`rczone.virtual.operation`: loop, night
        deadband, unmeasured scheduled gains, thermostat placement, trend resolution); default:
        as the shipped nights. The same seed with another operation gives a paired comparison.

    Returns
    -------
    pandas.DataFrame
        720 rows, columns :data:`COLUMNS`; metadata in ``df.attrs``.
    """
    check_season(season)
    if mode not in MODES:
        raise ParameterError(f"unknown mode {mode!r}; " + did_you_mean(mode, MODES))
    if zone != "target":
        raise ParameterError(
            f"zone {zone!r}: only 'target' has its five surroundings modelled in the virtual building;"
            " use zone='target'"
        )
    if not warmup >= 0 or warmup % SAMPLE:
        raise ParameterError(f"warmup must be a non-negative multiple of 60 s, got {warmup!r}")
    if commands is not None and mode != "forced":
        raise ParameterError(f"commands are played in mode 'forced' only, got mode {mode!r}")
    if commands is not None and (not commands or any(not isinstance(c, Command) for c in commands)):
        raise ParameterError("commands must be a non-empty tuple of rczone.virtual.emulator.Command")
    bld = build_building()
    g_run, g_meas, g_sched = np.random.default_rng(seed).spawn(3)
    seeded = forced_schedule(g_sched)
    forced = {zone: tuple(commands) if commands is not None else seeded} if mode == "forced" else None
    op = operation or Operation()
    sense = partial(sense_temperature, step_f=op.trend_quantum_F)
    r = run(bld, season, g_run, duration=NIGHT, warmup=warmup, forced=forced, sense=sense, operation=op)
    n = round(NIGHT / SAMPLE)
    k0 = round(warmup / SAMPLE)
    sl = slice(k0, k0 + n)
    data = {
        "time": r.t[sl] - r.t[k0],
        "Ti": r.sensed[zone][sl],
        "To": sense(r.input("To")[sl], g_meas),
        "Ts": sense(r.input(bld.supply_name(zone))[sl], g_meas),
        "m": sense_flow(r.flow(bld.flow_name(zone))[sl], g_meas),
        "Q": np.full(n, bld.gains[zone]),
    }
    for col, z in SURROUNDINGS.items():
        data[col] = r.sensed[z][sl]
    data["Tsd"] = np.mean([data[c] for c in SURROUNDINGS], axis=0)
    df = pd.DataFrame(data, columns=list(COLUMNS))
    tg = bld.target
    df.attrs.update(
        {
            "source": "rczone virtual building",
            "season": season,
            "mode": mode,
            "seed": int(seed),
            "zone": zone,
            "start": "18:00",
            "units": {"time": "s", "m": "kg/s", "Q": "W", "temperatures": "degC"},
            "ahu_supply_degC": SEASONS[season].t_ahu,
            "true_room_capacity_J_K": tg.room_capacity,
            "true_window_resistance_K_W": tg.window.resistance,
            "true_surface_resistance_K_W": {s.name: s.resistance for s in tg.surfaces},
            "true_surface_capacity_J_K": {s.name: s.capacity for s in tg.surfaces},
            "n_discretizations": r.n_discretizations,
            "operation": op.label(),
        }
    )
    if forced:
        df.attrs["forced_schedule"] = [(c.start, c.m, c.reheat) for c in forced[zone]]
        if any(c.ts is not None for c in forced[zone]):
            df.attrs["forced_ts_setpoints"] = [c.ts for c in forced[zone]]
    return df


def scenario(name: str) -> pd.DataFrame:
    """Generate the named scenario (``"A"``, ``"B"`` or ``"C"``) from scratch."""
    if name not in SCENARIOS:
        raise ParameterError(f"unknown scenario {name!r}; " + did_you_mean(name, SCENARIOS))
    s = SCENARIOS[name]
    df = generate_night(s.season, s.mode, s.seed)
    df.attrs["scenario"] = name
    df.attrs["description"] = s.description
    return df
