"""The built-in controllers behind the :class:`~rczone.control.plant.Controller` protocol.

* :class:`ThermostatController`: a zone's own VAV thermostat (single-maximum sequence,
  :class:`rczone.virtual.control.VAVController`) acting every plant step on the sensed room
  temperature; with the schedule's set points it is the ``naive`` baseline;
* :class:`CommissionedThermostat`: the same thermostat as a building would be commissioned, the
  fair baseline: set points inside the scored band and an optimal (early) start (below);
* :class:`MPCController`: the reference economic MPC (:class:`rczone.control.mpc.MPC`), deciding
  every ``settings.dt`` and holding its flow and reheat power in between. Its forecast is built
  from the plant's in the model's own input order (:meth:`MPCController.model_forecast`): the
  outdoor and AHU temperatures and the band, price and flow limits from the plant's forecast, the
  neighbours' temperatures held at their last measurement (their mean for ``Tsd``), the rest
  from the model's defaults (e.g. ``Q``): :func:`rczone.control.inputs.model_inputs`.

**The commissioned thermostat.** Two rules of ordinary commissioning, each against a weakness
of the schedule's own set points (issue 33):

* *Set points inside the band*: the occupied heating set point :data:`SETPOINT_MARGIN_K` above
  the band's lower edge, and the cooling set point so far below the upper edge that the flow
  stages up (at ``cool + band_up``) :data:`SETPOINT_MARGIN_K` before the room reaches it; at
  least :data:`MIN_DEADBAND_K` apart. The margin covers the sensor's noise and 0.1 F resolution
  and the loops' overshoot, so the room is held inside the band, not on its edges.
* *Optimal start* (ASHRAE Guideline 36 [1]_, the warm-up and cool-down modes before occupancy;
  the rule of Park [2]_): in unoccupied mode the box switches to its occupied set points as soon
  as the time left before occupancy (from the plant's ``occupied_<zone>`` forecast) is no more
  than the time needed to reach them, ``lead = START_MARGIN + |error| / RECOVERY_RATE`` (error:
  the sensed temperature's distance to the occupied set point it must reach), at most
  :data:`MAX_LEAD`. From then on the box runs in occupied mode: its occupied minimum flow (more
  reheat capacity than the unoccupied one, as Guideline 36's warm-up uses), staging and reheat
  loop on the occupied set points.

References
----------
.. [1] ASHRAE Guideline 36-2018, *High-performance sequences of operation for HVAC systems*
   (zone-group operating modes: warm-up and cool-down with optimal start, at most 3 h ahead).
.. [2] C. Park, "An optimum start/stop control algorithm for heating and cooling systems in
   buildings", NBSIR 83-2720, National Bureau of Standards, 1983.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from rczone.control.inputs import model_inputs
from rczone.control.mpc import MPC, ControlAction, Forecast
from rczone.network import CP_AIR
from rczone.virtual.control import CONTROL_DT, ControllerConfig, VAVController
from rczone.virtual.scenarios import SURROUNDINGS


class ThermostatController:
    """A zone's VAV thermostat as a :class:`~rczone.control.plant.Controller`.

    Parameters
    ----------
    config : ControllerConfig
        Set points, schedule and loop settings.
    zone : str
    t_start : float
        Plant time of the first call, s (the flow may change at once).
    dt : float
        The plant's step, s.
    """

    horizon = 0.0

    def __init__(
        self, config: ControllerConfig, *, zone: str = "target", t_start: float = 0.0, dt: float = CONTROL_DT
    ) -> None:
        self.box = VAVController(config, t_start)
        self.zone = zone
        self.interval = dt

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """The flow level and the reheat coil's set point (see :class:`VAVController`)."""
        m, _ = self.box.step(t, measurements[f"Ti_{self.zone}"], measurements["T_ahu"])
        return {f"m_{self.zone}": m, f"Ts_{self.zone}": self.box.command}


#: Margin of the occupied set points inside the scored band, K.
SETPOINT_MARGIN_K = 0.2
#: Smallest distance between the heating and the cooling set point, K.
MIN_DEADBAND_K = 0.2
#: Recovery rate the optimal start assumes, K per s (1 K per hour).
RECOVERY_RATE = 1.0 / 3600.0
#: Fixed part of the optimal start's lead, s.
START_MARGIN = 1800.0
#: Longest optimal-start lead, s (Guideline 36's default limit).
MAX_LEAD = 3 * 3600.0


def commissioned(config: ControllerConfig) -> ControllerConfig:
    """``config`` with its occupied set points inside the band (see the module notes)."""
    heat = config.heat_occ + SETPOINT_MARGIN_K
    cool = max(config.cool_occ - SETPOINT_MARGIN_K - config.band_up, heat + MIN_DEADBAND_K)
    return replace(config, heat_occ=heat, cool_occ=cool)


class _EarlyBox(VAVController):
    """A VAV box whose occupied mode can begin before the schedule's (an optimal start)."""

    early = False

    def _mode(self, t: float) -> bool:
        return self.cfg.unoccupied(t) and not self.early


