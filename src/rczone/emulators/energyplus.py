"""EnergyPlus as an emulator: one in-process run of a prototype building, read as a BMS reads it.

:class:`EnergyPlusEmulator` runs EnergyPlus through its Python API [1]_ (``pyenergyplus``, the
optional extra ``rczone[energyplus]``, imported only here and only when a run starts). The
prototype's input file is edited (:mod:`rczone.emulators.idf`: the run period, the time step, no
tabular reports), EnergyPlus runs in a temporary folder that is removed afterwards, and at the end
of every zone time step (the ``end zone timestep after zone reporting`` calling point) a callback
reads, through variable handles requested before the run:

* ``Zone Mean Air Temperature`` of every zone (the room air ``Ti``, also of plenums and attics);
* ``System Node Temperature`` and ``System Node Mass Flow Rate`` of every zone inlet node (the
  discharge air of the zone's terminal: the paper's ``Ts`` and ``m``);
* ``Site Outdoor Air Drybulb Temperature`` (``To``);
* ``Zone Lights Electricity Rate`` and ``Zone Electric Equipment Electricity Rate`` of every zone
  (sub-metered plug and lighting power, the measured part of the internal gain ``Q``);
* the ``Electricity:HVAC`` and ``NaturalGas:HVAC`` meters (the HVAC energy of the time step).

A ``controller`` called at the same point may return actuator values (by the labels of the
``actuators`` it declared), which EnergyPlus holds from the next time step on; ``None`` hands an
actuator back to the building's own control. A handle EnergyPlus does not know (an actuator it
refuses, a variable it does not have) stops the run with one line; a run that fails quotes the
severe errors of ``eplusout.err``.

References
----------
.. [1] U.S. Department of Energy, *EnergyPlus Application Guide for EMS* and the EnergyPlus Python
   API documentation (state, runtime callbacks, data exchange: request_variable,
   get_variable_handle, get_actuator_handle, set_actuator_value).
"""

from __future__ import annotations

import datetime as dt
import re
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from rczone.emulators import catalog, idf
from rczone.emulators.geometry import Geometry, read_eio
from rczone.emulators.session import Session, Stop
from rczone.errors import EmulatorError, ParameterError, did_you_mean

#: Zone time steps an hour that a trend may be sampled at (EnergyPlus allows divisors of 60).
STEPS_PER_HOUR = (1, 2, 3, 4, 5, 6, 10, 12, 15, 20, 30, 60)
#: Most severe errors quoted from eplusout.err.
MAX_QUOTED = 3


@dataclass(frozen=True)
class Actuator:
    """An EnergyPlus actuator: component type, control type and the key (a zone, a node...)."""

    component: str
    control: str
    key: str

    def __str__(self) -> str:
        return f"{self.component} / {self.control} / {self.key}"


#: A controller: (seconds since the start of the year, readings) -> actuator values by label.
Controller = Callable[[float, Mapping[str, float]], Mapping[str, float | None]]


