"""Closed-loop tests: a controller runs the virtual building's target zone for days, and is scored.

The plant is the full virtual building (:mod:`rczone.virtual`: the 152-state floor, its other
zones under their own thermostats, seeded weather, AHU drift, sensor noise and quantization,
and daytime gains of occupants and equipment that no zone model knows about), run for
``days`` from 6 pm with the schedules repeating daily (``emulator.run(..., daily=True)``).
The target zone is run either by its own thermostat or by the reference MPC
(:class:`MPCZoneController`), which sees only what a BMS sees: the sensed temperatures of the
target and its neighbours, the outdoor temperature and the AHU supply temperature.

Scores (from 6 pm of the first day on; the warm-up is not scored):

* ``comfort_Kh``: the integral of the room air temperature's distance outside the thermostat's
  occupied band (``heat_occ``, ``cool_occ``), over the occupied hours, K h;
* ``energy_kWh``: reheat + cooling + fan energy of the zone (:mod:`rczone.control.energy`);
* ``cost``: the same energy weighted by the price signal (equal to ``energy_kWh`` for a flat price);
* with the demand-response price (``price="dr"``) also ``event_energy_kWh``, ``event_cost``,
  ``event_peak_flow_kg_s`` and ``event_comfort_Kh``: the same scores over the event windows only;
* ``peak_flow_kg_s``; ``max_discharge_degC``;
* ``prediction_rmse_K``: the model's 10-min-ahead prediction error along the run (its Kalman
  filter without a disturbance state, on the run's sensed data averaged over each 10 min);
* ``solve_time_s``: the MPC's mean and largest QP time per step (none for the thermostat).

The MPC's forecast: the outdoor temperature's diurnal curve shifted by the last measured
error (:func:`rczone.virtual.weather.diurnal_curve`), the neighbours' and the AHU
temperatures held, the thermostat's band by its schedule, and the price; a demand-response
event is in the forecast only from its announcement (:data:`DR_NOTICE` before it) on.

Harder scenarios (both optional, the defaults are the plain summer and winter tests):

* ``comfort_band="tight"``: the occupied band narrowed to :data:`TIGHT_BAND_K` about its
  centre, for the thermostat, the MPC and the score alike (:func:`tighten`);
* ``price="dr"``: a demand-response event, the price :data:`DR_PRICE` times the normal one
  from 2 pm to 4 pm (:data:`DR_HOURS`), announced :data:`DR_NOTICE` ahead; the thermostat
  ignores it, the MPC can pre-cool. Demand-response events of this kind (a price or a
  curtailment signal for a few afternoon hours, notified hours ahead) are described in [2]_.

References
----------
.. [1] D. Sturzenegger, D. Gyalistras, M. Morari, R. S. Smith, "Model predictive climate
   control of a Swiss office building: implementation, results, and cost-benefit analysis",
   IEEE Trans. Control Systems Technology 24(1) (2016) 1-12 (the scores of a closed-loop test).
.. [2] J. E. Braun, "Load control using building thermal mass", J. Solar Energy Engineering
   125(3) (2003) 292-301 (pre-cooling ahead of an afternoon peak or event).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rczone.control.constraints import ZoneConstraints
from rczone.control.disturbance import Disturbance
from rczone.control.energy import zone_power
from rczone.control.model import ControlModel
from rczone.control.mpc import MPC, Forecast, MPCSettings
from rczone.control.observer import KalmanObserver
from rczone.errors import ParameterError, did_you_mean
from rczone.models.zone import ZoneModel
from rczone.network import CP_AIR
from rczone.virtual.building import build_building
from rczone.virtual.control import CONTROL_DT, ControllerConfig, VAVController, coil_lag
from rczone.virtual.emulator import DAY, EmulatorRun, run, thermostat_configs
from rczone.virtual.scenarios import SURROUNDINGS
from rczone.virtual.weather import diurnal_curve

SEASONS = ("summer", "winter")
CONTROLLERS = ("mpc", "thermostat")
#: Price signals: flat (energy), or time-of-use with a peak price of :data:`PEAK_PRICE` from
#: noon to 6 pm (a summer on-peak window, when pre-cooling pays).
PRICES = ("flat", "tou", "dr")
PEAK_PRICE = 3.0
PEAK_HOURS = (18 * 3600.0, 24 * 3600.0)  # s after 6 pm: noon to 6 pm
#: Demand-response event ("dr"): :data:`DR_PRICE` times the price from 2 pm to 4 pm, in the
#: MPC's forecast only from :data:`DR_NOTICE` before its start (announced at 11 am).
DR_PRICE = 10.0
DR_HOURS = (20 * 3600.0, 22 * 3600.0)  # s after 6 pm: 2 pm to 4 pm
DR_NOTICE = 3 * 3600.0
#: Comfort bands: the thermostat's ("normal"), or its occupied band narrowed to
#: :data:`TIGHT_BAND_K` about its centre ("tight"; the normal one is 1.8 K in summer, 1.1 K in winter).
BANDS = ("normal", "tight")
TIGHT_BAND_K = 0.8
#: Warm-up before the first 6 pm, s (the MPC's observer settles; not scored).
WARMUP = 6 * 3600.0
#: Interval of the prediction-error score, s.
PREDICTION_DT = 600.0


def band(cfg: ControllerConfig, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lower, upper, occupied)`` of the thermostat's schedule at times ``t`` (s from 6 pm)."""
    unocc = np.array([cfg.unoccupied(float(x)) for x in np.atleast_1d(t)])
    lower = np.where(unocc, cfg.heat_unocc, cfg.heat_occ)
    upper = np.where(unocc, cfg.cool_unocc, cfg.cool_occ)
    return lower, upper, ~unocc


