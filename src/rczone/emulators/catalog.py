"""What the EnergyPlus extra ships: prototype buildings, TMY3 weather files, and the run's dates.

The wheel ``pyenergyplus-lbnl`` holds the ASHRAE 90.1-2019 prototype buildings (PNNL's
commercial prototype models, climate zone 5B, Denver) and 16 TMY3 weather files (Wilcox &
Marion 2008). This module names them, checks a user's choice of building, weather file and dates
(one line with a close name for a typo), and reads the weather file's header: where the station
is, its standard time zone and the dates its data cover. Nothing here runs EnergyPlus.

References
----------
.. [1] S. Wilcox, W. Marion, "Users manual for TMY3 data sets", NREL/TP-581-43156, 2008 (the EPW
   header: LOCATION with the time zone in hours from GMT, DATA PERIODS).
.. [2] ANSI/ASHRAE/IES Standard 90.1-2019 and the DOE/PNNL commercial prototype building models.
"""

from __future__ import annotations

import datetime as dt
import re
from dataclasses import dataclass
from pathlib import Path

from rczone.errors import EmulatorError, ParameterError, did_you_mean

#: The command that installs the extra, quoted in the error when it is missing.
INSTALL = "pip install 'rczone[energyplus]'"
#: Calendar year of the trend's time stamps: 2017 starts on a Sunday, as the prototypes' run periods.
YEAR = 2017
#: Longest emulation, days (a year of the weather file).
MAX_DAYS = 365


def dataset():
    """The ``pyenergyplus.dataset`` module, or one line with the install command."""
    try:
        from pyenergyplus import dataset
    except ImportError:
        raise EmulatorError(f"the EnergyPlus emulator needs the energyplus extra: {INSTALL}") from None
    return dataset


def buildings() -> dict[str, Path]:
    """The ASHRAE 90.1-2019 prototype buildings: name (``office_small``...) to input file."""
    return {k: Path(v) for k, v in sorted(dataset().ashrae_models.items())}


def weather_files() -> dict[str, Path]:
    """The TMY3 weather files: name (``usa_il_chicago``...) to EPW file."""
    return {k: Path(v) for k, v in sorted(dataset().weather_files.items())}


def building_file(name: str) -> Path:
    """The input file of building ``name``, or one line naming the close ones."""
    known = buildings()
    if name not in known:
        raise ParameterError(
            f"unknown building {name!r}; {did_you_mean(name, known)} (rczone emulate --list)"
        )
    return known[name]


def weather_file(name: str) -> Path:
    """The EPW file of weather ``name``, or one line naming the close ones."""
    known = weather_files()
    if name not in known:
        raise ParameterError(f"unknown weather {name!r}; {did_you_mean(name, known)} (rczone emulate --list)")
    return known[name]


@dataclass(frozen=True)
class WeatherHeader:
    """The header of an EPW file.

    Attributes
    ----------
    city : str
    latitude, longitude : float
        Degrees.
    utc_offset_h : float
        Standard time zone, hours from UTC (EnergyPlus simulates in standard time).
    first, last : datetime.date
        First and last day of the data (in :data:`YEAR`).
    """

    city: str
    latitude: float
    longitude: float
    utc_offset_h: float
    first: dt.date
    last: dt.date


def timezone_name(utc_offset_h: float) -> str:
    """The fixed-offset IANA name of a standard time zone (``Etc/GMT+6`` is UTC-6)."""
    h = utc_offset_h
    if h != int(h):
        raise EmulatorError(f"a time zone of {h:g} h from UTC is not whole hours (no IANA fixed-offset name)")
    return "UTC" if h == 0 else f"Etc/GMT{-int(h):+d}"


def _md(text: str, where: str) -> dt.date:
    m = re.fullmatch(r"\s*(\d{1,2})\s*/\s*(\d{1,2})\s*", text)
    if not m:
        raise EmulatorError(f"{where}: cannot read the date {text!r} of DATA PERIODS")
    return dt.date(YEAR, int(m.group(1)), int(m.group(2)))


def read_header(path: Path) -> WeatherHeader:
    """Read the LOCATION and DATA PERIODS lines of an EPW file [1]_."""
    lines = path.read_text(encoding="latin-1").splitlines()[:8]
    loc = next((ln.split(",") for ln in lines if ln.startswith("LOCATION")), None)
    per = next((ln.split(",") for ln in lines if ln.startswith("DATA PERIODS")), None)
    if loc is None or per is None or len(loc) < 9 or len(per) < 7:
        raise EmulatorError(f"{path.name}: not an EPW weather file (no LOCATION or DATA PERIODS line)")
    return WeatherHeader(
        city=loc[1].strip(),
        latitude=float(loc[6]),
        longitude=float(loc[7]),
        utc_offset_h=float(loc[8]),
        first=_md(per[5], path.name),
        last=_md(per[6], path.name),
    )


def outdoor_temperatures(path: Path) -> tuple:
    """The EPW file's hourly dry-bulb temperatures: (s since 1 January at the end of each hour, degC)."""
    import numpy as np

    rows = [ln.split(",") for ln in path.read_text(encoding="latin-1").splitlines()[8:] if ln.count(",") > 6]
    t = [
        (dt.date(YEAR, int(r[1]), int(r[2])).timetuple().tm_yday - 1) * 86400.0 + int(r[3]) * 3600.0
        for r in rows
    ]
    return np.array(t), np.array([float(r[6]) for r in rows])


def parse_start(text: str) -> dt.date:
    """A start date ``MM-DD`` (in :data:`YEAR`), or one line saying what is wrong."""
    m = re.fullmatch(r"(\d{1,2})-(\d{1,2})", text.strip())
    if not m:
        raise ParameterError(f"--start {text!r}: give the first day as MM-DD (e.g. 01-15)")
    try:
        return dt.date(YEAR, int(m.group(1)), int(m.group(2)))
    except ValueError:
        raise ParameterError(
            f"--start {text!r} is not a day of a typical year (TMY files have 365 days, no 29 February)"
        ) from None


def check_period(header: WeatherHeader, start: dt.date, days: int, weather: str) -> dt.date:
    """The last day of a run of ``days`` from ``start``; one line if it leaves the weather file."""
    if isinstance(days, bool) or not isinstance(days, int) or not 1 <= days <= MAX_DAYS:
        raise ParameterError(f"--days must be a whole number from 1 to {MAX_DAYS}, got {days!r}")
    last = start + dt.timedelta(days=days - 1)
    if start < header.first or last > header.last or last.year != start.year:
        raise ParameterError(
            f"{days} days from {start:%m-%d} end on {last:%m-%d}"
            f"{' of the next year' if last.year != start.year else ''}, outside the weather file"
            f" {weather} ({header.first:%m-%d} to {header.last:%m-%d}); start earlier or run fewer days"
        )
    return last