@dataclass(frozen=True, eq=False, repr=False)
class Emulation:
    """What one EnergyPlus run gave, before any sensor (true values, SI units).

    Attributes
    ----------
    building, weather : str
    start : datetime.date
    days : int
    step_s : float
        Zone time step, s.
    utc_offset_h : float
        The weather station's standard time zone, hours from UTC.
    frame : DataFrame
        One row per zone time step, indexed by its end (local standard time, with its offset);
        columns ``To``, ``Ti:<zone>``, ``Ts:<node>``, ``m:<node>`` (kg/s), ``Pel:<zone>`` (lights and
        plug power, W), the meters in W, and ``cmd:<label>`` for what a controller set.
    inlets : dict of str to tuple of str
        Each zone's inlet nodes (empty for a plenum or attic).
    geometry : Geometry
        Zones and interzone adjacency read from EnergyPlus's ``eplusout.eio``.
    reported : DataFrame, optional
        EnergyPlus's own time-step report (``eplusout.csv``) of the variables asked for, as it
        wrote them, for checks.
    """

    building: str
    weather: str
    start: dt.date
    days: int
    step_s: float
    utc_offset_h: float
    frame: pd.DataFrame
    inlets: dict[str, tuple[str, ...]]
    geometry: Geometry
    reported: pd.DataFrame | None = field(default=None)

    @property
    def zones(self) -> tuple[str, ...]:
        """Every zone, in the input file's order."""
        return tuple(self.inlets)

    @property
    def conditioned(self) -> tuple[str, ...]:
        """Zones with at least one inlet node (air terminals)."""
        return tuple(z for z, n in self.inlets.items() if n)

    def summary(self) -> str:
        """One paragraph: what ran, and the range of each zone's temperature."""
        lines = [
            f"EnergyPlus {self.building}, weather {self.weather}, {self.days} days from {self.start:%m-%d},"
            f" {len(self.frame)} steps of {self.step_s / 60:g} min"
        ]
        for z in self.zones:
            ti = self.frame[f"Ti:{z}"]
            lines.append(f"  {z}: {ti.min():.1f}..{ti.max():.1f} degC")
        return "\n".join(lines) + "\n"

    def to_frame(self) -> pd.DataFrame:
        """The time-step table (:attr:`frame`)."""
        return self.frame

    def to_dict(self) -> dict:
        """What the run was (not its data)."""
        return {
            "emulator": "energyplus",
            "building": self.building,
            "weather": self.weather,
            "start": f"{self.start:%m-%d}",
            "days": self.days,
            "step_s": self.step_s,
            "zones": list(self.zones),
            "samples": len(self.frame),
        }


def _severe(err: Path) -> str:
    """The severe and fatal errors of ``eplusout.err``, each with its continuation lines, joined."""
    if not err.exists():
        return "EnergyPlus wrote no eplusout.err"
    found: list[str] = []
    for line in err.read_text(errors="replace").splitlines():
        if re.match(r"\s*\*\*\s*(Severe|Fatal)\s*\*\*", line):
            found.append(line.split("**", 2)[-1].strip())
        elif found and re.match(r"\s*\*\*\s*~~~\s*\*\*", line) and len(found) <= MAX_QUOTED:
            found[-1] += " " + line.split("**", 2)[-1].strip()
    return "; ".join(found[:MAX_QUOTED]) or "no severe error written"