def _window(t: np.ndarray, hours: tuple[float, float]) -> np.ndarray:
    tm = np.asarray(t, float) % DAY
    return (tm >= hours[0]) & (tm < hours[1])


def price_signal(kind: str, t: np.ndarray) -> np.ndarray:
    """Price per kWh at ``t`` (s from 6 pm): 1, :data:`PEAK_PRICE` in the peak window ("tou"),
    or :data:`DR_PRICE` in the demand-response event ("dr")."""
    if kind == "dr":
        return np.where(_window(t, DR_HOURS), DR_PRICE, 1.0)
    return np.where(_window(t, PEAK_HOURS) & (kind == "tou"), PEAK_PRICE, 1.0)


def forecast_price(kind: str, now: float, times: np.ndarray) -> np.ndarray:
    """The price at ``times`` as known at ``now`` (s from 6 pm).

    The time-of-use price is known in advance; a demand-response event only from its
    announcement, :data:`DR_NOTICE` before its start, on (the normal price before that).
    """
    p = price_signal(kind, times)
    if kind == "dr":
        starts = np.floor((np.asarray(times, float) - DR_HOURS[0]) / DAY) * DAY + DR_HOURS[0]
        p = np.where(now >= starts - DR_NOTICE, p, 1.0)
    return p


def tighten(cfg: ControllerConfig, width: float = TIGHT_BAND_K) -> ControllerConfig:
    """``cfg`` with its occupied band narrowed to ``width`` K about its centre (unoccupied band kept)."""
    mid = 0.5 * (cfg.heat_occ + cfg.cool_occ)
    return replace(cfg, heat_occ=mid - 0.5 * width, cool_occ=mid + 0.5 * width)


