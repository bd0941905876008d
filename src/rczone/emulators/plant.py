"""EnergyPlus stepped by a controller: the plant interface of ``rczone.control.plant``, BOPTEST's shape.

:class:`EnergyPlusPlant` runs :class:`~rczone.emulators.energyplus.EnergyPlusEmulator` in a worker
thread. At the end of every zone time step EnergyPlus calls back; the callback hands the readings
to :meth:`EnergyPlusPlant.step` (or :meth:`~EnergyPlusPlant.measure`) through a queue and waits for
the next actions, so EnergyPlus advances exactly one step per call, as a BOPTEST test case [1]_.

**Actions** are **zone set points**, the actuators EnergyPlus's own HVAC honours (measured, see
docs/energyplus.md): ``Tset_<zone>`` (the thermostat's heating set point at ``Tset - 0.5 K`` and
cooling at ``Tset + 0.5 K``), or ``heating_<zone>`` and ``cooling_<zone>`` separately; a zone
without an action in a step runs on the building's own schedules (the baseline). ``m_<zone>`` and
``Ts_<zone>`` (the virtual building's actions) are refused with one line: the prototypes' terminals
do not follow flow or discharge set points.

**Constraints** (:meth:`~EnergyPlusPlant.constraints`, the same for every controller): the set
points a supervisory controller may give, by the occupancy schedule (:data:`SETPOINT_LIMITS`):
``heating_min_<zone>``, ``heating_max_<zone>``, ``cooling_min_<zone>``, ``cooling_max_<zone>``,
the tightest over each interval. A commanded set point is clipped to them (and the heating set
point kept :data:`MIN_DEADBAND_K` below the cooling one), as a BMS clips an operator's entry; the
set points *in effect* (EnergyPlus's ``Zone Thermostat Heating/Cooling Setpoint Temperature``,
whoever set them: the building's schedules too) are checked against them at every step and the
steps outside are counted (``constraint_violations``).

**Measurements**: ``time`` (s from the start of the run, 00:00 of the first day, local standard
time), ``To``, ``T_ahu`` (NaN: the prototypes' AHUs are not read), and per controlled zone
``Ti_<zone>``, ``m_<zone>``, ``Ts_<zone>`` through the BMS sensors of :mod:`rczone.virtual.sensors`
(the first inlet node's discharge temperature, the summed flow), ``Q_<zone>`` (the sub-metered
lighting and plug power, 1 % noise) and ``Tsd_<zone>`` (the neighbours' sensed air temperatures
weighted by the conductance each shares with the zone, from EnergyPlus's ``eplusout.eio``, as the
column map of ``rczone emulate`` defines it); and ``Ti_<zone>`` of every neighbour not controlled
(plenum, attic, the next floor: the boundaries of a joint floor model).

**Forecasts**: the weather file's outdoor temperature plus BOPTEST's forecast error of the chosen
scenario (:mod:`rczone.emulators.forecasts`: none, low, medium, high), the price (``flat``,
``tou``, ``dr`` of :mod:`rczone.control.signals`, by the local hour), and the comfort band of the
prototype's thermostat schedule (:data:`SCHEDULES`: occupied weekday hours and band; otherwise
its setback band). Schedules and prices follow the building's clock, an hour ahead of the plant's
standard time during daylight saving, as EnergyPlus shifts the prototypes' schedules.

**Scores** from EnergyPlus's own values: ``comfort_Kh`` (and ``comfort_Kh_<zone>``) from the true
zone temperatures outside the band over the occupied hours; ``energy_kWh`` and ``cost`` (price
weighted) of the controlled zones' HVAC (:mod:`rczone.emulators.hvacmeters`: their own coils and
their share of their air loop's fans and coils by supply flow; parts ``fan_kWh``, ``cooling_kWh``,
``heating_kWh``, ``reheat_kWh``), ``peak_power_kW`` (their HVAC power's largest step mean),
``building_hvac_kWh`` (the ``Electricity:HVAC`` and ``NaturalGas:HVAC`` meters of the whole
building) and ``unattributed_kWh`` (what those meters hold that no zone's components do).

References
----------
.. [1] D. Blum et al., "Building optimization testing framework (BOPTEST) for simulation-based
   benchmarking of control strategies in buildings", Journal of Building Performance Simulation
   14(5) (2021) 586-610.
"""

from __future__ import annotations

