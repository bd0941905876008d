"""Closed-loop tests: a controller runs a plant for days, and is scored.

:func:`closed_loop_test` runs any :class:`~rczone.control.plant.Controller` against any
:class:`~rczone.control.plant.Plant` (by default the virtual building,
:class:`~rczone.control.virtualplant.VirtualPlant`: see there for the plant, its forecasts and
its scores), one plant step at a time: the controller gets the measurements and the forecast
over its horizon and returns its actions. The controller may be given by name
(:mod:`rczone.control.registry`: ``thermostat``, ``naive``, ``mpc``, a registered or plug-in
one). The result adds to the plant's scores:

* ``prediction_rmse_K``, ``prediction_1h_rmse_K``, ``open_loop_rmse_K``: the model's one-step
  (its Kalman filter, the sensor noise floored at the sensor's resolution), one-hour and
  open-loop prediction errors on the run's measurements (:mod:`rczone.control.prediction`);
* ``solve_time_s``: the controller's mean and largest solve time per decision, if it keeps
  ``solve_times`` (the MPC does; none for the thermostat).

The result records the test's settings and the limits every controller was held to
(``setup["constraints"]``); :func:`check_comparable` refuses to compare runs that differ in them.

References
----------
.. [1] D. Sturzenegger, D. Gyalistras, M. Morari, R. S. Smith, "Model predictive climate
   control of a Swiss office building: implementation, results, and cost-benefit analysis",
   IEEE Trans. Control Systems Technology 24(1) (2016) 1-12 (the scores of a closed-loop test).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rczone.control.mpc import MPCSettings
from rczone.control.plant import Controller, Plant
from rczone.control.prediction import SENSOR_RESOLUTION_K, prediction_scores
from rczone.control.registry import ControllerOptions, make_controller
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """Scores and series of a closed-loop test (see the module notes).

    Attributes
    ----------
    scores : mapping
        The plant's KPIs (``comfort_Kh``, ``energy_kWh`` and its parts, ``cost``,
        ``peak_flow_kg_s``, ``max_discharge_degC``, ``constraint_violations``, ...),
        ``prediction_rmse_K`` (None without a model) and ``solve_time_s`` (mean, max) or None.
    setup : mapping
        The plant's settings (scenario, days, seed, price, band, forecast, ``constraints`` per
        zone), ``controller`` and ``model``.
    t : ndarray, shape (N,)
        s from the first 6 pm, one per plant step (scored part).
    series : mapping of str to ndarray, shape (N,)
        ``Ti`` (true where the plant knows it), ``lower``, ``upper``, ``occupied``, ``m``, ``Ts``,
        ``power_W``.
    """

    scores: Mapping[str, Any]
    setup: Mapping[str, Any]
    t: np.ndarray
    series: Mapping[str, np.ndarray]

    def to_dict(self) -> dict[str, Any]:
        """The scores and the setup (what ``--json`` writes)."""
        return {**dict(self.scores), "setup": dict(self.setup)}

    def to_frame(self) -> pd.DataFrame:
        """The series, one row per plant step, indexed by ``t`` (s from the first 6 pm)."""
        return pd.DataFrame(dict(self.series), index=pd.Index(self.t, name="t"))

    def summary(self) -> str:
        """The scores in a few lines (what the CLI prints)."""
        s, st = self.scores, self.setup
        lines = [
            f"closed-loop test: {st['controller']} on the {st['scenario']} scenario, {st['days']} day(s), "
            f"seed {st['seed']}, model {st['model']}, {st.get('forecast', 'measured')} forecast",
            f"  comfort      {s['comfort_Kh']:.2f} K h outside the band (occupied hours)",
        ]
        per_zone = {k[len("comfort_Kh_") :]: v for k, v in s.items() if k.startswith("comfort_Kh_")}
        if len(per_zone) > 1:
            lines.append("  per zone     " + ", ".join(f"{z} {v:.2f} K h" for z, v in per_zone.items()))
        if "reheat_kWh" in s:
            lines += [
                f"  energy       {s['energy_kWh']:.2f} kWh (reheat {s['reheat_kWh']:.2f}, cooling "
                f"{s['cooling_kWh']:.2f}, fan {s['fan_kWh']:.2f})",
                f"  peak flow    {s['peak_flow_kg_s']:.3f} kg/s; {s['constraint_violations']} step(s) outside"
                " the zone's limits",
            ]
        else:  # a heated zone (rczone.control.house)
            lines += [
                f"  energy       {s['energy_kWh']:.2f} kWh of heat (cost {s['cost']:.2f})",
                f"  peak power   {s['peak_power_kW']:.2f} kW; {s['constraint_violations']} step(s) outside"
                " the heater's limits",
            ]
        if s.get("prediction_rmse_K") is not None:
            lines.append(
                f"  prediction   {s['prediction_rmse_K']:.3f} K RMSE one plant step ahead (filter), "
                f"{s['prediction_1h_rmse_K']:.3f} K 1 h ahead, {s['open_loop_rmse_K']:.3f} K open loop"
            )
        if "event_energy_kWh" in s:
            lines.append(
                f"  DR event     {s['event_energy_kWh']:.2f} kWh, peak flow {s['event_peak_flow_kg_s']:.3f} kg/s, "
                f"{s['event_comfort_Kh']:.2f} K h outside the band"
            )
        if s.get("solve_time_s") is not None:
            lines.append(
                f"  QP time      {1e3 * s['solve_time_s']['mean']:.1f} ms mean, "
                f"{1e3 * s['solve_time_s']['max']:.1f} ms max per step"
            )
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class MeasurementLog:
    """Every measurement of a run, one row per plant step: ``t`` (N + 1,) and ``values`` by name."""

    t: np.ndarray
    values: Mapping[str, np.ndarray]


def run_loop(plant: Plant, controller: Controller, progress: Any = None) -> MeasurementLog:
    """Run ``controller`` on ``plant`` to the plant's end; every measurement, in order.

    ``progress.advance(hours, total_hours)`` is told each simulated hour (None: nothing).
    """
    y = plant.measure()
    rows = [y]
    t0, told = float(y["time"]), 0
    hours = max(math.ceil((plant.end - t0) / 3600.0 - 1e-9), 1)
    while y["time"] < plant.end - 1e-9:
        fc = plant.forecast(controller.horizon, interval=controller.interval)
        y = plant.step(controller.act(y["time"], y, fc))
        rows.append(y)
        done = int((float(y["time"]) - t0 + 1e-6) // 3600.0)
        if progress is not None and done > told:
            told = done
            progress.advance(min(done, hours), hours)
    frame = pd.DataFrame(rows)
    return MeasurementLog(frame["time"].to_numpy(), {c: frame[c].to_numpy() for c in frame.columns})


def closed_loop_test(
    plant: Plant,
    controller: Controller | str,
    *,
    model: ZoneModel | Mapping[str, ZoneModel] | None = None,
    settings: MPCSettings | None = None,
    disturbance: bool = True,
    noise_floor: float = SENSOR_RESOLUTION_K,
    progress: Any = None,
) -> ClosedLoopResult:
    """Run ``controller`` on ``plant`` to its end, and score it.

    Parameters
    ----------
    plant : Plant
        E.g. ``VirtualPlant("summer", days=2, seed=11)`` (fresh: a plant runs once).
    controller : Controller or str
        A controller object, or a name of :mod:`rczone.control.registry` (made for ``plant``
        with ``model``, ``settings`` and ``disturbance``).
    model : ZoneModel or mapping of zone to ZoneModel, optional
        The controller's model; also the model whose prediction error is scored (a mapping: each
        controlled zone's, scored per zone; a named controller takes one).
    settings : MPCSettings, optional
    disturbance : bool
        For a named MPC: its observer estimates an unmeasured heat input (offset-free).
    noise_floor : float
        The prediction score's lowest sensor noise, K (:mod:`rczone.control.prediction`).
    progress : object, optional
        Told ``progress.advance(hours, total_hours)`` each simulated hour; None: nothing.

    Returns
    -------
    ClosedLoopResult
    """
    name = controller if isinstance(controller, str) else type(controller).__name__
    zone = plant.zones[0]
    models = dict(model) if isinstance(model, Mapping) else ({} if model is None else {zone: model})
    if isinstance(controller, str):
        if len(models) > 1:
            raise ParameterError(
                f"the {controller!r} controller runs one zone; it was given {len(models)} models"
            )
        options = ControllerOptions(next(iter(models.values()), None), settings, disturbance)
        controller = make_controller(controller, plant, options)
    log = run_loop(plant, controller, progress)
    scores = dict(plant.kpis())
    scores.update(_prediction_scores(plant, log, models, noise_floor))
    times = getattr(controller, "solve_times", None)
    scores["solve_time_s"] = {"mean": float(np.mean(times)), "max": float(np.max(times))} if times else None
    labels = {z: m.label for z, m in models.items()}
    setup = {
        **dict(plant.describe()),
        "controller": name,
        "model": (next(iter(labels.values())) if len(labels) == 1 else labels) if labels else None,
        "disturbance_estimate": bool(disturbance) if hasattr(controller, "mpc") else None,
    }
    series = plant.series(zone) if hasattr(plant, "series") else _measured_series(log, zone)
    t = series.pop("t")
    return ClosedLoopResult(scores, setup, t, series)


def _prediction_scores(
    plant: Plant, log: MeasurementLog, models: Mapping[str, ZoneModel], noise_floor: float
) -> dict[str, Any]:
    """Each zone's model's prediction errors on the run's measurements.

    One zone: ``prediction_rmse_K``, ``prediction_1h_rmse_K``, ``open_loop_rmse_K``. Several: the
    same keys per zone (``..._<zone>``) and, unsuffixed, their root mean square over the zones
    (None where a zone has none).
    """
    if not models:
        return {"prediction_rmse_K": None}
    # a plant that measures other inputs (EnergyPlus's) scores the model itself
    score = getattr(plant, "prediction_scores", prediction_scores)
    per = {z: score(log.values, log.t, m, zone=z, noise_floor=noise_floor) for z, m in models.items()}
    if len(per) == 1:
        return dict(next(iter(per.values())))
    out: dict[str, Any] = {}
    for z, s in per.items():
        out.update({f"{k}_{z}": v for k, v in s.items()})
    for k in next(iter(per.values())):
        vals = [s.get(k) for s in per.values()]
        ok = all(isinstance(v, (int, float)) and math.isfinite(v) for v in vals)
        out[k] = float(math.sqrt(np.mean(np.square(vals)))) if ok else None
    return out


def _measured_series(log: MeasurementLog, zone: str) -> dict[str, np.ndarray]:
    """The scored part of a run as measured (for a plant that gives no true series)."""
    k0 = int(np.searchsorted(log.t, 0.0))
    v = log.values
    return {
        "t": log.t[k0:-1],
        "Ti": v[f"Ti_{zone}"][k0:-1],
        "m": v[f"m_{zone}"][k0 + 1 :],
        "Ts": v[f"Ts_{zone}"][k0 + 1 :],
    }


#: What two closed-loop results must share to be compared.
COMPARABLE = ("plant", "scenario", "days", "seed", "price", "band", "forecast", "constraints")


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