class MPCZoneController:
    """The reference MPC as a controller of the virtual building (``ObservingController``).

    Parameters
    ----------
    mpc : MPC
    config : ControllerConfig
        The zone thermostat's settings: its band and schedule are the MPC's comfort band.
    season : str
        For the outdoor forecast's diurnal curve.
    price : {"flat", "tou", "dr"}
    constraints : ZoneConstraints, optional
        The zone's limits, handed to the MPC as per-step flow bounds (default: those of ``config``).
    """

    def __init__(
        self,
        mpc: MPC,
        config: ControllerConfig,
        season: str,
        price: str = "flat",
        *,
        constraints: ZoneConstraints | None = None,
    ) -> None:
        self.mpc = mpc
        self.cfg = config
        self.constraints = constraints or ZoneConstraints.from_config(config)
        self.season = season
        self.price = price
        self.readings: dict[str, float] = {}
        self.next_time: float | None = None
        self.action = None
        self.ts: float | None = None
        self.solve_times: list[float] = []

    def observe(self, t: float, readings: Mapping[str, float]) -> None:
        self.readings = dict(readings)

    def forecast(self, t: float, t_ahu: float) -> Forecast:
        """What the MPC is told at ``t`` (see the module notes)."""
        s = self.mpc.settings
        times = t + s.dt * np.arange(s.horizon + 1)
        r = self.readings
        to = diurnal_curve(self.season, times) + (
            r["To"] - float(diurnal_curve(self.season, np.array([t]))[0])
        )
        held = {c: np.full(times.size, r[c]) for c in SURROUNDINGS}
        held["Tsd"] = np.full(times.size, float(np.mean([r[c] for c in SURROUNDINGS])))
        lower, upper, _ = band(self.cfg, times)
        used = set(self.mpc.cm.input_names)
        inputs = {k: v for k, v in {"To": to, **held}.items() if k in used}
        bounds = self.constraints.steps(t, s.dt, s.horizon)
        return Forecast(
            inputs,
            np.full(times.size, t_ahu),
            lower,
            upper,
            forecast_price(self.price, t, times),
            m_min=bounds.m_min,
            m_max=bounds.m_max,
        )

    def step(self, t: float, t_sensed: float, t_ahu: float) -> tuple[float, float]:
        if self.next_time is None or t >= self.next_time - 1e-9:
            self.action = self.mpc.step(t, {"Ti": t_sensed}, self.forecast(t, t_ahu))
            self.solve_times.append(self.action.plan.solve_time)
            self.next_time = t + self.mpc.settings.dt
        a = self.action
        target = min(t_ahu + a.reheat / (a.m * CP_AIR), self.mpc.limits.ts_max)
        self.ts = coil_lag(self.ts, max(target, t_ahu), self.cfg.tau_coil)
        return a.m, self.ts


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """Scores and series of a closed-loop test (see the module notes).

    Attributes
    ----------
    scores : mapping
        ``comfort_Kh``, ``energy_kWh`` (and its parts), ``peak_flow_kg_s``,
        ``max_discharge_degC``, ``prediction_rmse_K``, ``solve_time_s`` (mean, max) or None.
    setup : mapping
        Model, scenario, days, seed, controller, disturbance, and ``constraints``: the zone's
        limits the controller ran under (:class:`ZoneConstraints`, as a mapping).
    t : ndarray, shape (N,)
        s from the first 6 pm, one per minute (scored part).
    series : mapping of str to ndarray, shape (N,)
        ``Ti`` (true), ``lower``, ``upper``, ``occupied``, ``m``, ``Ts``, ``power_W``.
    """

    scores: Mapping[str, Any]
    setup: Mapping[str, Any]
    t: np.ndarray
    series: Mapping[str, np.ndarray]

    def to_dict(self) -> dict[str, Any]:
        return {**dict(self.scores), "setup": dict(self.setup)}

    def summary(self) -> str:
        s, st = self.scores, self.setup
        lines = [
            f"closed-loop test: {st['controller']} on the {st['scenario']} scenario, {st['days']} day(s), "
            f"seed {st['seed']}, model {st['model']}",
            f"  comfort      {s['comfort_Kh']:.2f} K h outside the band (occupied hours)",
            f"  energy       {s['energy_kWh']:.2f} kWh (reheat {s['reheat_kWh']:.2f}, cooling "
            f"{s['cooling_kWh']:.2f}, fan {s['fan_kWh']:.2f})",
            f"  peak flow    {s['peak_flow_kg_s']:.3f} kg/s; {s['constraint_violations']} minute(s) outside"
            " the zone's limits",
            f"  prediction   {s['prediction_rmse_K']:.3f} K RMSE (10 min ahead)",
        ]
        if "event_energy_kWh" in s:
            lines.append(
                f"  DR event     {s['event_energy_kWh']:.2f} kWh, peak flow {s['event_peak_flow_kg_s']:.3f} kg/s, "
                f"{s['event_comfort_Kh']:.2f} K h outside the band"
            )
        if s["solve_time_s"] is not None:
            lines.append(
                f"  QP time      {1e3 * s['solve_time_s']['mean']:.1f} ms mean, "
                f"{1e3 * s['solve_time_s']['max']:.1f} ms max per step"
            )
        return "\n".join(lines)