class EnergyPlusEmulator:
    """One run of an ASHRAE prototype building in EnergyPlus (see the module notes).

    Parameters
    ----------
    building : str
        A prototype (``office_small``, ``office_medium``...; :func:`rczone.emulators.catalog.buildings`).
    weather : str
        A TMY3 file (``usa_il_chicago``...).
    start : str
        First day, ``MM-DD``.
    days : int
        Whole days to run.
    step_minutes : int
        Zone time step (and trend interval), minutes; 60 divided by it is EnergyPlus's ``Timestep``.
    """

    def __init__(
        self, building: str, weather: str, *, start: str = "01-15", days: int = 2, step_minutes: int = 5
    ) -> None:
        self.building = building
        self.weather = weather
        self._idf_path = catalog.building_file(building)
        self._epw = catalog.weather_file(weather)
        self.header = catalog.read_header(self._epw)
        self.start = catalog.parse_start(start)
        self.days = days
        self.last = catalog.check_period(self.header, self.start, days, weather)
        if isinstance(step_minutes, bool) or not isinstance(step_minutes, int) or step_minutes <= 0:
            raise ParameterError(f"--step must be whole minutes, got {step_minutes!r}")
        if 60 % step_minutes or 60 // step_minutes not in STEPS_PER_HOUR:
            raise ParameterError(
                f"--step {step_minutes} min: EnergyPlus needs a divisor of 60 ("
                + ", ".join(str(60 // n) for n in reversed(STEPS_PER_HOUR))
                + ")"
            )
        self.step_s = 60.0 * step_minutes
        self._objects = idf.parse_idf(self._idf_path.read_text(encoding="latin-1"))
        self.hvac = idf.zones(self._objects)
        self._ran = False
        self.folder: Path | None = None

    @property
    def zone_names(self) -> tuple[str, ...]:
        """The building's zones, as its input file spells them."""
        return tuple(z.name for z in self.hvac)

    def zone(self, name: str) -> str:
        """The zone named ``name`` (any case), or one line naming the close ones."""
        for z in self.zone_names:
            if z.lower() == name.lower():
                return z
        raise ParameterError(
            f"building {self.building} has no zone {name!r}; {did_you_mean(name, self.zone_names)}"
        )

    def run(
        self,
        controller: Controller | None = None,
        actuators: Mapping[str, Actuator] | None = None,
        *,
        report: Sequence[str] = (),
        extra: Mapping[str, tuple[str, str]] | None = None,
    ) -> Emulation:
        """Run EnergyPlus once (an emulator object runs once).

        Parameters
        ----------
        controller : callable, optional
            Called at the end of every zone time step of the run period as ``controller(t,
            readings)`` (``t`` s since 1 January, local standard time; ``readings`` the column
            names of :attr:`Emulation.frame`); returns values of ``actuators`` by label (``None``
            releases one).
        actuators : mapping of str to Actuator, optional
            The actuators the controller may set, by label.
        report : sequence of str
            EnergyPlus output variables to write into its own time-step report
            (:attr:`Emulation.reported`), for checks.
        extra : mapping of str to (str, str), optional
            More output variables ``(variable, key)`` read each step into the rows by label
            (:class:`~rczone.emulators.session.Session`).

        Returns
        -------
        Emulation

        Raises
        ------
        EmulatorError
            The extra is missing, EnergyPlus refuses an actuator or a variable, or the run fails.
        """
        if self._ran:
            raise EmulatorError("an EnergyPlusEmulator runs once; make a new one for another run")
        self._ran = True
        catalog.dataset()  # one line with the install command when the extra is missing
        from pyenergyplus.api import EnergyPlusAPI

        objects = idf.for_run(self._objects, self.start, self.last, int(3600 // self.step_s), report)
        with tempfile.TemporaryDirectory(prefix="rczone-energyplus-") as tmp:
            folder = Path(tmp)
            self.folder = folder  # while the run lasts: a controller may read eplusout.eio
            (folder / "in.idf").write_text(idf.write_idf(objects), encoding="latin-1")
            api = EnergyPlusAPI()
            session = Session(api, self.hvac, dict(actuators or {}), controller, extra)
            code = session.run(["-d", str(folder), "-w", str(self._epw), str(folder / "in.idf")])
            stopped = isinstance(session.error, Stop)
            if session.error is not None and not stopped:
                raise session.error
            if code != 0 and not stopped:
                raise EmulatorError(
                    f"EnergyPlus failed ({self.building}): {_severe(folder / 'eplusout.err')}"
                )
            geometry = read_eio((folder / "eplusout.eio").read_text(errors="replace"), self.zone_names)
            reported = _read_report(folder / "eplusout.csv") if report else None
        return Emulation(
            building=self.building,
            weather=self.weather,
            start=self.start,
            days=self.days,
            step_s=self.step_s,
            utc_offset_h=self.header.utc_offset_h,
            frame=self._frame(session.rows),
            inlets={z.name: z.inlets for z in self.hvac},
            geometry=geometry,
            reported=reported,
        )

    def _frame(self, rows: list[dict[str, float]]) -> pd.DataFrame:
        if not rows:
            raise EmulatorError(f"EnergyPlus ran no time step of the run period ({self.building})")
        frame = pd.DataFrame(rows)
        tz = dt.timezone(dt.timedelta(hours=self.header.utc_offset_h))
        origin = pd.Timestamp(dt.datetime(catalog.YEAR, 1, 1, tzinfo=tz))
        frame.index = pd.DatetimeIndex(origin + pd.to_timedelta(frame.pop("t"), unit="s"), name="time")
        return frame


def _read_report(path: Path) -> pd.DataFrame:
    """EnergyPlus's own CSV report (``Date/Time`` stamps ``MM/DD  HH:MM:SS`` kept as text)."""
    if not path.exists():
        raise EmulatorError("EnergyPlus wrote no eplusout.csv for the variables asked for")
    return pd.read_csv(path)