import datetime as dt
import queue
import threading
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from rczone.control.plant import forecast_steps, forecast_times
from rczone.control.signals import PRICES, forecast_price, price_signal
from rczone.emulators import hvacmeters
from rczone.emulators.catalog import outdoor_temperatures
from rczone.emulators.energyplus import Actuator, EnergyPlusEmulator
from rczone.emulators.forecasts import forecast_error, scenario
from rczone.emulators.geometry import read_eio
from rczone.emulators.session import METERS, Stop
from rczone.errors import EmulatorError, ParameterError, did_you_mean
from rczone.virtual.sensors import sense_flow, sense_temperature


class Schedule(NamedTuple):
    """A prototype's thermostat schedule: occupied weekday hours (local), its bands, degC."""

    hours: tuple[float, float]
    occupied: tuple[float, float]
    unoccupied: tuple[float, float]


#: The prototypes' own thermostat schedules on weekdays (their input files' HTGSETP_SCH and
#: CLGSETP_SCH, without the morning ramps); other buildings get :data:`DEFAULT_SCHEDULE`.
SCHEDULES = {
    "office_small": Schedule((8.0, 18.0), (21.11, 23.89), (15.56, 29.44)),
    "office_medium": Schedule((7.0, 22.0), (21.0, 24.0), (15.6, 26.7)),
}
DEFAULT_SCHEDULE = Schedule((7.0, 19.0), (21.0, 24.0), (15.6, 26.7))
#: Set points a supervisory controller may give (heating min, max; cooling min, max), degC,
#: occupied and unoccupied: the building's own schedules lie inside them.
SETPOINT_LIMITS = {"occupied": (18.0, 24.0, 21.0, 27.0), "unoccupied": (12.0, 24.0, 21.0, 32.0)}
#: Half the thermostat's dead band around ``Tset``, K; the least distance heating to cooling, K.
HALF_DEADBAND = 0.5
MIN_DEADBAND_K = 0.5
#: Seconds a step waits for EnergyPlus before it gives up.
TIMEOUT_S = 600.0
#: The price signal's clock starts at 6 pm (:mod:`rczone.control.signals`); the plant's at 00:00.
PRICE_SHIFT = 6 * 3600.0
#: Sub-meter noise of the lighting and plug power (relative).
POWER_NOISE = 0.01


def _nth_sunday(year: int, month: int, n: int) -> dt.date:
    first = dt.date(year, month, 1)
    return first + dt.timedelta(days=(6 - first.weekday()) % 7 + 7 * (n - 1))


def daylight_saving(objects, year: int) -> tuple[dt.date, dt.date] | None:
    """The prototype's daylight saving period (its ``RunPeriodControl:DaylightSavingTime``), or None.

    EnergyPlus keeps its clock on standard time and shifts the schedules; the prototypes use the
    US rule, second Sunday in March to first Sunday in November (the only one read here).
    """
    for o in objects:
        if o.is_a("RunPeriodControl:DaylightSavingTime"):
            if o.field(0).lower().startswith("2nd sunday in march") and o.field(1).lower().startswith(
                "1st sunday in november"
            ):
                return _nth_sunday(year, 3, 2), _nth_sunday(year, 11, 1)
            raise EmulatorError(f"unsupported daylight saving period {o.field(0)!r} to {o.field(1)!r}")
    return None