def _check(season: str, days: float, controller: str, price: str, comfort_band: str) -> None:
    if comfort_band not in BANDS:
        raise ParameterError(f"unknown comfort band {comfort_band!r}; " + did_you_mean(comfort_band, BANDS))
    if price not in PRICES:
        raise ParameterError(f"unknown price signal {price!r}; " + did_you_mean(price, PRICES))
    if season not in SEASONS:
        raise ParameterError(f"unknown scenario {season!r}; " + did_you_mean(season, SEASONS))
    if controller not in CONTROLLERS:
        raise ParameterError(f"unknown controller {controller!r}; " + did_you_mean(controller, CONTROLLERS))
    if not (isinstance(days, (int, float)) and math.isfinite(days) and 0 < days <= 60):
        raise ParameterError(f"days must be a number in (0, 60], got {days!r}")


def closed_loop_test(
    model: ZoneModel,
    *,
    season: str = "summer",
    days: float = 1,
    seed: int = 0,
    controller: str = "mpc",
    disturbance: bool = True,
    settings: MPCSettings | None = None,
    price: str = "flat",
    comfort_band: str = "normal",
) -> ClosedLoopResult:
    """Run the virtual building for ``days`` with ``controller`` on its target zone, and score it.

    Parameters
    ----------
    model : ZoneModel
        The MPC's model; also the model whose prediction error is scored.
    season : {"summer", "winter"}
    days : float
    seed : int
        Weather, thermostat settings, AHU drift and sensor noise.
    controller : {"mpc", "thermostat"}
    disturbance : bool
        The MPC's observer estimates an unmeasured heat input (offset-free); False: none.
    settings : MPCSettings, optional
    price : {"flat", "tou", "dr"}
        The price the MPC minimizes (``cost`` in the scores); the thermostat ignores it.
    comfort_band : {"normal", "tight"}
        The thermostat's occupied band, or that band narrowed to :data:`TIGHT_BAND_K`; the
        thermostat, the MPC and the comfort score all use it.

    Returns
    -------
    ClosedLoopResult
    """
    _check(season, days, controller, price, comfort_band)
    bld = build_building()
    duration = round(days * DAY / CONTROL_DT) * CONTROL_DT
    cfg = thermostat_configs(bld, season, np.random.default_rng(seed), warmup=WARMUP, daily=True)["target"]
    limits = ZoneConstraints.from_config(cfg)
    ctrl = None
    if comfort_band == "tight":
        cfg = tighten(cfg)
        ctrl = VAVController(cfg, -WARMUP)  # the thermostat, on the tight band
    if controller == "mpc":
        mpc = MPC(model, settings, disturbance=Disturbance("heat") if disturbance else None)
        ctrl = MPCZoneController(mpc, cfg, season, price, constraints=limits)
    r = run(
        bld,
        season,
        np.random.default_rng(seed),
        duration=duration,
        warmup=WARMUP,
        controllers={"target": ctrl} if ctrl else None,
        daily=True,
    )
    result = _score(r, bld, cfg, model, price)
    result[0]["constraint_violations"] = limits.violations(result[1], result[2]["m"], result[2]["Ts"])
    setup = {
        "model": model.label,
        "scenario": season,
        "days": days,
        "seed": seed,
        "controller": controller,
        "disturbance_estimate": bool(disturbance) if controller == "mpc" else None,
        "price": price,
        "band": comfort_band,
        "constraints": limits.to_dict(),
    }
    solve = None
    if isinstance(ctrl, MPCZoneController) and ctrl.solve_times:
        solve = {"mean": float(np.mean(ctrl.solve_times)), "max": float(np.max(ctrl.solve_times))}
    return ClosedLoopResult({**result[0], "solve_time_s": solve}, setup, result[1], result[2])


