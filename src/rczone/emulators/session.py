"""One EnergyPlus state: the variables requested, the handles, and the time-step callback.

EnergyPlus calls Python back from inside ``run_energyplus``; an exception raised in a callback is
lost in the C library, so the callback keeps the first error, asks EnergyPlus to stop, and
:meth:`Session.run` hands the error back after the run has ended. Handles can only be had once
EnergyPlus has read its input (``api_data_fully_ready``), so they are looked up at the first
call; a handle of ``-1`` is a name EnergyPlus does not know: a variable it has no key for, or an
actuator it refuses (the component does not exist, or does not offer that control).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rczone.emulators.idf import ZoneHvac
from rczone.errors import EmulatorError

#: (label prefix, EnergyPlus variable) read for every zone, and for every inlet node.
ZONE_VARIABLES = (("Ti", "Zone Mean Air Temperature"),)
GAIN_VARIABLES = ("Zone Lights Electricity Rate", "Zone Electric Equipment Electricity Rate")
NODE_VARIABLES = (("Ts", "System Node Temperature"), ("m", "System Node Mass Flow Rate"))
OUTDOOR = ("Site Outdoor Air Drybulb Temperature", "Environment")
#: Meters read each step (J over the step, turned into W).
METERS = ("Electricity:HVAC", "NaturalGas:HVAC")
#: EnergyPlus's kind of simulation for a weather-file run period (not sizing, not design days).
RUN_PERIOD_WEATHER = 3


class Stop(Exception):
    """Raised by a controller to end the run early, cleanly (what was read so far is kept)."""


class Session:
    """Runs one EnergyPlus state with the rczone callback (see the module notes).

    Parameters
    ----------
    api : pyenergyplus.api.EnergyPlusAPI
    zones : sequence of ZoneHvac
        The zones and their inlet nodes.
    actuators : mapping of str to Actuator
        What the controller may set, by label.
    controller : callable, optional
        As in :meth:`rczone.emulators.energyplus.EnergyPlusEmulator.run`.
    extra : mapping of str to (str, str), optional
        More output variables ``(variable, key)`` to read each step, by row label; one EnergyPlus
        does not have for this building reads zero (e.g. a DX coil's defrost heater).
    """

    def __init__(
        self,
        api: Any,
        zones: Sequence[ZoneHvac],
        actuators: Mapping,
        controller,
        extra: Mapping[str, tuple[str, str]] | None = None,
    ) -> None:
        self.api = api
        self.zones = tuple(zones)
        self.actuators = dict(actuators)
        self.controller = controller
        self.rows: list[dict[str, float]] = []
        self.error: BaseException | None = None
        self._variables: dict[str, tuple[str, str]] = {"To": OUTDOOR}
        for z in self.zones:
            self._variables[f"Ti:{z.name}"] = (ZONE_VARIABLES[0][1], z.name)
            for n in z.inlets:
                for prefix, var in NODE_VARIABLES:
                    self._variables[f"{prefix}:{n}"] = (var, n)
        self._gains = {z.name: [(v, z.name) for v in GAIN_VARIABLES] for z in self.zones}
        self._extra = dict(extra or {})
        self._extra_handles: dict[str, int] = {}
        self._handles: dict[str, int] | None = None
        self._gain_handles: dict[str, list[int]] = {}
        self._meters: dict[str, int] = {}
        self._act: dict[str, int] = {}
        self._set: dict[str, float | None] = {}

    def run(self, args: list[str]) -> int:
        """Run EnergyPlus with command-line ``args``; returns its exit code."""
        api = self.api
        state = api.state_manager.new_state()
        try:
            api.runtime.set_console_output_status(state, False)
            gains = (p for g in self._gains.values() for p in g)
            for var, key in (*self._variables.values(), *gains, *self._extra.values()):
                api.exchange.request_variable(state, var, key)
            api.runtime.callback_end_zone_timestep_after_zone_reporting(state, self._callback)
            return api.runtime.run_energyplus(state, args)
        finally:
            api.state_manager.delete_state(state)

    def _fail(self, state, error: Exception) -> None:
        if self.error is None:
            self.error = error
        self.api.runtime.stop_simulation(state)

    def _lookup(self, state) -> None:
        ex = self.api.exchange
        handles = {k: ex.get_variable_handle(state, *vk) for k, vk in self._variables.items()}
        missing = [f"{v[0]} of {v[1]}" for k, v in self._variables.items() if handles[k] < 0]
        if missing:
            raise EmulatorError(f"EnergyPlus has no output variable {missing[0]} in this building")
        self._gain_handles = {
            z: [h for h in (ex.get_variable_handle(state, *p) for p in pairs) if h >= 0]
            for z, pairs in self._gains.items()
        }
        self._meters = {m: ex.get_meter_handle(state, m) for m in METERS}
        self._extra_handles = {k: ex.get_variable_handle(state, *vk) for k, vk in self._extra.items()}
        for label, act in self.actuators.items():
            h = ex.get_actuator_handle(state, act.component, act.control, act.key)
            if h < 0:
                raise EmulatorError(
                    f"EnergyPlus refuses the actuator {act} ({label}): this building has no such"
                    " component or it offers no such control (see its eplusout.edd)"
                )
            self._act[label] = h
        self._handles = handles

    def _callback(self, state) -> None:
        if self.error is not None:
            return
        try:
            self._step(state)
        except Stop:
            self.api.runtime.stop_simulation(state)
            self.error = Stop()
        except (
            BaseException
        ) as exc:  # kept and raised after the run (Ctrl-C too): a callback cannot raise into C
            self._fail(state, exc)

    def _step(self, state) -> None:
        ex = self.api.exchange
        if not ex.api_data_fully_ready(state):
            return
        if self._handles is None:
            self._lookup(state)
        if ex.warmup_flag(state) or ex.kind_of_sim(state) != RUN_PERIOD_WEATHER:
            return
        dt = ex.zone_time_step(state) * 3600.0
        # the end of this zone time step (current_time is the last HVAC sub-step's when there are several)
        t = (ex.day_of_year(state) - 1) * 86400.0 + ex.hour(state) * 3600.0
        t += round(ex.zone_time_step_number(state) * dt)
        row = {"t": t}
        row.update({k: ex.get_variable_value(state, h) for k, h in self._handles.items()})
        for z, hs in self._gain_handles.items():
            row[f"Pel:{z}"] = sum(ex.get_variable_value(state, h) for h in hs)
        row.update(
            {k: ex.get_variable_value(state, h) if h >= 0 else 0.0 for k, h in self._extra_handles.items()}
        )
        for m in METERS:
            row[f"meter:{m}"] = (
                ex.get_meter_value(state, self._meters[m]) / dt if self._meters[m] >= 0 else 0.0
            )
        if self.controller is not None:
            self._actuate(state, t, row)
        row.update({f"cmd:{k}": (float("nan") if v is None else v) for k, v in self._set.items()})
        self.rows.append(row)

    def _actuate(self, state, t: float, row: Mapping[str, float]) -> None:
        ex = self.api.exchange
        values = self.controller(t, dict(row)) or {}
        for label, value in values.items():
            if label not in self._act:
                raise EmulatorError(f"the controller set {label!r}, which is not one of its actuators")
            if value is None:
                ex.reset_actuator(state, self._act[label])
            else:
                ex.set_actuator_value(state, self._act[label], float(value))
            self._set[label] = value