class EnergyPlusPlant:
    """An EnergyPlus prototype as a plant (see the module notes).

    Parameters
    ----------
    building, weather, start, days, step_minutes
        As :class:`~rczone.emulators.energyplus.EnergyPlusEmulator`.
    zones : sequence of str
        The zones a controller runs.
    seed : int
        Seed of the sensor noise and of the forecast error.
    price : {"flat", "tou", "dr"}
    forecast : {"none", "low", "medium", "high"}
        BOPTEST's forecast uncertainty scenario of the outdoor temperature.
    """

    def __init__(
        self,
        building: str,
        weather: str,
        *,
        zones: Sequence[str],
        start: str = "01-15",
        days: int = 2,
        step_minutes: int = 15,
        seed: int = 0,
        price: str = "flat",
        forecast: str = "none",
    ) -> None:
        if price not in PRICES:
            raise ParameterError(f"unknown price signal {price!r}; {did_you_mean(price, PRICES)}")
        self._error = scenario(forecast)
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ParameterError(f"seed must be an integer >= 0, got {seed!r}")
        self._em = EnergyPlusEmulator(building, weather, start=start, days=days, step_minutes=step_minutes)
        self.zones = tuple(self._em.zone(z) for z in zones)
        if not self.zones:
            raise ParameterError("a plant needs at least one zone a controller runs")
        self._inlets = {z.name: z.inlets for z in self._em.hvac}
        for z in self.zones:
            if not self._inlets[z]:
                raise ParameterError(f"zone {z} has no air terminal: a controller cannot run it")
        self.price, self.forecast_kind, self.seed = price, forecast, int(seed)
        self.schedule = SCHEDULES.get(building, DEFAULT_SCHEDULE)
        self._equipment = hvacmeters.zone_equipment(self._em._objects, self._em.hvac)
        self.dt = self._em.step_s
        self.end = days * 86400.0
        self._t0 = (self._em.start.timetuple().tm_yday - 1) * 86400.0
        self._rng = np.random.default_rng(seed)
        self._forecast_rng = np.random.default_rng([seed, 1])
        self._boundary_rng = np.random.default_rng([seed, 2])
        self._to_ep: queue.Queue = queue.Queue(maxsize=1)
        self._from_ep: queue.Queue = queue.Queue(maxsize=1)
        self._rows: list[dict[str, float]] = []
        self._asked: list[dict[str, float]] = []  # the set points sent after each row (clipped)
        self._now: dict[str, float] | None = None
        self._thread: threading.Thread | None = None
        self._closed = False
        self._weather = outdoor_temperatures(self._em._epw)
        self.neighbours: dict[str, dict[str, float]] = {}
        self._dst = daylight_saving(self._em._objects, self._em.start.year)
        #: The controlled zones' floor areas, m2 (known once EnergyPlus has started).
        self.floor_area: dict[str, float] = {}

    @property
    def zone_names(self) -> tuple[str, ...]:
        """Every zone of the building (a neighbour's sensed temperature is a joint model's boundary)."""
        return self._em.zone_names

    # --- the EnergyPlus side (worker thread) ---------------------------------------------------

    def _actuators(self) -> dict[str, Actuator]:
        acts = {}
        for z in self.zones:
            acts[f"heating_{z}"] = Actuator("Zone Temperature Control", "Heating Setpoint", z)
            acts[f"cooling_{z}"] = Actuator("Zone Temperature Control", "Cooling Setpoint", z)
        return acts

    def _extra(self) -> dict[str, tuple[str, str]]:
        extra = hvacmeters.requested(self._equipment)
        for z in self.zones:
            extra[f"sp_heating:{z}"] = ("Zone Thermostat Heating Setpoint Temperature", z)
            extra[f"sp_cooling:{z}"] = ("Zone Thermostat Cooling Setpoint Temperature", z)
        return extra

    def _controller(self, t: float, row: Mapping[str, float]) -> dict[str, float | None]:
        if not self.neighbours:  # EnergyPlus wrote eplusout.eio before the first time step
            geo = read_eio(
                (self._em.folder / "eplusout.eio").read_text(errors="replace"), self._em.zone_names
            )
            for z in self.zones:
                self.floor_area[z] = geo.zone(z).floor_area
                ua = geo.neighbours(z)
                total = sum(ua.values())
                self.neighbours[z] = {k: v / total for k, v in ua.items()} if total > 0 else {}
        self._from_ep.put(("row", t - self._t0, dict(row)))
        actions = self._to_ep.get()
        if actions is None:
            raise Stop
        return actions

    def _work(self) -> None:
        try:
            self._em.run(self._controller, self._actuators(), extra=self._extra())
            self._from_ep.put(("end", None, None))
        except Exception as exc:  # handed to the caller of step()
            self._from_ep.put(("error", None, exc))

    def _receive(self) -> dict[str, float]:
        try:
            kind, t, payload = self._from_ep.get(timeout=TIMEOUT_S)
        except queue.Empty:
            raise EmulatorError(f"EnergyPlus gave no step within {TIMEOUT_S:g} s") from None
        if kind == "error":
            self._closed = True
            raise payload
        if kind == "end":
            self._closed = True
            raise EmulatorError("the EnergyPlus run has ended (plant.end reached)")
        row = {**payload, "time": t}
        self._rows.append(row)
        self._now = row
        return row

    # --- the controller side -------------------------------------------------------------------

    def _started(self) -> dict[str, float]:
        if self._closed:
            raise EmulatorError("this EnergyPlus plant is closed")
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="energyplus", daemon=True)
            self._thread.start()
            self._receive()
        return self._now

    def describe(self) -> Mapping[str, object]:
        """The test's settings and the set-point limits every controller is held to."""
        em, sch = self._em, self.schedule
        rule = {
            "occupied_hours_weekdays": list(sch.hours),
            **{
                k: dict(zip(("heating_min", "heating_max", "cooling_min", "cooling_max"), v, strict=True))
                for k, v in SETPOINT_LIMITS.items()
            },
            "min_deadband_K": MIN_DEADBAND_K,
        }
        return {
            "plant": "energyplus",
            "emulator": "energyplus",
            "building": em.building,
            "weather": em.weather,
            "scenario": f"{em.building} {em.weather} {em.start:%m-%d}",
            "start": f"{em.start:%m-%d}",
            "days": em.days,
            "seed": self.seed,
            "price": self.price,
            "band": {"occupied": list(sch.occupied), "unoccupied": list(sch.unoccupied)},
            "forecast": self.forecast_kind,
            "dt": self.dt,
            "zones": list(self.zones),
            "constraints": {z: rule for z in self.zones},
        }

    def measure(self) -> Mapping[str, float]:
        """What the BMS reads now (sensed), without advancing."""
        return self._sensed(self._started())

    def _sensed(self, row: Mapping[str, float]) -> dict[str, float]:
        out = {"time": row["time"], "T_ahu": float("nan")}
        out["To"] = float(sense_temperature(np.array([row["To"]]), self._rng)[0])
        for z in self.zones:
            nodes = self._inlets[z]
            truth = np.array([row[f"Ti:{z}"], row[f"Ts:{nodes[0]}"]])
            out[f"Ti_{z}"], out[f"Ts_{z}"] = (float(v) for v in sense_temperature(truth, self._rng))
            out[f"m_{z}"] = float(sense_flow(np.array([sum(row[f"m:{n}"] for n in nodes)]), self._rng)[0])
            q = row.get(f"Pel:{z}", 0.0)
            out[f"Q_{z}"] = float(q * (1.0 + POWER_NOISE * self._rng.standard_normal()))
            weights = self.neighbours.get(z, {})
            if weights:
                sensed = sense_temperature(np.array([row[f"Ti:{n}"] for n in weights]), self._rng)
                out[f"Tsd_{z}"] = float(np.dot(list(weights.values()), sensed))
            else:
                out[f"Tsd_{z}"] = out["To"]
        others = sorted({n for w in self.neighbours.values() for n in w} - set(self.zones))
        if others:  # a joint model's boundaries: own noise stream, the zones' readings unchanged
            sensed = sense_temperature(np.array([row[f"Ti:{n}"] for n in others]), self._boundary_rng)
            out |= {f"Ti_{n}": float(v) for n, v in zip(others, sensed, strict=True)}
        return out

    def _limits(self, t: float) -> tuple[float, float, float, float]:
        occ = bool(self._occupied(np.array([t]))[0])
        return SETPOINT_LIMITS["occupied" if occ else "unoccupied"]

    def _commands(self, actions: Mapping[str, float]) -> dict[str, float | None]:
        cmds: dict[str, float | None] = {f"{k}_{z}": None for z in self.zones for k in ("heating", "cooling")}
        for name, value in actions.items():
            kind, _, zone = name.partition("_")
            if kind in ("m", "Ts"):
                raise EmulatorError(
                    f"action {name}: EnergyPlus's terminals do not follow flow or discharge set points"
                    " (docs/energyplus.md); act on Tset_<zone> or heating_/cooling_<zone>"
                )
            if zone not in self.zones or kind not in ("Tset", "heating", "cooling"):
                raise ParameterError(
                    f"unknown action {name!r}: give Tset_<zone>, heating_<zone> or cooling_<zone>"
                )
            v = float(value)
            if not np.isfinite(v):
                raise ParameterError(f"action {name} must be a finite set point, got {value!r}")
            if kind == "Tset":
                cmds[f"heating_{zone}"], cmds[f"cooling_{zone}"] = v - HALF_DEADBAND, v + HALF_DEADBAND
            else:
                cmds[f"{kind}_{zone}"] = v
        return self._clipped(cmds)

    def _clipped(self, cmds: dict[str, float | None]) -> dict[str, float | None]:
        """Commands held to the limits over the next step (see the module notes)."""
        now = self._now["time"]
        h_lo, h_hi, c_lo, c_hi = self._limits(now)
        h_lo2, h_hi2, c_lo2, c_hi2 = self._limits(now + self.dt - 1.0)
        h_lo, h_hi, c_lo, c_hi = max(h_lo, h_lo2), min(h_hi, h_hi2), max(c_lo, c_lo2), min(c_hi, c_hi2)
        for z in self.zones:
            h, c = cmds[f"heating_{z}"], cmds[f"cooling_{z}"]
            if c is not None:
                c = min(max(c, c_lo), c_hi)
            if h is not None:
                h = min(max(h, h_lo), h_hi)
                if c is not None:
                    h = min(h, c - MIN_DEADBAND_K)
            cmds[f"heating_{z}"], cmds[f"cooling_{z}"] = h, c
        return cmds

    def step(self, actions: Mapping[str, float]) -> Mapping[str, float]:
        """Hold ``actions`` for :attr:`dt` and return the measurements at the end of the step."""
        self._started()
        cmds = self._commands(actions)
        self._asked.append({k: (np.nan if v is None else v) for k, v in cmds.items()})
        self._to_ep.put(cmds)
        return self._sensed(self._receive())

    def _band(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        occ = self._occupied(t)
        sch = self.schedule
        return (
            occ,
            np.where(occ, sch.occupied[0], sch.unoccupied[0]),
            np.where(occ, sch.occupied[1], sch.unoccupied[1]),
        )

    def forecast(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """Outdoor temperature (with the scenario's error), price, band and limits from now."""
        now = self._started()["time"]
        t, step = forecast_times(now, self.dt, horizon, interval)
        occ, lo, hi = self._band(t)
        to = np.interp(t + self._t0, *self._weather) + forecast_error(
            self._error, t - now, self._forecast_rng
        )
        out = {"time": t, "To": to, "T_ahu": np.full_like(t, np.nan)}
        out["price"] = forecast_price(
            self.price, self._clock(now) + PRICE_SHIFT, self._clock(t) + PRICE_SHIFT
        )
        for z in self.zones:
            out[f"occupied_{z}"] = occ.astype(float)
            out[f"lower_{z}"], out[f"upper_{z}"] = lo, hi
        out.update(self.constraints(horizon, interval=step))
        return out

    def constraints(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """The set-point limits per control interval from now, the tightest in each (module notes)."""
        now = self._started()["time"]
        step = self.dt if interval is None else float(interval)
        n = forecast_steps(horizon, step)
        per = max(1, round(step / self.dt))
        t = now + step * np.arange(n)[:, None] + self.dt * np.arange(per)[None, :]
        lim = np.array([[self._limits(float(x)) for x in row] for row in t])  # (n, per, 4)
        out = {}
        for z in self.zones:
            out[f"heating_min_{z}"] = lim[:, :, 0].max(axis=1)
            out[f"heating_max_{z}"] = lim[:, :, 1].min(axis=1)
            out[f"cooling_min_{z}"] = lim[:, :, 2].max(axis=1)
            out[f"cooling_max_{z}"] = lim[:, :, 3].min(axis=1)
        return out

    def _clock(self, t: np.ndarray) -> np.ndarray:
        """Plant time (standard time) as the building's clock reads it: an hour on in daylight saving."""
        t = np.asarray(t, float)
        if self._dst is None:
            return t
        day = [self._em.start + dt.timedelta(days=int(d)) for d in np.floor(t / 86400.0).ravel()]
        shift = np.array([self._dst[0] <= d < self._dst[1] for d in day], dtype=float).reshape(t.shape)
        return t + 3600.0 * shift

    def _occupied(self, t: np.ndarray) -> np.ndarray:
        t = self._clock(t)
        day = np.floor(t / 86400.0).astype(int)
        weekday = np.array([(self._em.start + dt.timedelta(days=int(d))).weekday() < 5 for d in day])
        hour = (t % 86400.0) / 3600.0
        h0, h1 = self.schedule.hours
        return weekday & (hour >= h0) & (hour < h1)

    def kpis(self) -> Mapping[str, Any]:
        """Scores of the run so far from EnergyPlus's own values (see the module notes)."""
        rows = self._rows
        if not rows:
            raise ParameterError("nothing is scored yet: the plant has not stepped")
        # row k holds the step that ended at t_k, i.e. the interval (t_k - dt, t_k]
        t = np.array([r["time"] for r in rows]) - self.dt
        occ, lo, hi = self._band(t + self.dt)
        h, kwh = self.dt / 3600.0, self.dt / 3.6e6
        price = price_signal(self.price, self._clock(t) + PRICE_SHIFT)
        out: dict[str, Any] = {"emulator": "energyplus"}
        comfort, power, parts, violations = 0.0, np.zeros(len(rows)), dict.fromkeys(hvacmeters.PARTS, 0.0), 0
        flows, discharge = [], []
        for z in self.zones:
            ti = np.array([r[f"Ti:{z}"] for r in rows])
            kh = float(np.sum((np.clip(lo - ti, 0, None) + np.clip(ti - hi, 0, None)) * occ) * h)
            out[f"comfort_Kh_{z}"] = kh
            comfort += kh
            zp = hvacmeters.attribute(rows, self._equipment[z], self._inlets)
            for k, v in zp.items():
                parts[k] += float(v.sum() * kwh)
                power += v
            violations += self._violations(z, t)
            nodes = self._inlets[z]
            flows.append(np.array([sum(r[f"m:{n}"] for n in nodes) for r in rows]))
            discharge.append(np.array([r[f"Ts:{nodes[0]}"] for r in rows]))
        building = np.array([sum(r[f"meter:{m}"] for m in METERS) for r in rows])
        everything = sum(
            (
                hvacmeters.attribute(rows, eq, self._inlets)[p]
                for eq in self._equipment.values()
                for p in hvacmeters.PARTS
            ),
            np.zeros(len(rows)),
        )
        out.update(
            comfort_Kh=comfort,
            energy_kWh=float(power.sum() * kwh),
            cost=float((power * price).sum() * kwh),
            **{f"{k}_kWh": v for k, v in parts.items()},
            peak_power_kW=float(power.max() / 1000.0),
            peak_flow_kg_s=float(np.max(flows)),
            max_discharge_degC=float(np.max(discharge)),
            constraint_violations=violations,
            building_hvac_kWh=float(building.sum() * kwh),
            building_cost=float((building * price).sum() * kwh),
            unattributed_kWh=float((building - everything).sum() * kwh),
        )
        return out

    def _violations(self, z: str, t: np.ndarray) -> int:
        """Steps whose set points in effect lie outside the limits (module notes)."""
        bad = 0
        for r, tk in zip(self._rows, t, strict=True):
            h_lo, h_hi, c_lo, c_hi = self._limits(float(tk))
            h, c = r.get(f"sp_heating:{z}", np.nan), r.get(f"sp_cooling:{z}", np.nan)
            bad += int(not (h_lo - 1e-6 <= h <= h_hi + 1e-6 and c_lo - 1e-6 <= c <= c_hi + 1e-6))
        return bad

    def series(self, zone: str) -> dict[str, np.ndarray]:
        """The run so far: ``t`` (start of each step, s) and the zone's true ``Ti``, band, ``m``, ``Ts``,
        set points in effect and asked for (NaN: the building's own), attributed HVAC power (W)."""
        rows = self._rows
        t = np.array([r["time"] for r in rows]) - self.dt
        occ, lo, hi = self._band(t + self.dt)
        nodes = self._inlets[zone]
        parts = hvacmeters.attribute(rows, self._equipment[zone], self._inlets)
        return {
            "t": t,
            "Ti": np.array([r[f"Ti:{zone}"] for r in rows]),
            "lower": lo,
            "upper": hi,
            "occupied": occ,
            "m": np.array([sum(r[f"m:{n}"] for n in nodes) for r in rows]),
            "Ts": np.array([r[f"Ts:{nodes[0]}"] for r in rows]),
            "heating_sp": np.array([r.get(f"sp_heating:{zone}", np.nan) for r in rows]),
            "cooling_sp": np.array([r.get(f"sp_cooling:{zone}", np.nan) for r in rows]),
            **{
                f"{side}_asked": np.array([np.nan] + [a[f"{side}_{zone}"] for a in self._asked])[: len(rows)]
                for side in ("heating", "cooling")
            },
            "power_W": sum(parts.values()),
        }

    def prediction_scores(
        self, values: Mapping[str, np.ndarray], t: np.ndarray, model, *, zone: str, noise_floor: float
    ) -> dict[str, float | None]:
        """The model's prediction errors on this plant's measurements (:mod:`rczone.emulators.prediction`)."""
        from rczone.emulators.prediction import prediction_scores

        return prediction_scores(values, t, model, zone=zone, noise_floor=noise_floor)

    def close(self) -> None:
        """Stop EnergyPlus (if it still runs) and wait for its thread."""
        if self._thread is not None and self._thread.is_alive() and not self._closed:
            self._closed = True
            self._to_ep.put(None)
            while self._thread.is_alive():
                try:
                    self._from_ep.get(timeout=1.0)
                except queue.Empty:
                    pass
            self._thread.join()
        self._closed = True