def _score(
    r: EmulatorRun, bld, cfg: ControllerConfig, model: ZoneModel, price: str
) -> tuple[dict, np.ndarray, dict]:
    """Scores and series of the scored part of a run (from t = 0)."""
    k0 = int(np.searchsorted(r.t, 0.0))
    t = r.t[k0:-1]
    ti = r.state(bld.air_nodes["target"])[k0:-1]
    m = r.flow(bld.flow_name("target"))[k0:]
    ts = r.input(bld.supply_name("target"))[k0:]
    p = zone_power(m, ts, r.t_ahu[k0:], ti, r.t_out[k0:])
    lower, upper, occ = band(cfg, t)
    outside = np.maximum(lower - ti, 0.0) + np.maximum(ti - upper, 0.0)
    h = CONTROL_DT / 3600.0
    kwh = {k: float(v.sum() * CONTROL_DT / 3.6e6) for k, v in p._asdict().items()}
    scores = {
        "comfort_Kh": float((outside * occ).sum() * h),
        "energy_kWh": float(sum(kwh.values())),
        "cost": float((p.total * price_signal(price, t)).sum() * CONTROL_DT / 3.6e6),
        "reheat_kWh": kwh["reheat"],
        "cooling_kWh": kwh["cooling"],
        "fan_kWh": kwh["fan"],
        "peak_flow_kg_s": float(m.max()),
        "max_discharge_degC": float(ts.max()),
        "prediction_rmse_K": prediction_rmse(r, bld, model),
    }
    if price == "dr":
        ev = _window(t, DR_HOURS)
        scores.update(
            event_energy_kWh=float(p.total[ev].sum() * CONTROL_DT / 3.6e6),
            event_cost=float(p.total[ev].sum() * DR_PRICE * CONTROL_DT / 3.6e6),
            event_peak_flow_kg_s=float(m[ev].max()) if ev.any() else 0.0,
            event_comfort_Kh=float((outside * occ * ev).sum() * h),
        )
    series = {"Ti": ti, "lower": lower, "upper": upper, "occupied": occ, "m": m, "Ts": ts, "power_W": p.total}
    return scores, t, series


def prediction_rmse(r: EmulatorRun, bld, model: ZoneModel) -> float:
    """10-min-ahead RMSE of the model's Kalman filter on the run's sensed data (see module notes)."""
    k0 = int(np.searchsorted(r.t, 0.0))
    step = round(PREDICTION_DT / CONTROL_DT)
    n = (len(r.t) - 1 - k0) // step
    sl = slice(k0, k0 + n * step)

    def avg(a: np.ndarray) -> np.ndarray:
        return a[sl].reshape(n, step).mean(axis=1)

    m = avg(r.flow(bld.flow_name("target")))
    cols = {
        "To": avg(r.t_out),
        "Ts": avg(r.flow(bld.flow_name("target")) * r.input(bld.supply_name("target"))) / m,
        **{c: avg(r.sensed[z][:-1]) for c, z in SURROUNDINGS.items()},
    }
    cols["Tsd"] = np.mean([cols[c] for c in SURROUNDINGS], axis=0)
    net = model.network
    u = np.column_stack(
        [cols[nm] if nm in cols else np.full(n, model.inputs.defaults.get(nm, 0.0)) for nm in net.input_names]
    )
    y = r.sensed["target"][k0 : k0 + n * step : step][:, None]
    obs = KalmanObserver(ControlModel(model))
    fr = obs.filter(PREDICTION_DT * np.arange(n), u, m[:, None], y, obs.prior(y[0]))
    e = fr.innovations[6:, 0]  # the first hour settles the filter
    return float(np.sqrt(np.mean(e**2)))


#: What two closed-loop results must share to be compared.
COMPARABLE = ("scenario", "days", "seed", "price", "band", "constraints")


def check_comparable(a: ClosedLoopResult, b: ClosedLoopResult) -> None:
    """Refuse to compare two runs that differ in the test or in the limits their controllers had.

    Raises
    ------
    ParameterError
        Naming the first setting that differs (e.g. the constraints: a controller allowed a lower
        ventilation minimum saves energy by breaking what the other was held to).
    """
    for k in COMPARABLE:
        if a.setup.get(k) != b.setup.get(k):
            raise ParameterError(
                f"cannot compare {a.setup['controller']} with {b.setup['controller']}: their {k} differ "
                f"({a.setup.get(k)!r} vs {b.setup.get(k)!r}); run both under the same test and limits"
            )
