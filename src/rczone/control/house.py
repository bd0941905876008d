"""A heated house behind the :class:`~rczone.control.plant.Plant` protocol: one room and an electric heater.

The emulator ``house`` (:mod:`rczone.emulators.registry`) for controllers that decide a heat input
rather than a supply flow (issue 38, item 9). The plant is the ``TiTh+heater`` model of Bacher and
Madsen [1]_ (room air ``Ti`` and the heater's own capacity ``Th``, the power ``Ph`` into ``Th``)
with its capacities and envelope resistance moved 10-15 % from the built-in values
(:data:`MODEL_ERROR`: a model fitted or taken from the library is never the house), simulated by
the exact discretization of :class:`~rczone.control.model.ControlModel` one minute at a time. The
outdoor temperature is the virtual building's seeded winter weather
(:func:`rczone.virtual.weather.outdoor_temperature`); the room sensor adds seeded noise of
:data:`SENSOR_NOISE_K`. The run starts :data:`WARMUP` s before 6 pm at 20 degC and is scored from
6 pm on for ``days``.

Names (SI; ``house`` is the zone):

* **measurements**: ``time``, ``To``, ``Ti_house`` (sensed), ``P_house`` (the heater's power over
  the last step, W; NaN before the first);
* **action**: ``P_house``, the heater's power command, W. The heater delivers it clipped to
  ``[0, heat_limit]``; a command outside is counted in ``constraint_violations``;
* **forecasts**: ``time``, ``To`` (the diurnal curve shifted by the last measured error, as the
  virtual building's ``measured`` forecast), ``price``, ``lower_house``, ``upper_house``,
  ``occupied_house`` and the limits;
* **constraints**: ``heat_min_house`` (0 W) and ``heat_max_house`` (the heater's limit, W), one
  per control interval;
* **KPIs**: ``comfort_Kh`` (the true room temperature's distance outside the band over the
  occupied hours), ``energy_kWh`` and ``cost`` (the delivered heat, weighted by the price),
  ``peak_power_kW``, ``constraint_violations`` (commands outside the heater's limits); with a model,
  its prediction errors (:meth:`HousePlant.prediction_scores`).

The comfort band: 20-23 degC while occupied (7 am to 7 pm), 15-26 degC otherwise.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43(7) (2011) 1511-1522.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rczone import validation
from rczone.control.model import ControlModel
from rczone.control.plant import forecast_steps, forecast_times
from rczone.control.signals import PRICES, forecast_price, price_signal
from rczone.errors import ParameterError, did_you_mean
from rczone.virtual.emulator import DAY
from rczone.virtual.weather import NIGHT_START_HOUR, diurnal_curve, outdoor_temperature

ZONE = "house"
#: The house's structure (a built-in family of :mod:`rczone.models.library`).
TRUTH = "TiTh+heater"
#: The house's parameters as factors on the family's built-in values.
MODEL_ERROR = {"Ci": 1.15, "Ria": 0.9, "Ch": 0.9}
SEASON = "winter"
#: The plant's step, s.
STEP = 60.0
#: Warm-up before the first 6 pm, s (not scored).
WARMUP = 6 * 3600.0
#: Standard deviation of the room sensor's noise, K.
SENSOR_NOISE_K = 0.05
#: The heater's limit when none is given, W.
HEAT_LIMIT_W = 3000.0
#: Occupied hours (clock) and the comfort band, degC: occupied, then unoccupied.
OCCUPIED_HOURS = (7.0, 19.0)
BAND_OCCUPIED = (20.0, 23.0)
BAND_UNOCCUPIED = (15.0, 26.0)
#: Longest run, days.
MAX_DAYS = 60


def house_band(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lower, upper, occupied)`` at ``t`` (s from 6 pm)."""
    hour = (NIGHT_START_HOUR + np.asarray(t, float) / 3600.0) % 24.0
    occ = (hour >= OCCUPIED_HOURS[0]) & (hour < OCCUPIED_HOURS[1])
    lower = np.where(occ, BAND_OCCUPIED[0], BAND_UNOCCUPIED[0])
    return lower, np.where(occ, BAND_OCCUPIED[1], BAND_UNOCCUPIED[1]), occ


