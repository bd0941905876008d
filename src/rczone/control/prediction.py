"""How well a model predicts a closed-loop run: one step (the filter), one hour and open loop.

The filter's one-step prediction error ranks a fit's *noise levels* as much as its R and C: a fit
whose measurement noise is tiny (``sigma_v`` = 0.0016 K on night C, below the sensor's 0.1 F
resolution) makes its filter follow every reading, and its one-step error says little about the
dynamics (issue 33, item 4). Three figures side by side, on the run's measurements averaged
over :data:`PREDICTION_DT`:

* ``prediction_rmse_K``: the Kalman filter's one-step (10-min) prediction error, its
  measurement noise no lower than a floor at the sensor's resolution (:data:`SENSOR_RESOLUTION_K`,
  0.1 F, overridable: ``noise_floor``);
* ``prediction_1h_rmse_K``: the model's mean :data:`K_STEPS` steps (1 h) ahead from each filtered
  state, the measured inputs known, no measurement in between;
* ``open_loop_rmse_K``: the model's mean from the filtered state after the first hour, simulated
  with the measured inputs to the end of the run, never corrected: the figure about R and C.

The k-step and open-loop errors are the simulation and multi-step prediction errors of Ljung
[1]_ (section 16.4, model validation by simulation and k-step-ahead prediction).

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall, 1999.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rczone.control.model import ControlModel
from rczone.control.noise import NoiseModel
from rczone.control.observer import KalmanObserver
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel
from rczone.virtual.scenarios import SURROUNDINGS

#: Interval of the prediction scores, s.
PREDICTION_DT = 600.0
#: Steps of the k-step score (1 h at 10 min).
K_STEPS = 6
#: The floor of the filter's measurement noise: a BMS sensor's 0.1 F resolution, K.
SENSOR_RESOLUTION_K = 0.1 * 5.0 / 9.0
#: Samples that settle the filter before any error is scored (1 h).
SETTLE = 6


def floored(noise: NoiseModel, floor: float) -> NoiseModel:
    """``noise`` with every measurement standard deviation at least ``floor`` K."""
    if not (np.isfinite(floor) and floor >= 0):
        raise ParameterError(f"the sensor-noise floor must be a finite number >= 0 K, got {floor!r}")
    r = np.diag(np.maximum(np.diag(noise.R), floor**2))
    return NoiseModel(noise.Qc, r, noise.state_names, noise.output_names, noise.source)


def _averaged(values: Mapping[str, np.ndarray], t: np.ndarray, zone: str, model: ZoneModel):
    """Inputs (n, p), flows (n,) and outputs (n,) of the scored part, averaged per interval."""
    k0 = int(np.searchsorted(t, 0.0))
    step = round(PREDICTION_DT / float(t[1] - t[0]))
    n = (len(t) - 1 - k0) // step
    sl = slice(k0, k0 + n * step)

    def avg(a: np.ndarray) -> np.ndarray:
        return a[sl].reshape(n, step).mean(axis=1)

    flow = values[f"m_{zone}"][1:]  # held over [t_k, t_k+1), measured at t_k+1
    m = avg(flow)
    cols = {
        "To": avg(values["To"][:-1]),
        "Ts": avg(flow * values[f"Ts_{zone}"][1:]) / m,
        **{c: avg(values[f"Ti_{z}"][:-1]) for c, z in SURROUNDINGS.items() if f"Ti_{z}" in values},
    }
    cols["Tsd"] = np.mean([cols[c] for c in SURROUNDINGS if c in cols], axis=0)
    u = np.column_stack(
        [
            cols[nm] if nm in cols else np.full(n, model.inputs.defaults.get(nm, 0.0))
            for nm in model.network.input_names
        ]
    )
    return u, m, values[f"Ti_{zone}"][k0 : k0 + n * step : step]


def prediction_scores(
    values: Mapping[str, np.ndarray],
    t: np.ndarray,
    model: ZoneModel,
    *,
    zone: str = "target",
    noise_floor: float = SENSOR_RESOLUTION_K,
) -> dict[str, float | None]:
    """The three prediction errors of ``model`` on a run's measurements (see the module notes).

    Parameters
    ----------
    values : mapping of str to ndarray
        Measurements per plant step (``To``, ``Ti_<zone>``, ``m_<zone>``, ``Ts_<zone>``, ...).
    t : ndarray
        Their times, s (the scored part starts at 0).
    model : ZoneModel
    zone : str
    noise_floor : float
        Lowest measurement standard deviation the filter may assume, K.

    Returns
    -------
    dict
        ``prediction_rmse_K``, ``prediction_1h_rmse_K``, ``open_loop_rmse_K`` (None for a run
        too short to score, under two hours).
    """
    u, m, y = _averaged(values, t, zone, model)
    return averaged_scores(u, m[:, None], y, model, noise_floor=noise_floor)


def averaged_scores(
    u: np.ndarray, m: np.ndarray, y: np.ndarray, model: ZoneModel, *, noise_floor: float = SENSOR_RESOLUTION_K
) -> dict[str, float | None]:
    """The three prediction errors from inputs ``u`` (n, p), flows ``m`` (n, nf) and the room
    temperature ``y`` (n,), averaged over :data:`PREDICTION_DT` (see :func:`prediction_scores`)."""
    n = len(y)
    if n < SETTLE + K_STEPS + 1:
        return dict.fromkeys(("prediction_rmse_K", "prediction_1h_rmse_K", "open_loop_rmse_K"))
    cm = ControlModel(model)
    cm = ControlModel(model, noise=floored(cm.noise, noise_floor))
    obs = KalmanObserver(cm)
    fr = obs.filter(PREDICTION_DT * np.arange(n), u, m, y[:, None], obs.prior(np.array([y[0]])))
    c = cm.matrices

    def advance(x: np.ndarray, i: int) -> np.ndarray:
        d = cm.discrete(PREDICTION_DT, m[i])
        return d.Ad @ x + d.Bd @ u[i]

    ahead = []
    for i in range(SETTLE, n - K_STEPS):
        x = fr.x_filt[i]
        for j in range(K_STEPS):
            x = advance(x, i + j)
        ahead.append(c.C[0] @ x + c.D[0] @ u[i + K_STEPS] - y[i + K_STEPS])
    x, free = fr.x_filt[SETTLE], []
    for i in range(SETTLE, n - 1):
        x = advance(x, i)
        free.append(c.C[0] @ x + c.D[0] @ u[i + 1] - y[i + 1])
    rms = lambda e: float(np.sqrt(np.mean(np.square(e))))  # noqa: E731
    return {
        "prediction_rmse_K": rms(fr.innovations[SETTLE:, 0]),
        "prediction_1h_rmse_K": rms(ahead),
        "open_loop_rmse_K": rms(free),
    }
