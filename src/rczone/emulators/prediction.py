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
from rczone.kernels.arrays import StateMoments
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


KEYS = ("prediction_rmse_K", "prediction_1h_rmse_K", "open_loop_rmse_K")


def prediction_scores(
    values: Mapping[str, np.ndarray],
    t: np.ndarray,
    model: ZoneModel,
    *,
    zone: str,
    noise_floor: float = SENSOR_RESOLUTION_K,
) -> dict[str, float | None]:
    """``prediction_rmse_K``, ``prediction_1h_rmse_K``, ``open_loop_rmse_K`` (None if too short).

    A joint model of several zones (outputs ``T<zone's letters and digits>``, the floor model) is
    scored as it predicts: all its zones together (:func:`joint_prediction_scores`); ``zone``'s
    output is scored.
    """
    t = np.asarray(t, float)
    keys = KEYS
    if len(model.network.outputs) > 1:
        return joint_prediction_scores(values, t, model, noise_floor=noise_floor).get(
            zone, dict.fromkeys(keys)
        )
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
    errors = _errors(obs, cm.discrete(dt, 0.0), obs.prior(np.array([y[0]])), u, heat, y[:, None], dt)
    return dict(zip(keys, (float(e[0]) for e in errors)))


def _errors(
    obs: KalmanObserver,
    d,
    est: StateMoments,
    u: np.ndarray,
    heat: np.ndarray,
    y: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each output's RMS one-step, one-hour-ahead and open-loop error (after :data:`SETTLE_S`).

    ``obs`` filters with inputs ``u`` (n, p) and supply-node heat ``heat`` (n,) held over each step,
    from ``est``; ``d`` are its discrete matrices at zero flow, ``y`` (n, ny) the measurements.
    """
    n = len(y)
    settle, k_ahead = max(1, round(SETTLE_S / dt)), max(1, round(AHEAD_S / dt))

    def advance(x: np.ndarray, i: int) -> np.ndarray:
        return d.Ad @ x + d.Bd @ u[i] + d.Ed[:, 0] * heat[i]

    innov, filtered = [], []
    for i in range(n):
        if i:
            est = obs.predict(est, u[i - 1], 0.0, dt, heat=heat[i - 1])
        est, e = obs.update(est, y[i], u[i])
        innov.append(e)
        filtered.append(est.x)
    ahead = []
    for i in range(settle, n - k_ahead):
        x = filtered[i]
        for j in range(k_ahead):
            x = advance(x, i + j)
        ahead.append(d.C @ x + d.D @ u[i + k_ahead] - y[i + k_ahead])
    x, free = filtered[settle], []
    for i in range(settle, n - 1):
        x = advance(x, i)
        free.append(d.C @ x + d.D @ u[i + 1] - y[i + 1])

    def rms(e: list) -> np.ndarray:
        return np.sqrt(np.nanmean(np.square(np.array(e)), axis=0))

    return rms(innov[settle:]), rms(ahead), rms(free)


def _joint_zones(values: Mapping[str, np.ndarray], model: ZoneModel) -> tuple[list[str], list[str]] | None:
    """The measured zones that are the joint model's outputs (in output order), and the others."""
    from rczone.emulators.floor import alias

    measured = [k[3:] for k in values if k.startswith("Ti_")]
    zones = []
    for o in model.network.outputs:
        hits = [z for z in measured if o in (f"T{alias(z)}", z)]
        if not hits:
            return None
        zones.append(hits[0])
    return zones, [z for z in measured if z not in zones]


def joint_prediction_scores(
    values: Mapping[str, np.ndarray],
    t: np.ndarray,
    model: ZoneModel,
    *,
    noise_floor: float = SENSOR_RESOLUTION_K,
) -> dict[str, dict[str, float | None]]:
    """Each zone's three figures of a joint model of several zones, predicting them all together.

    As :func:`prediction_scores` for one zone, on the joint model (:mod:`rczone.emulators.floormpc`):
    one Kalman filter, every zone's supply air as the heat it brought, the boundaries off the
    floor (measured ``Ti_<zone>`` of the building's other zones) and the metered ``Q`` as measured
    at each step, the outdoor temperature as measured; one hour ahead and open loop from the filtered
    state, every zone's prediction feeding its neighbours'. Zones the model does not name, or a
    model it cannot read (no supply air into a zone), give None.

    Returns
    -------
    dict of zone to dict
        ``{zone: {"prediction_rmse_K": ..., "prediction_1h_rmse_K": ..., "open_loop_rmse_K": ...}}``.
    """
    from rczone.control.model import DiscreteMatrices
    from rczone.control.noise import NoiseModel
    from rczone.control.observer import NODE_PRIOR_SD
    from rczone.emulators.floormpc import JointMatrices, input_sources, owners, supply_columns
    from rczone.errors import ParameterError
    from rczone.simulation.discretize import process_noise_covariance, zoh

    found = _joint_zones(values, model)
    t = np.asarray(t, float)
    if found is None or len(t) < 3:
        return {}
    zones, others = found
    outputs = list(model.network.outputs)
    try:
        E = supply_columns(model, outputs)
        sources = input_sources(model, zones, outputs, others)
    except ParameterError:
        return {}
    dt = float(t[1] - t[0])
    settle, k_ahead = max(1, round(SETTLE_S / dt)), max(1, round(AHEAD_S / dt))
    n_t = len(t)
    if n_t < settle + k_ahead + 2:
        return {z: dict.fromkeys(KEYS) for z in zones}
    cols = []
    for kind, what in sources:
        if kind == "forecast":
            cols.append(np.asarray(values["To"], float))
        elif kind == "measured":
            key, default = what
            v = np.asarray(values.get(key, np.full(n_t, np.nan)), float)
            cols.append(np.where(np.isfinite(v), v, np.nan if default is None else float(default)))
        else:
            cols.append(np.full(n_t, float(what)))
    u = np.column_stack(cols)
    y = np.column_stack([np.asarray(values[f"Ti_{z}"], float) for z in zones])
    heat = np.zeros((n_t, len(zones)))
    for j, z in enumerate(zones):
        m = np.nan_to_num(np.asarray(values[f"m_{z}"], float))
        ts = np.asarray(values[f"Ts_{z}"], float)
        heat[:-1, j] = np.nan_to_num(m[1:] * CP_AIR * (ts[1:] - y[1:, j]))  # step k's, metered at k + 1
    ss = model.state_space()
    noise = floored(NoiseModel.from_model(model), noise_floor)
    Ad, Bd = zoh(ss.A, np.hstack([ss.B, E]), dt)
    nz, n_x = len(zones), ss.n_states
    d = DiscreteMatrices(
        Ad,
        Bd,
        np.zeros((n_x, 1)),
        ss.C,
        np.hstack([ss.D, np.zeros((nz, nz))]),
        process_noise_covariance(ss.A, noise.Qc, dt),
        noise.R,
    )
    first = y[0]
    x0 = [
        np.nanmean(first) if j is None or not np.isfinite(first[j]) else first[j]
        for j in owners(model, outputs)
    ]
    est = StateMoments(np.array(x0), np.eye(n_x) * NODE_PRIOR_SD**2)
    # every zone's supply-air heat enters as an input of its own (B = [B | E])
    obs = KalmanObserver(JointMatrices(d, noise))
    one, hour, loop = _errors(obs, d, est, np.hstack([u, heat]), np.zeros(n_t), y, dt)
    return {z: dict(zip(KEYS, (float(one[j]), float(hour[j]), float(loop[j])))) for j, z in enumerate(zones)}
