"""The virtual building behind the :class:`~rczone.control.plant.Plant` protocol.

The plant is the full virtual building (:mod:`rczone.virtual`: the 152-state floor, its other
zones under their own thermostats, seeded weather, AHU drift, sensor noise and quantization,
and daytime gains of occupants and equipment that no zone model knows about), run from
``warmup`` s before 6 pm for ``days`` with the schedules repeating daily, one minute per
:meth:`VirtualPlant.step` (:class:`rczone.virtual.emulator.Simulation`). The controlled zones'
reheat coils are part of the plant: the action ``Ts_<zone>`` is the coil's set point, clipped to
``[T_ahu, ts_max]`` and reached through the coil's first-order lag
(:func:`rczone.virtual.control.coil_lag`).

Forecasts (``forecast=``):

* ``measured`` (default): the outdoor temperature's diurnal curve shifted by the last measured
  error (:func:`rczone.virtual.weather.diurnal_curve`), the AHU temperature held, the price as
  announced (a demand-response event only from its notice on);
* ``perfect``: the true outdoor and AHU temperatures of the run (held past its end) and the
  true price (every event known in advance);
* ``biased``: the measured forecast :data:`FORECAST_BIAS_K` warmer (a systematic error).

The comfort band and the limits (:class:`~rczone.control.constraints.ZoneConstraints`) follow
the zone thermostat's schedule, or its occupied band narrowed (``comfort_band="tight"``).

Scores (:meth:`VirtualPlant.kpis`, from 6 pm of the first day on; the warm-up is not scored):
``comfort_Kh`` (the integral of the true room temperature's distance outside the occupied band
over the occupied hours), ``energy_kWh`` (:mod:`rczone.control.energy`), ``cost`` (the energy
weighted by the price), ``peak_flow_kg_s``, ``max_discharge_degC``, ``constraint_violations``
(minutes outside the zone's limits) and, with ``price="dr"``, the same over the event windows
(``event_energy_kWh``, ``event_cost``, ``event_peak_flow_kg_s``, ``event_comfort_Kh``). These are
the scores of a closed-loop test in Sturzenegger et al. [1]_.

References
----------
.. [1] D. Sturzenegger, D. Gyalistras, M. Morari, R. S. Smith, "Model predictive climate
   control of a Swiss office building: implementation, results, and cost-benefit analysis",
   IEEE Trans. Control Systems Technology 24(1) (2016) 1-12.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rczone import validation
from rczone.control.constraints import ZoneConstraints
from rczone.control.energy import zone_power
from rczone.control.plant import forecast_steps, forecast_times
from rczone.control.signals import (
    BANDS,
    DR_HOURS,
    DR_PRICE,
    PRICES,
    band,
    forecast_price,
    price_signal,
    tighten,
    window,
)
from rczone.errors import ParameterError, did_you_mean
from rczone.virtual.building import build_building
from rczone.virtual.control import CONTROL_DT, coil_lag
from rczone.virtual.emulator import DAY, DAY_GAIN, Simulation, day_gain_share
from rczone.virtual.weather import diurnal_curve

SEASONS = ("summer", "winter")
FORECASTS = ("measured", "perfect", "biased")
#: The biased forecast's outdoor-temperature error, K.
FORECAST_BIAS_K = 2.0
#: Warm-up before the first 6 pm, s (observers settle; not scored).
WARMUP = 6 * 3600.0
#: Longest run, days.
MAX_DAYS = 60


def check_run(season: str, days: float, seed: int, price: str, comfort_band: str, forecast: str) -> None:
    """Refuse a test that cannot run or leaves nothing to score, in one line (:class:`ParameterError`)."""
    for value, allowed, what in (
        (season, SEASONS, "scenario"),
        (price, PRICES, "price signal"),
        (comfort_band, BANDS, "comfort band"),
        (forecast, FORECASTS, "forecast"),
    ):
        if value not in allowed:
            raise ParameterError(f"unknown {what} {value!r}; " + did_you_mean(str(value), allowed))
    if isinstance(days, bool) or not (isinstance(days, (int, float)) and math.isfinite(days)):
        raise ParameterError(f"days must be a number in (0, {MAX_DAYS}], got {days!r}")
    if not (0 < days <= MAX_DAYS) or round(days * DAY / CONTROL_DT) < 1:
        raise ParameterError(
            f"days must be in (0, {MAX_DAYS}] and leave at least one scored minute "
            f"({CONTROL_DT / DAY:.6g} days), got {days!r}"
        )
    validation.seed(seed)


class VirtualPlant:
    """The virtual building as a :class:`~rczone.control.plant.Plant` (see the module notes).

    Parameters
    ----------
    season : {"summer", "winter"}
    days : float
        Scored days from 6 pm (after the warm-up).
    seed : int
        Weather, thermostat settings, AHU drift and sensor noise (>= 0).
    price : {"flat", "tou", "dr"}
    comfort_band : {"normal", "tight"}
    forecast : {"measured", "perfect", "biased"}
    zones : tuple of str
        The zones an outside controller runs (default the target); the others keep their thermostats.
    """

    dt = CONTROL_DT

    def __init__(
        self,
        season: str = "summer",
        *,
        days: float = 1.0,
        seed: int = 0,
        price: str = "flat",
        comfort_band: str = "normal",
        forecast: str = "measured",
        zones: tuple[str, ...] = ("target",),
    ) -> None:
        check_run(season, days, seed, price, comfort_band, forecast)
        self.bld = build_building()
        for z in zones:
            if z not in self.bld.zones:
                raise ParameterError(f"unknown zone {z!r}; " + did_you_mean(z, self.bld.zones))
        self.season, self.days, self.seed = season, days, int(seed)
        self.price, self.comfort_band, self.forecast_kind = price, comfort_band, forecast
        self.zones = tuple(zones)
        self.sim = Simulation(
            self.bld,
            season,
            np.random.default_rng(int(seed)),
            duration=round(days * DAY / CONTROL_DT) * CONTROL_DT,
            warmup=WARMUP,
            daily=True,
        )
        cf = self.sim.configs
        #: The controlled zones' thermostat settings (band, schedule), narrowed for a tight band.
        self.configs = {z: tighten(cf[z]) if comfort_band == "tight" else cf[z] for z in self.zones}
        self.limits = {z: ZoneConstraints.from_config(c) for z, c in self.configs.items()}
        self.end = float(self.sim.t[-1])
        self._coil: dict[str, float | None] = dict.fromkeys(self.zones)
        self._col = {z: j for j, z in enumerate(self.bld.zones)}

    # ------------------------------------------------------------ the protocol
    @property
    def time(self) -> float:
        """Plant time now, s from 6 pm."""
        return float(self.sim.t[self.sim.k])

    def measure(self) -> dict[str, float]:
        """What the BMS reads now (see :mod:`rczone.control.plant`; flows NaN before the first step)."""
        s, k = self.sim, self.sim.k
        out = {"time": self.time, "To": float(s.t_out[k]), "T_ahu": float(s.t_ahu[k])}
        for z, j in self._col.items():
            out[f"Ti_{z}"] = float(s.sensed[k, j])
            out[f"m_{z}"] = float(s.m[k - 1, j]) if k else math.nan
            out[f"Ts_{z}"] = float(s.u[k - 1, s._ts[j]]) if k else math.nan
        return out

    def step(self, actions: Mapping[str, float]) -> dict[str, float]:
        """Hold ``actions`` (``m_<zone>``, ``Ts_<zone>``) for one minute; the measurements after it."""
        if self.sim.done:
            raise ParameterError(f"the test ended at {self.end:.0f} s; no step is left")
        needed = [f"{v}_{z}" for z in self.zones for v in ("m", "Ts")]
        for name in actions:
            if name not in needed:
                raise ParameterError(f"unknown action {name!r}; " + did_you_mean(str(name), needed))
        held = {}
        t_ahu = float(self.sim.t_ahu[self.sim.k])
        for z in self.zones:
            m, ts = (actions.get(f"{v}_{z}") for v in ("m", "Ts"))
            if m is None or ts is None or not (math.isfinite(m) and math.isfinite(ts)):
                raise ParameterError(f"zone {z!r} needs finite actions m_{z} and Ts_{z}, got {m!r}, {ts!r}")
            lim = self.limits[z]
            m = min(max(float(m), 0.0), lim.flow_max)  # what the damper can do
            self._coil[z] = coil_lag(
                self._coil[z], min(max(float(ts), t_ahu), lim.ts_max), self.configs[z].tau_coil
            )
            held[z] = (m, self._coil[z])
        self.sim.advance(held)
        return self.measure()

    def _times(self, horizon: float, interval: float | None) -> tuple[np.ndarray, float]:
        return forecast_times(self.time, self.dt, horizon, interval)

    def _truth(self, series: np.ndarray, times: np.ndarray) -> np.ndarray:
        """A true series of the run at ``times`` (held past the run's last value)."""
        t = self.sim.t
        idx = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(series) - 1)
        return series[idx]

    def forecast(self, horizon: float, *, interval: float | None = None) -> dict[str, np.ndarray]:
        """Forecasts over ``horizon`` s at ``interval`` s (see the module notes and the protocol)."""
        return self._forecast(self.forecast_kind, horizon, interval)

    def true_forecast(self, horizon: float, *, interval: float | None = None) -> dict[str, np.ndarray]:
        """The perfect forecast whatever the test's kind, with the zones' true internal gains ``Q_<zone>`` (W).

        What only an oracle may know (:class:`~rczone.control.controllers.OracleController`).
        """
        out = self._forecast("perfect", horizon, interval)
        share = np.array([day_gain_share(float(t), True) for t in out["time"]])
        for z in self.zones:
            out[f"Q_{z}"] = self.bld.gains[z] + share * DAY_GAIN.get(z, 0.0)
        return out

    def true_temperature(self, zone: str = "target") -> float:
        """The zone's true (unsensed) air temperature now, degC (what only an oracle may know)."""
        return float(self.sim.x[self.sim.k, self.sim.ss.state_names.index(self.bld.air_nodes[zone])])

    def _forecast(self, kind: str, horizon: float, interval: float | None) -> dict[str, np.ndarray]:
        times, iv = self._times(horizon, interval)
        now, k = self.time, self.sim.k
        if kind == "perfect":
            to = self._truth(self.sim.t_out, times)
            t_ahu = self._truth(self.sim.t_ahu, times)
            price = price_signal(self.price, times)
        else:
            d = diurnal_curve(self.season, times)
            to = d + (float(self.sim.t_out[k]) - float(diurnal_curve(self.season, np.array([now]))[0]))
            to = to + (FORECAST_BIAS_K if kind == "biased" else 0.0)
            t_ahu = np.full(times.size, float(self.sim.t_ahu[k]))
            price = forecast_price(self.price, now, times)
        out = {"time": times, "To": to, "T_ahu": t_ahu, "price": price}
        for z, cfg in self.configs.items():
            b = band(cfg, times)
            out.update(
                {f"lower_{z}": b.lower, f"upper_{z}": b.upper, f"occupied_{z}": b.occupied.astype(float)}
            )
        out.update(self.constraints(horizon, interval=iv))
        return out

    def constraints(self, horizon: float, *, interval: float | None = None) -> dict[str, np.ndarray]:
        """The zones' limits per interval from now, the tightest in each (see the protocol)."""
        _, iv = self._times(horizon, interval)
        out = {}
        for z, lim in self.limits.items():
            b = lim.steps(self.time, iv, forecast_steps(horizon, iv), sample=self.dt)
            out.update({f"m_min_{z}": b.m_min, f"m_max_{z}": b.m_max, f"ts_max_{z}": b.ts_max})
        return out

    # ------------------------------------------------------------ scores
    def series(self, zone: str = "target") -> dict[str, np.ndarray]:
        """The scored part of the run so far: ``t`` and the zone's true ``Ti``, band, ``m``, ``Ts``, power."""
        r, bld = self.sim.result(), self.bld
        k0 = int(np.searchsorted(r.t, 0.0))
        t = r.t[k0:-1]
        ti = r.state(bld.air_nodes[zone])[k0:-1]
        m = r.flow(bld.flow_name(zone))[k0:]
        ts = r.input(bld.supply_name(zone))[k0:]
        p = zone_power(m, ts, r.t_ahu[k0:], ti, r.t_out[k0:])
        b = band(self.configs.get(zone, self.sim.configs[zone]), t)
        return {
            "t": t,
            "Ti": ti,
            "lower": b.lower,
            "upper": b.upper,
            "occupied": b.occupied,
            "m": m,
            "Ts": ts,
            "power_W": p.total,
            **{f"{k}_W": v for k, v in p._asdict().items()},
        }

    def kpis(self) -> dict[str, Any]:
        """The scores of the run so far (see the module notes); of the first controlled zone."""
        zone = self.zones[0]
        s = self.series(zone)
        if s["t"].size == 0:
            raise ParameterError("nothing is scored yet: the plant has not reached 6 pm")
        t, ti, m, ts = s["t"], s["Ti"], s["m"], s["Ts"]
        outside = np.maximum(s["lower"] - ti, 0.0) + np.maximum(ti - s["upper"], 0.0)
        h, kwh = CONTROL_DT / 3600.0, CONTROL_DT / 3.6e6
        parts = {k: float(s[f"{k}_W"].sum() * kwh) for k in ("reheat", "cooling", "fan")}
        scores: dict[str, Any] = {
            "comfort_Kh": float((outside * s["occupied"]).sum() * h),
            "energy_kWh": float(sum(parts.values())),
            "cost": float((s["power_W"] * price_signal(self.price, t)).sum() * kwh),
            **{f"{k}_kWh": v for k, v in parts.items()},
            "peak_flow_kg_s": float(m.max()),
            "max_discharge_degC": float(ts.max()),
            "constraint_violations": self.limits[zone].violations(t, m, ts),
        }
        if self.price == "dr":
            ev = window(t, DR_HOURS)
            scores.update(
                event_energy_kWh=float(s["power_W"][ev].sum() * kwh),
                event_cost=float(s["power_W"][ev].sum() * DR_PRICE * kwh),
                event_peak_flow_kg_s=float(m[ev].max()) if ev.any() else 0.0,
                event_comfort_Kh=float((outside * s["occupied"] * ev).sum() * h),
            )
        return scores

    def describe(self) -> dict[str, Any]:
        """The test's settings and the controlled zones' limits (what a result records)."""
        return {
            "plant": "virtual building",
            "scenario": self.season,
            "days": self.days,
            "seed": self.seed,
            "price": self.price,
            "band": self.comfort_band,
            "forecast": self.forecast_kind,
            "constraints": {z: lim.to_dict() for z, lim in self.limits.items()},
        }
