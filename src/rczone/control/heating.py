"""Controllers of a heat input (an electric heater, a radiator circuit): a thermostat and the MPC.

For a plant whose zone is heated by a power it is told (``P_<zone>``, W, within the forecast's
``heat_min_<zone>`` and ``heat_max_<zone>``: :class:`rczone.control.house.HousePlant`), the
counterparts of :mod:`rczone.control.controllers`, held to the same limits and told the same:

* :class:`HeaterThermostat`: the baseline as a house would be commissioned, a PI loop on the sensed
  room temperature (anti-windup by conditional integration, Åström and Hägglund [1]_, section 3.5)
  with its set point :data:`~rczone.control.controllers.SETPOINT_MARGIN_K` inside the band's lower
  edge and the optimal start of :class:`~rczone.control.controllers.CommissionedThermostat`
  (switching to the occupied set point as soon as occupancy is within the time the recovery needs),
  its output clipped to the heater's limits;
* :class:`HeaterMPCController`: the reference MPC (:class:`rczone.control.mpc.MPC`) deciding the
  model's heater input with the plant's limits as ``MPCSettings.heat_limits``, every ``settings.dt``,
  holding its power in between; it aims at the band narrowed by the thermostat's margin on each side
  (the same cover for the sensor's noise and the model's error).

References
----------
.. [1] K. J. Åström, T. Hägglund, *Advanced PID Control*, ISA, 2006.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from rczone.control.controllers import MAX_LEAD, RECOVERY_RATE, SETPOINT_MARGIN_K, START_MARGIN
from rczone.control.inputs import input_roles, model_inputs
from rczone.control.mpc import MPC, Forecast, MPCSettings
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel

#: The PI loop's integral time, s.
INTEGRAL_TIME = 3600.0
#: The room-temperature error at which the PI loop's proportional part asks for the full power, K.
FULL_POWER_ERROR_K = 2.0


def heat_limits(plant, zone: str) -> tuple[float, float]:
    """The heater's ``(lowest, highest)`` power of ``zone`` (W) from the plant's constraints."""
    c = plant.constraints(plant.dt, interval=plant.dt)
    return float(c[f"heat_min_{zone}"][0]), float(c[f"heat_max_{zone}"][0])


class HeaterThermostat:
    """A commissioned PI thermostat of a heater (see the module notes).

    Parameters
    ----------
    zone : str
    limits : (float, float)
        The heater's lowest and highest power, W (the proportional gain gives the highest at
        :data:`FULL_POWER_ERROR_K`).
    dt : float
        The plant's step, s.
    """

    horizon = MAX_LEAD

    def __init__(self, *, zone: str, limits: tuple[float, float], dt: float) -> None:
        self.zone, self.limits, self.interval = zone, limits, dt
        self.kp = max(limits[1], 1.0) / FULL_POWER_ERROR_K
        self.integral = 0.0

    def setpoint(self, ti: float, forecast: Mapping[str, np.ndarray]) -> float:
        """The band's lower edge plus the margin; the occupied one within the optimal start's lead."""
        z = self.zone
        lower = np.asarray(forecast[f"lower_{z}"], float)
        occ = np.asarray(forecast[f"occupied_{z}"], float) > 0.5
        target = lower[0]
        if not occ[0] and occ.any():
            first = int(np.argmax(occ))
            error = max(lower[first] + SETPOINT_MARGIN_K - ti, 0.0)
            if first * self.interval <= min(START_MARGIN + error / RECOVERY_RATE, MAX_LEAD):
                target = lower[first]
        return target + SETPOINT_MARGIN_K

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """The heater's power for the next step."""
        ti = measurements[f"Ti_{self.zone}"]
        e = self.setpoint(ti, forecast) - ti
        lo = max(self.limits[0], float(forecast[f"heat_min_{self.zone}"][0]))
        hi = min(self.limits[1], float(forecast[f"heat_max_{self.zone}"][0]))
        raw = self.kp * e + self.integral
        p = float(np.clip(raw, lo, hi))
        if raw == p or (raw > hi and e < 0) or (raw < lo and e > 0):  # integrate unless it winds up
            self.integral += self.kp * e * self.interval / INTEGRAL_TIME
        return {f"P_{self.zone}": p}


def heater_input(model: ZoneModel) -> str:
    """The model's heater input: the one heat input it declares an actuator, else ``Ph``.

    Raises
    ------
    ParameterError
        For a model with neither (naming its inputs).
    """
    air = {s.temperature for s in model.network.supply_air}
    declared = [n for n, r in model.inputs.roles.items() if r == "actuator" and n not in air]
    if len(declared) == 1:
        return declared[0]
    names = list(input_roles(model))
    if not declared and "Ph" in names:
        return "Ph"
    raise ParameterError(
        f"model {model.name!r} has no single heater input to decide (an input Ph, or one declared an "
        f"actuator in the model file's inputs.roles); its inputs are {names}"
    )


class HeaterMPCController:
    """The reference MPC deciding a heater within the plant's limits (see the module notes).

    Parameters
    ----------
    model : ZoneModel
    settings : MPCSettings or None
        Its ``heat_limits`` are replaced by the plant's for the model's heater input.
    limits : (float, float)
        The heater's lowest and highest power, W.
    zone : str
    disturbance : Disturbance or None
        The observer's disturbance state.
    """

    def __init__(self, model: ZoneModel, settings, *, limits, zone: str, disturbance) -> None:
        self.heater = heater_input(model)
        settings = replace(settings or MPCSettings(), heat_limits={self.heater: tuple(limits)})
        self.mpc = MPC(model, settings, disturbance=disturbance)
        self.zone = zone
        self.interval = settings.dt
        self.horizon = settings.horizon * settings.dt
        self.next_time: float | None = None
        self.power = 0.0
        self.solve_times: list[float] = []

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Every ``settings.dt``: observe and plan; in between, hold the heater's power."""
        if self.next_time is None or t >= self.next_time - 1e-9:
            z, n = self.zone, len(forecast["time"])
            inputs = model_inputs(self.mpc.cm.model, {"To": forecast["To"]}, n, decided=self.mpc.heaters)
            lower = np.asarray(forecast[f"lower_{z}"], float) + SETPOINT_MARGIN_K
            upper = np.maximum(np.asarray(forecast[f"upper_{z}"], float) - SETPOINT_MARGIN_K, lower)
            fc = Forecast(inputs, None, lower, upper, forecast["price"])
            action = self.mpc.step(t, {"Ti": measurements[f"Ti_{z}"]}, fc)
            lo, hi = self.mpc.settings.heat_limits[self.heater]
            self.power = float(np.clip(action.heat[self.heater], lo, hi))  # the QP's tolerance
            self.solve_times.append(action.plan.solve_time)
            self.next_time = t + self.mpc.settings.dt
        return {f"P_{self.zone}": self.power}
