"""Play a supply-air command schedule (e.g. a designed test) in the virtual building.

A schedule from :func:`rczone.diagnostics.design.design_test` (or a BMS CSV with the same
meaning) gives, per block, an absolute supply-air temperature ``Ts`` (degC) and a flow ``m``
(kg/s). The emulator's VAV box takes a flow and a discharge temperature that its reheat
coil reaches from the AHU supply temperature, so each block becomes a
:class:`~rczone.virtual.emulator.Command` with an absolute setpoint: the coil aims at
``max(Ts, T_ahu)`` through its 3-minute lag (a box cannot cool below the AHU supply,
about 13 degC at night). The night is then generated exactly like
:func:`rczone.virtual.scenarios.generate_night` in forced mode, with the same seed
meaning the same weather, neighbours and sensor noise.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rczone.errors import DataError, ParameterError
from rczone.virtual.emulator import Command
from rczone.virtual.scenarios import NIGHT, SAMPLE, generate_night

#: Columns a schedule must have: block start (s from 6 pm), Ts (degC), m (kg/s).
SCHEDULE_COLUMNS = ("start_s", "Ts", "m")


def schedule_commands(schedule: pd.DataFrame) -> tuple[Command, ...]:
    """Turn a schedule table into emulator commands with absolute supply temperatures.

    Parameters
    ----------
    schedule : DataFrame
        One row per block with ``start_s`` (s from 6 pm, increasing, the first 0), ``Ts``
        (degC) and ``m`` (kg/s), as ``DesignResult.schedule``.

    Returns
    -------
    tuple of Command
    """
    missing = [c for c in SCHEDULE_COLUMNS if c not in schedule.columns]
    if missing:
        raise DataError(
            f"schedule lacks column(s) {missing}; expected {list(SCHEDULE_COLUMNS)}"
            " (as DesignResult.schedule: start_s in s, Ts in degC, m in kg/s)"
        )
    if len(schedule) == 0:
        raise DataError("schedule is empty; expected at least one block")
    start = schedule["start_s"].to_numpy(float)
    ts = schedule["Ts"].to_numpy(float)
    m = schedule["m"].to_numpy(float)
    if not (np.all(np.isfinite(start)) and np.all(np.isfinite(ts)) and np.all(np.isfinite(m))):
        raise DataError("schedule has non-finite start_s, Ts or m values; fill or drop those rows")
    if start[0] != 0.0 or np.any(np.diff(start) <= 0):
        raise DataError(
            f"schedule start_s must begin at 0 s and increase strictly, got {start[:5].tolist()}...;"
            " sort the blocks and measure their starts from the beginning of the test"
        )
    if start[-1] >= NIGHT:
        raise DataError(f"schedule block starts at {start[-1]:.0f} s, after the {NIGHT:.0f} s night ends")
    if np.any(m < 0):
        raise DataError(f"schedule flows must be >= 0 kg/s, got min {m.min():g}")
    return tuple(Command(float(s), float(f), ts=float(t)) for s, f, t in zip(start, m, ts, strict=True))


def play_schedule(
    schedule: pd.DataFrame,
    season: str = "autumn",
    seed: int = 0,
    warmup: float = 6 * 3600.0,
) -> pd.DataFrame:
    """Generate one 6 pm to 6 am night in which the target room follows ``schedule``.

    Parameters
    ----------
    schedule : DataFrame
        ``start_s``, ``Ts``, ``m`` per block (see :func:`schedule_commands`); a
        ``DesignResult`` may be passed as ``result.schedule``.
    season : {"summer", "winter", "autumn"}
    seed : int
        Seed of the night (weather, neighbours' controllers, AHU drift, sensors).
    warmup : float
        Simulated time before 6 pm under thermostat control, s (multiple of 60 s).

    Returns
    -------
    pandas.DataFrame
        Same shape and columns as :func:`~rczone.virtual.scenarios.generate_night`; the
        measured ``Ts`` is what the coil delivered (lagged, floored at the AHU supply).
    """
    if not isinstance(schedule, pd.DataFrame):
        raise ParameterError(
            f"schedule must be a pandas DataFrame, got {type(schedule).__name__}; pass DesignResult.schedule"
        )
    if warmup % SAMPLE:
        raise ParameterError(f"warmup must be a multiple of {SAMPLE:.0f} s, got {warmup!r}")
    df = generate_night(season, "forced", seed, warmup=warmup, commands=schedule_commands(schedule))
    df.attrs["mode"] = "played schedule"
    return df
