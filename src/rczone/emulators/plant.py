"""EnergyPlus stepped by a controller: the plant interface of ``rczone.control.plant``, BOPTEST's shape.

:class:`EnergyPlusPlant` runs :class:`~rczone.emulators.energyplus.EnergyPlusEmulator` in a worker
thread. At the end of every zone time step EnergyPlus calls back; the callback hands the readings
to :meth:`EnergyPlusPlant.step` (or :meth:`~EnergyPlusPlant.measure`) through a queue and waits for
the next actions, so EnergyPlus advances exactly one step per call, as a BOPTEST test case [1]_.

Actions are **zone set points**, the actuators EnergyPlus's own HVAC honours (measured, see
docs/energyplus.md): ``Tset_<zone>`` (the thermostat's heating set point at ``Tset - 0.5 K`` and
cooling at ``Tset + 0.5 K``: a supervisory MPC), or ``heating_<zone>`` and ``cooling_<zone>``
separately; a zone without an action in a step runs on the building's own schedules (the
baseline). ``m_<zone>`` and ``Ts_<zone>`` (the virtual building's actions) are refused with one
line: the prototypes' terminals do not follow flow or discharge set points.

Measurements: ``time`` (s from the start of the run, 00:00 of the first day, local standard time),
``To``, ``T_ahu`` (NaN: the prototypes' AHUs are not read), and per controlled zone ``Ti_<zone>``,
``m_<zone>``, ``Ts_<zone>`` through the BMS sensors of :mod:`rczone.virtual.sensors` (the first
inlet node's discharge temperature, the summed flow). Forecasts are the weather file's own
outdoor temperature (BOPTEST's scenario without forecast error), a flat price, and the comfort band
of the prototypes' thermostat schedules: occupied on weekdays from :data:`OCCUPIED_HOURS`, 21 to 24
degC, otherwise 15.6 to 26.7 degC. Scores come from EnergyPlus's own values: comfort from the true
zone temperatures, energy and peak power from the building's ``Electricity:HVAC`` and
``NaturalGas:HVAC`` meters (the whole building's HVAC: fans, coils, reheat, plant).

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

import numpy as np

from rczone.emulators.catalog import outdoor_temperatures
from rczone.emulators.energyplus import Actuator, EnergyPlusEmulator
from rczone.emulators.session import METERS, Stop
from rczone.errors import EmulatorError, ParameterError
from rczone.virtual.sensors import sense_flow, sense_temperature

#: Occupied hours on weekdays (local standard time), and the comfort bands, degC.
OCCUPIED_HOURS = (7, 19)
OCCUPIED_BAND = (21.0, 24.0)
UNOCCUPIED_BAND = (15.6, 26.7)
#: Half the thermostat's dead band around ``Tset``, K; the set points an action may take, degC.
HALF_DEADBAND = 0.5
SETPOINT_RANGE = (10.0, 35.0)
#: Seconds a step waits for EnergyPlus before it gives up.
TIMEOUT_S = 600.0


class EnergyPlusPlant:
    """An EnergyPlus prototype as a plant (see the module notes).

    Parameters
    ----------
    building, weather, start, days, step_minutes
        As :class:`~rczone.emulators.energyplus.EnergyPlusEmulator`.
    zones : sequence of str
        The zones a controller runs.
    seed : int
        Seed of the sensor noise.
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
    ) -> None:
        self._em = EnergyPlusEmulator(building, weather, start=start, days=days, step_minutes=step_minutes)
        self.zones = tuple(self._em.zone(z) for z in zones)
        if not self.zones:
            raise ParameterError("a plant needs at least one zone a controller runs")
        self._inlets = {z.name: z.inlets for z in self._em.hvac if z.name in self.zones}
        for z, nodes in self._inlets.items():
            if not nodes:
                raise ParameterError(f"zone {z} has no air terminal: a controller cannot run it")
        self.dt = self._em.step_s
        self.end = days * 86400.0
        self._t0 = (self._em.start.timetuple().tm_yday - 1) * 86400.0
        self._rng = np.random.default_rng(seed)
        self._to_ep: queue.Queue = queue.Queue(maxsize=1)
        self._from_ep: queue.Queue = queue.Queue(maxsize=1)
        self._rows: list[dict[str, float]] = []
        self._now: dict[str, float] | None = None
        self._thread: threading.Thread | None = None
        self._closed = False
        self._weather = outdoor_temperatures(self._em._epw)

    # --- the EnergyPlus side (worker thread) ---------------------------------------------------

    def _actuators(self) -> dict[str, Actuator]:
        acts = {}
        for z in self.zones:
            acts[f"heating_{z}"] = Actuator("Zone Temperature Control", "Heating Setpoint", z)
            acts[f"cooling_{z}"] = Actuator("Zone Temperature Control", "Cooling Setpoint", z)
        return acts

    def _controller(self, t: float, row: Mapping[str, float]) -> dict[str, float | None]:
        self._from_ep.put(("row", t - self._t0, dict(row)))
        actions = self._to_ep.get()
        if actions is None:
            raise Stop
        return actions

    def _work(self) -> None:
        try:
            self._em.run(self._controller, self._actuators())
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
        """The test's settings (a result records them)."""
        em = self._em
        return {
            "emulator": "energyplus",
            "building": em.building,
            "weather": em.weather,
            "start": f"{em.start:%m-%d}",
            "days": em.days,
            "dt": self.dt,
            "zones": list(self.zones),
            "constraints": {"setpoint_range_degC": list(SETPOINT_RANGE), "actions": "zone set points"},
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
        return out

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
            if not SETPOINT_RANGE[0] <= v <= SETPOINT_RANGE[1]:
                raise ParameterError(
                    f"action {name} = {v:g} degC is outside {SETPOINT_RANGE[0]:g}..{SETPOINT_RANGE[1]:g}"
                )
            if kind == "Tset":
                cmds[f"heating_{zone}"], cmds[f"cooling_{zone}"] = v - HALF_DEADBAND, v + HALF_DEADBAND
            else:
                cmds[f"{kind}_{zone}"] = v
        return cmds

    def step(self, actions: Mapping[str, float]) -> Mapping[str, float]:
        """Hold ``actions`` for :attr:`dt` and return the measurements at the end of the step."""
        self._started()
        cmds = self._commands(actions)
        self._to_ep.put(cmds)
        return self._sensed(self._receive())

    def forecast(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """Outdoor temperature (the weather file's), price, comfort band and occupancy from now."""
        now = self._started()["time"]
        step = self.dt if interval is None else float(interval)
        t = now + step * np.arange(round(horizon / step) + 1)
        occ = self._occupied(t)
        out = {"time": t, "To": np.interp(t + self._t0, *self._weather), "price": np.ones_like(t)}
        out["T_ahu"] = np.full_like(t, np.nan)
        for z in self.zones:
            out[f"occupied_{z}"] = occ.astype(float)
            out[f"lower_{z}"] = np.where(occ, OCCUPIED_BAND[0], UNOCCUPIED_BAND[0])
            out[f"upper_{z}"] = np.where(occ, OCCUPIED_BAND[1], UNOCCUPIED_BAND[1])
        return out

    def constraints(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """The set-point limits per control interval (constant)."""
        step = self.dt if interval is None else float(interval)
        n = max(1, round(horizon / step))
        out = {}
        for z in self.zones:
            out[f"tset_min_{z}"] = np.full(n, SETPOINT_RANGE[0])
            out[f"tset_max_{z}"] = np.full(n, SETPOINT_RANGE[1])
        return out

    def _occupied(self, t: np.ndarray) -> np.ndarray:
        day = np.floor(t / 86400.0).astype(int)
        weekday = np.array([(self._em.start + dt.timedelta(days=int(d))).weekday() < 5 for d in day])
        hour = (t % 86400.0) / 3600.0
        return weekday & (hour >= OCCUPIED_HOURS[0]) & (hour < OCCUPIED_HOURS[1])

    def kpis(self) -> Mapping[str, float]:
        """Scores of the run so far from EnergyPlus's own values (see the module notes)."""
        if not self._rows:
            return {"comfort_Kh": 0.0, "energy_kWh": 0.0, "cost": 0.0, "peak_power_kW": 0.0}
        t = np.array([r["time"] for r in self._rows])
        occ = self._occupied(t)
        lo = np.where(occ, OCCUPIED_BAND[0], UNOCCUPIED_BAND[0])
        hi = np.where(occ, OCCUPIED_BAND[1], UNOCCUPIED_BAND[1])
        out = {}
        comfort = 0.0
        for z in self.zones:
            ti = np.array([r[f"Ti:{z}"] for r in self._rows])
            kh = float(np.sum(np.clip(lo - ti, 0, None) + np.clip(ti - hi, 0, None)) * self.dt / 3600.0)
            out[f"comfort_Kh_{z}"] = kh
            comfort += kh
        power = np.array([sum(r[f"meter:{m}"] for m in METERS) for r in self._rows])
        out["comfort_Kh"] = comfort
        out["energy_kWh"] = float(power.sum() * self.dt / 3.6e6)
        out["cost"] = out["energy_kWh"]  # flat price of one per kWh
        out["peak_power_kW"] = float(power.max() / 1000.0)
        for k in ("reheat_kWh", "cooling_kWh", "fan_kWh", "peak_flow_kg_s", "max_discharge_degC"):
            out[k] = float("nan")  # not separated from the building's meters here
        out["constraint_violations"] = 0.0
        return out

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