def _check(days: float, seed: int, price: str, heat_limit: float) -> None:
    if price not in PRICES:
        raise ParameterError(f"unknown price signal {price!r}; " + did_you_mean(str(price), PRICES))
    for value, what, top in ((days, "days", MAX_DAYS), (heat_limit, "heat_limit (W)", 1e7)):
        if isinstance(value, bool) or not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ParameterError(f"house: {what} must be a number in (0, {top:g}], got {value!r}")
        if not 0 < value <= top:
            raise ParameterError(f"house: {what} must be in (0, {top:g}], got {value!r}")
    if round(days * DAY / STEP) < 1:
        raise ParameterError(f"house: days must leave at least one scored minute, got {days!r}")
    validation.seed(seed)


class HousePlant:
    """A heated house as a :class:`~rczone.control.plant.Plant` (see the module notes).

    Parameters
    ----------
    days : float
        Scored days from 6 pm (after the warm-up).
    seed : int
        Weather and sensor noise (>= 0).
    price : {"flat", "tou", "dr"}
    heat_limit : float
        The heater's largest power, W.
    """

    dt = STEP
    zones = (ZONE,)

    def __init__(
        self, *, days: float = 1.0, seed: int = 0, price: str = "flat", heat_limit: float = HEAT_LIMIT_W
    ) -> None:
        from rczone.models import load_model

        _check(days, seed, price, heat_limit)
        self.days, self.seed, self.price, self.heat_limit = days, int(seed), price, float(heat_limit)
        base = load_model(TRUTH)
        self.truth = base.with_values({k: f * base.theta[k] for k, f in MODEL_ERROR.items()})
        cm = ControlModel(self.truth)
        self._d = cm.discrete(STEP, 0.0)
        self._inputs = cm.input_names
        self._defaults = dict(self.truth.inputs.defaults)
        n = round(days * DAY / STEP) + round(WARMUP / STEP)
        self.t = -WARMUP + STEP * np.arange(n + 1)
        rng = np.random.default_rng(self.seed)
        self.t_out = outdoor_temperature(SEASON, self.t, rng)
        self.noise = rng.normal(0.0, SENSOR_NOISE_K, self.t.size)
        self.x = np.full((self.t.size, len(cm.state_names)), 20.0)
        self.command = np.full(n, np.nan)
        self.power = np.full(n, np.nan)
        self.k = 0
        self.end = float(self.t[-1])

    @property
    def time(self) -> float:
        """Plant time now, s from 6 pm."""
        return float(self.t[self.k])

    def measure(self) -> dict[str, float]:
        """``time``, ``To``, ``Ti_house`` (sensed) and ``P_house`` (over the last step)."""
        k = self.k
        return {
            "time": self.time,
            "To": float(self.t_out[k]),
            f"Ti_{ZONE}": float(self.x[k, 0] + self.noise[k]),
            f"P_{ZONE}": float(self.power[k - 1]) if k else math.nan,
        }

    def step(self, actions: Mapping[str, float]) -> dict[str, float]:
        """Hold the heater's command ``P_house`` (W) for one minute; the measurements after it."""
        if self.k >= self.command.size:
            raise ParameterError(f"the test ended at {self.end:.0f} s; no step is left")
        name = f"P_{ZONE}"
        unknown = [a for a in actions if a != name]
        if unknown:
            raise ParameterError(f"unknown action {unknown[0]!r}; the house takes {name} (heater power, W)")
        p = actions.get(name)
        if p is None or isinstance(p, bool) or not math.isfinite(p):
            raise ParameterError(f"the house needs a finite action {name} (heater power, W), got {p!r}")
        k = self.k
        self.command[k] = float(p)
        self.power[k] = min(max(float(p), 0.0), self.heat_limit)  # what the heater can do
        values = {"To": self.t_out[k], "Ph": self.power[k]}
        u = np.array([values.get(n, self._defaults.get(n, 0.0)) for n in self._inputs])
        self.x[k + 1] = self._d.Ad @ self.x[k] + self._d.Bd @ u
        self.k += 1
        return self.measure()

    def _times(self, horizon: float, interval: float | None) -> tuple[np.ndarray, float]:
        return forecast_times(self.time, self.dt, horizon, interval)

    def forecast(self, horizon: float, *, interval: float | None = None) -> dict[str, np.ndarray]:
        """Forecasts over ``horizon`` s at ``interval`` s (see the module notes)."""
        times, iv = self._times(horizon, interval)
        now = np.array([self.time])
        to = diurnal_curve(SEASON, times) + (float(self.t_out[self.k]) - diurnal_curve(SEASON, now)[0])
        lower, upper, occ = house_band(times)
        return {
            "time": times,
            "To": to,
            "price": forecast_price(self.price, self.time, times),
            f"lower_{ZONE}": lower,
            f"upper_{ZONE}": upper,
            f"occupied_{ZONE}": occ.astype(float),
            **self.constraints(horizon, interval=iv),
        }

    def constraints(self, horizon: float, *, interval: float | None = None) -> dict[str, np.ndarray]:
        """``heat_min_house`` and ``heat_max_house`` (W), one per interval from now."""
        _, iv = self._times(horizon, interval)
        n = forecast_steps(horizon, iv)
        return {f"heat_min_{ZONE}": np.zeros(n), f"heat_max_{ZONE}": np.full(n, self.heat_limit)}

    def prediction_scores(
        self, values: Mapping[str, np.ndarray], t: np.ndarray, model, *, zone: str = ZONE, noise_floor: float
    ) -> dict[str, float | None]:
        """The model's prediction errors on the run's measurements (:mod:`rczone.control.prediction`).

        The outdoor temperature and the heater's metered power (the model's heater input,
        :func:`rczone.control.heating.heater_input`) averaged over each 10-min interval.
        """
        from rczone.control.heating import heater_input
        from rczone.control.prediction import PREDICTION_DT, averaged_scores

        k0 = int(np.searchsorted(t, 0.0))
        step = round(PREDICTION_DT / STEP)
        n = (len(t) - 1 - k0) // step

        def avg(a: np.ndarray) -> np.ndarray:
            return a[k0 : k0 + n * step].reshape(n, step).mean(axis=1)

        cols = {"To": avg(values["To"][:-1]), heater_input(model): avg(values[f"P_{zone}"][1:])}
        defaults = model.inputs.defaults
        u = np.column_stack(
            [cols.get(c, np.full(n, defaults.get(c, 0.0))) for c in model.network.input_names]
        )
        y = values[f"Ti_{zone}"][k0 : k0 + n * step : step]
        return averaged_scores(u, np.zeros((n, 0)), y, model, noise_floor=noise_floor)

    def series(self, zone: str = ZONE) -> dict[str, np.ndarray]:
        """The scored part of the run so far: ``t``, true ``Ti``, the band, delivered and commanded power."""
        k0 = int(np.searchsorted(self.t, 0.0))
        t = self.t[k0 : self.k]
        lower, upper, occ = house_band(t)
        return {
            "t": t,
            "Ti": self.x[k0 : self.k, 0],
            "lower": lower,
            "upper": upper,
            "occupied": occ,
            "power_W": self.power[k0 : self.k],
            "command_W": self.command[k0 : self.k],
        }

    def kpis(self) -> dict[str, Any]:
        """The scores of the run so far (see the module notes)."""
        s = self.series()
        if s["t"].size == 0:
            raise ParameterError("nothing is scored yet: the plant has not reached 6 pm")
        ti, p, cmd = s["Ti"], s["power_W"], self.command[: self.k]
        outside = np.maximum(s["lower"] - ti, 0.0) + np.maximum(ti - s["upper"], 0.0)
        kwh = STEP / 3.6e6
        tol = 1e-6 * self.heat_limit
        return {
            "comfort_Kh": float((outside * s["occupied"]).sum() * STEP / 3600.0),
            "energy_kWh": float(p.sum() * kwh),
            "cost": float((p * price_signal(self.price, s["t"])).sum() * kwh),
            "peak_power_kW": float(p.max() / 1e3),
            "constraint_violations": int(np.sum((cmd < -tol) | (cmd > self.heat_limit + tol))),
        }

    def describe(self) -> dict[str, Any]:
        """The test's settings and the heater's limits (what a result records)."""
        return {
            "plant": "heated house",
            "scenario": SEASON,
            "days": self.days,
            "seed": self.seed,
            "price": self.price,
            "band": "normal",
            "forecast": "measured",
            "constraints": {ZONE: {"heat_min_W": 0.0, "heat_max_W": self.heat_limit}},
        }