class CommissionedThermostat(ThermostatController):
    """The zone's thermostat as commissioned: set points inside the band, optimal start (module notes).

    Parameters
    ----------
    config : ControllerConfig
        The schedule's settings (the band); its occupied set points are moved inside it.
    zone : str
    t_start : float
        Plant time of the first call, s.
    dt : float
        The plant's step, s.
    """

    horizon = MAX_LEAD

    def __init__(
        self, config: ControllerConfig, *, zone: str = "target", t_start: float = 0.0, dt: float = CONTROL_DT
    ) -> None:
        self.box = _EarlyBox(commissioned(config), t_start)
        self.zone = zone
        self.interval = dt

    def lead(self, t_sensed: float) -> float:
        """The time needed to reach the occupied set points from ``t_sensed`` degC, s."""
        c = self.box.cfg
        error = max(c.heat_occ - t_sensed, t_sensed - (c.cool_occ + c.band_up), 0.0)
        return min(START_MARGIN + error / RECOVERY_RATE, MAX_LEAD)

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Start early when occupancy is within the lead; otherwise the thermostat's sequence."""
        z = self.zone
        ti = measurements[f"Ti_{z}"]
        occ = np.asarray(forecast.get(f"occupied_{z}", [1.0]), float) > 0.5
        ahead = float(np.argmax(occ)) * self.interval if occ.any() else np.inf
        self.box.early = bool(not occ[0] and ahead <= self.lead(ti))
        m, _ = self.box.step(t, ti, measurements["T_ahu"])
        return {f"m_{z}": m, f"Ts_{z}": self.box.command}


class MPCController:
    """The reference MPC as a :class:`~rczone.control.plant.Controller` (see the module notes).

    Parameters
    ----------
    mpc : MPC
    zone : str
        The zone it runs; its model's output ``Ti`` is the measurement ``Ti_<zone>``.
    surroundings : mapping of str to str
        Model input name -> zone whose measured temperature it is (held over the horizon).
    """

    def __init__(
        self, mpc: MPC, *, zone: str = "target", surroundings: Mapping[str, str] = SURROUNDINGS
    ) -> None:
        self.mpc = mpc
        self.zone = zone
        self.surroundings = dict(surroundings)
        self.interval = mpc.settings.dt
        self.horizon = mpc.settings.horizon * mpc.settings.dt
        self.next_time: float | None = None
        self.action: ControlAction | None = None
        self.solve_times: list[float] = []

    def model_forecast(
        self, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]
    ) -> Forecast:
        """The plant's forecast in the model's inputs and conventions (see the module notes)."""
        n = len(forecast["time"])
        held = {c: np.full(n, measurements[f"Ti_{z}"]) for c, z in self.surroundings.items()}
        series = {"To": forecast["To"], **held}
        inputs = model_inputs(self.mpc.cm.model, series, n, decided=self.mpc.heaters)
        z = self.zone
        return Forecast(
            inputs,
            forecast["T_ahu"],
            forecast[f"lower_{z}"],
            forecast[f"upper_{z}"],
            forecast["price"],
            m_min=forecast[f"m_min_{z}"],
            m_max=forecast[f"m_max_{z}"],
        )

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Every ``settings.dt``: observe and plan; in between, hold the flow and the reheat power."""
        if self.next_time is None or t >= self.next_time - 1e-9:
            fc = self.model_forecast(measurements, forecast)
            self.action = self.mpc.step(t, {"Ti": measurements[f"Ti_{self.zone}"]}, fc)
            self.solve_times.append(self.action.plan.solve_time)
            self.next_time = t + self.mpc.settings.dt
        a = self.action
        ts = min(measurements["T_ahu"] + a.reheat / (a.m * CP_AIR), self.mpc.limits.ts_max)
        return {f"m_{self.zone}": a.m, f"Ts_{self.zone}": ts}


class OracleController(MPCController):
    """The MPC with what no real controller has: the limit a model-based controller can approach.

    The true plant's model (the reduced model of the zone's *true* construction, not the nominal
    one a modeller would use), the true room temperature (no sensor noise or quantization), the
    true forecast of the weather, AHU temperature and price, and the true internal gains (the
    daytime gains no other model knows) as its heat input ``Q``. Its gap to another controller is
    what better models, sensing and forecasts could gain at most (at the reduced model's order).

    Parameters
    ----------
    mpc : MPC
        Built on the true construction's model.
    plant : VirtualPlant
        Read for the truth (:meth:`VirtualPlant.true_forecast`, :meth:`VirtualPlant.true_temperature`).
    zone : str
    """

    def __init__(self, mpc: MPC, plant, *, zone: str = "target") -> None:
        super().__init__(mpc, zone=zone)
        self.plant = plant

    def model_forecast(
        self, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]
    ) -> Forecast:
        """The MPC's forecast with the true internal gains as ``Q``."""
        fc = super().model_forecast(measurements, forecast)
        if "Q" in self.mpc.cm.input_names:
            fc = replace(fc, inputs={**fc.inputs, "Q": forecast[f"Q_{self.zone}"]})
        return fc

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """The MPC's step on the true temperature and the true forecast."""
        truth = {**measurements, f"Ti_{self.zone}": self.plant.true_temperature(self.zone)}
        return super().act(t, truth, self.plant.true_forecast(self.horizon, interval=self.interval))
