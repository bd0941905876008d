"""How well a zone model predicts an EnergyPlus closed-loop run, from what the BMS measured.

The three figures of :mod:`rczone.control.prediction` (the filter's one-step error, the mean one
hour ahead, open loop) on the plant's own step, with the zone's inputs as the EnergyPlus plant
measures them: ``To``, ``Tsd_<zone>``, ``Q_<zone>``, and the supply air as the heat it brought,
``m cp (Ts - Ti)`` (the model at zero flow with that heat at the room node is the fitted model; see
:mod:`rczone.emulators.supervisory`). The k-step and open-loop errors are Ljung's [1]_ simulation
and multi-step prediction errors.

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall, 1999,
   section 16.4.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rczone.control.model import ControlModel
from rczone.control.observer import KalmanObserver
from rczone.control.prediction import SENSOR_RESOLUTION_K, floored
from rczone.models.zone import ZoneModel
from rczone.network import CP_AIR

#: The k-step score's look-ahead, s, and the samples that settle the filter first, s.
AHEAD_S = 3600.0
SETTLE_S = 3600.0


def _series(values: Mapping[str, np.ndarray], zone: str, model: ZoneModel, cm: ControlModel):
    """Inputs (N, p), heat (N,) held over each step, and the measured room temperature (N,)."""
    ti = np.asarray(values[f"Ti_{zone}"], float)
    m = np.nan_to_num(np.asarray(values[f"m_{zone}"], float))
    ts = np.asarray(values[f"Ts_{zone}"], float)
    heat = np.r_[np.nan_to_num(m[1:] * CP_AIR * (ts[1:] - ti[1:])), 0.0]  # step k's, metered at k + 1
    defaults = dict(model.inputs.defaults)
    cols = []
    for name in cm.input_names:
        key = {"To": "To", "Tsd": f"Tsd_{zone}", "Q": f"Q_{zone}", "Ts": f"Ti_{zone}"}.get(name)
        if key in values:
            cols.append(np.asarray(values[key], float))
        else:
            cols.append(np.full(len(ti), defaults.get(name, 0.0)))
    return np.column_stack(cols), heat, ti


def prediction_scores(
    values: Mapping[str, np.ndarray],
    t: np.ndarray,
    model: ZoneModel,
    *,
    zone: str,
    noise_floor: float = SENSOR_RESOLUTION_K,
) -> dict[str, float | None]:
    """``prediction_rmse_K``, ``prediction_1h_rmse_K``, ``open_loop_rmse_K`` (None if too short)."""
    t = np.asarray(t, float)
    keys = ("prediction_rmse_K", "prediction_1h_rmse_K", "open_loop_rmse_K")
    if len(t) < 3:
        return dict.fromkeys(keys)
    dt = float(t[1] - t[0])
    settle, k_ahead = max(1, round(SETTLE_S / dt)), max(1, round(AHEAD_S / dt))
    cm = ControlModel(model)
    cm = ControlModel(model, noise=floored(cm.noise, noise_floor))
    u, heat, y = _series(values, zone, model, cm)
    n = len(y)
    if n < settle + k_ahead + 2:
        return dict.fromkeys(keys)
    obs = KalmanObserver(cm)
    d = cm.discrete(dt, 0.0)
    c = cm.matrices

    def advance(x: np.ndarray, i: int) -> np.ndarray:
        return d.Ad @ x + d.Bd @ u[i] + d.Ed[:, 0] * heat[i]

    est = obs.prior(np.array([y[0]]))
    innov, filtered = [], []
    for i in range(n):
        if i:
            est = obs.predict(est, u[i - 1], 0.0, dt, heat=heat[i - 1])
        est, e = obs.update(est, np.array([y[i]]), u[i])
        innov.append(e[0])
        filtered.append(est.x)
    ahead = []
    for i in range(settle, n - k_ahead):
        x = filtered[i]
        for j in range(k_ahead):
            x = advance(x, i + j)
        ahead.append(c.C[0] @ x + c.D[0] @ u[i + k_ahead] - y[i + k_ahead])
    x, free = filtered[settle], []
    for i in range(settle, n - 1):
        x = advance(x, i)
        free.append(c.C[0] @ x + c.D[0] @ u[i + 1] - y[i + 1])

    def rms(e) -> float:
        return float(np.sqrt(np.mean(np.square(e))))

    return {keys[0]: rms(innov[settle:]), keys[1]: rms(ahead), keys[2]: rms(free)}
