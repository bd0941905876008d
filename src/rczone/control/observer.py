"""Kalman filter over the bilinear zone model: the hidden nodes and the disturbance from data.

The filter runs on :class:`~rczone.control.model.ControlModel`: at each sample the measured
outputs update the estimate (the textbook measurement update in Joseph form, [1]_ section
5.4; missing outputs are skipped), then the exact discrete model at that interval's flow
and length predicts the next sample ([1]_ section 5.1). The model is LTI between samples
and time-varying with the flow; the discrete matrices are cached per ``(dt, m)``.

:meth:`KalmanObserver.steady_state` gives the constant gain of the filter at a constant flow
from the discrete algebraic Riccati equation (scipy's ``solve_discrete_are``, [2]_).
:func:`estimate_state` warms the filter up on the data before "now" and returns the mean and
covariance of every node, named.

References
----------
.. [1] D. Simon, *Optimal State Estimation: Kalman, H-infinity and Nonlinear Approaches*,
   Wiley, 2006, chapter 5 (the discrete-time Kalman filter) and section 7.3 (steady state).
.. [2] B. D. O. Anderson, J. B. Moore, *Optimal Filtering*, Prentice-Hall, 1979, section 4.4.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from scipy.linalg import solve_discrete_are

from rczone.control.disturbance import Disturbance
from rczone.control.model import ControlModel
from rczone.errors import DataError, InputShapeError
from rczone.kernels.arrays import StateMoments
from rczone.models.zone import ZoneModel

#: Prior standard deviation of the disturbance state when the filter starts: W or K.
DISTURBANCE_PRIOR_SD = {"heat": 200.0, "offset": 1.0}
#: Prior standard deviation of every node temperature when the filter starts, K.
NODE_PRIOR_SD = 2.0


class SteadyStateGain(NamedTuple):
    """Constant filter at a flow: gain ``K`` (n, ny) and predicted / filtered covariances (n, n)."""

    K: np.ndarray
    P_pred: np.ndarray
    P_filt: np.ndarray


class FilterRun(NamedTuple):
    """Time-first results of :meth:`KalmanObserver.filter`: filtered means (N, n) and covariances
    (N, n, n), one-step predictions (N, n) and innovations (N, ny, NaN where missing)."""

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    innovations: np.ndarray


class KalmanObserver:
    """The Kalman filter of a :class:`ControlModel` (see the module notes).

    Parameters
    ----------
    model : ControlModel
    """

    def __init__(self, model: ControlModel) -> None:
        self.model = model

    def predict(
        self, est: StateMoments, u: np.ndarray, m: float | np.ndarray, dt: float, *, heat: float = 0.0
    ) -> StateMoments:
        """Time update over ``dt`` s with inputs ``u`` (p,), flow ``m`` and supply-node heat ``heat`` W held."""
        d = self.model.discrete(dt, m)
        x = d.Ad @ est.x + d.Bd @ np.asarray(u, float) + d.Ed[:, 0] * heat
        P = d.Ad @ est.P @ d.Ad.T + d.Qd
        return StateMoments(x, 0.5 * (P + P.T))

    def update(self, est: StateMoments, y: np.ndarray, u: np.ndarray) -> tuple[StateMoments, np.ndarray]:
        """Measurement update with outputs ``y`` (ny,; NaN = missing); returns the estimate and the innovation."""
        c = self.model.matrices
        y = np.asarray(y, float)
        e = y - c.C @ est.x - c.D @ np.asarray(u, float)
        obs = np.flatnonzero(np.isfinite(y))
        if obs.size == 0:
            return est, e
        C, R = c.C[obs], self.model.noise.R[np.ix_(obs, obs)]
        S = C @ est.P @ C.T + R
        K = np.linalg.solve(S, C @ est.P).T
        ImKC = np.eye(len(est.x)) - K @ C
        P = ImKC @ est.P @ ImKC.T + K @ R @ K.T
        return StateMoments(est.x + K @ e[obs], 0.5 * (P + P.T)), e

    def filter(
        self, t: np.ndarray, u: np.ndarray, m: np.ndarray, y: np.ndarray, prior: StateMoments
    ) -> FilterRun:
        """Filter samples ``t`` (N,), inputs ``u`` (N, p), flows ``m`` (N, nf), outputs ``y`` (N, ny).

        ``prior`` is the state at ``t[0]`` before its measurement; inputs and flows are held from
        ``t[k]`` to ``t[k+1]``.
        """
        N = len(t)
        n = self.model.n_states
        xf, Pf, xp = np.empty((N, n)), np.empty((N, n, n)), np.empty((N, n))
        innov = np.full((N, len(self.model.output_names)), np.nan)
        est = prior
        for k in range(N):
            xp[k] = est.x
            est, innov[k] = self.update(est, y[k], u[k])
            xf[k], Pf[k] = est
            if k < N - 1:
                est = self.predict(est, u[k], m[k], float(t[k + 1] - t[k]))
        return FilterRun(xf, Pf, xp, innov)

    def steady_state(self, dt: float, m: float | np.ndarray) -> SteadyStateGain:
        """The constant (steady-state) filter at sample time ``dt`` and constant flow ``m``."""
        d = self.model.discrete(dt, m)
        P = solve_discrete_are(d.Ad.T, d.C.T, d.Qd, d.R)
        S = d.C @ P @ d.C.T + d.R
        K = np.linalg.solve(S, d.C @ P).T
        Pf = P - K @ S @ K.T
        return SteadyStateGain(K, 0.5 * (P + P.T), 0.5 * (Pf + Pf.T))

    def prior(self, y0: np.ndarray) -> StateMoments:
        """A broad prior: every node at the first measured output, :data:`NODE_PRIOR_SD` K; disturbance 0."""
        finite = np.asarray(y0, float)[np.isfinite(y0)]
        if finite.size == 0:
            raise DataError("the first sample has no measured output to start the state estimate from")
        n = self.model.n_states
        x = np.full(n, float(finite[0]))
        sd = np.full(n, NODE_PRIOR_SD)
        dist = self.model.disturbance
        if dist is not None:
            x[-1] = 0.0
            sd[-1] = DISTURBANCE_PRIOR_SD[dist.kind]
        return StateMoments(x, np.diag(sd**2))


@dataclass(frozen=True, eq=False)
class StateEstimate:
    """Mean and covariance of every node (and the disturbance) at a time.

    Attributes
    ----------
    time : float
        s, the data's time axis.
    mean : ndarray, shape (n,)
    cov : ndarray, shape (n, n)
    state_names : tuple of str
    units : tuple of str
        ``degC`` for nodes, ``W`` or ``K`` for the disturbance.
    n_samples : int
        Samples the filter used.
    """

    time: float
    mean: np.ndarray
    cov: np.ndarray
    state_names: tuple[str, ...]
    units: tuple[str, ...]
    n_samples: int

    def __getitem__(self, name: str) -> float:
        return float(self.mean[self.state_names.index(name)])

    @property
    def sd(self) -> dict[str, float]:
        """Standard deviation of each state."""
        return dict(zip(self.state_names, np.sqrt(np.clip(np.diag(self.cov), 0, None)).tolist()))

    def to_dict(self) -> dict[str, Any]:
        return {
            "time_s": self.time,
            "mean": dict(zip(self.state_names, self.mean.tolist())),
            "sd": self.sd,
            "cov": self.cov.tolist(),
            "units": dict(zip(self.state_names, self.units)),
            "n_samples": self.n_samples,
        }

    def summary(self) -> str:
        lines = [f"state estimate at t = {self.time:g} s ({self.n_samples} samples)"]
        sd = self.sd
        lines += [
            f"  {n:<10s} {self.mean[i]:10.3f} +- {sd[n]:.3f} {u}"
            for i, (n, u) in enumerate(zip(self.state_names, self.units))
        ]
        return "\n".join(lines)


def estimate_state(
    model: ZoneModel | ControlModel,
    data: pd.DataFrame,
    now: float,
    *,
    disturbance: Disturbance | None = None,
    warmup: float | None = None,
    constants: dict[str, float] | None = None,
) -> StateEstimate:
    """The state of ``model`` at time ``now`` from the data up to ``now``.

    The filter starts ``warmup`` s before ``now`` (default: the first sample) from a broad
    prior (:meth:`KalmanObserver.prior`), runs over every sample with ``time <= now`` and
    predicts from the last sample to ``now`` with its inputs held.

    Parameters
    ----------
    model : ZoneModel or ControlModel
    data : DataFrame
        ``time`` (s) and the model's signals (:meth:`ZoneModel.signals`).
    now : float
        s, on the data's time axis.
    disturbance : Disturbance, optional
        Appended state (only with a ZoneModel; a ControlModel carries its own).
    warmup : float, optional
        s of data before ``now`` to use.
    constants : mapping, optional
        Inputs held constant (as :meth:`ZoneModel.signals`).

    Returns
    -------
    StateEstimate
    """
    cm = model if isinstance(model, ControlModel) else ControlModel(model, disturbance=disturbance)
    t, u, m, y = cm.model.signals(data, constants)
    start = -np.inf if warmup is None else now - float(warmup)
    keep = (t <= now) & (t >= start)
    if keep.sum() < 1:
        raise DataError(f"no samples between t = {start:g} s and now = {now:g} s to estimate the state from")
    t, u, m, y = t[keep], u[keep], m[keep], y[keep]
    if np.any(np.diff(t) <= 0) or not np.all(np.isfinite(u)) or not np.all(np.isfinite(m)):
        raise InputShapeError(
            "the data for the state estimate need increasing times and finite inputs and flows"
        )
    obs = KalmanObserver(cm)
    run = obs.filter(t, u, m, y, obs.prior(y[np.flatnonzero(np.isfinite(y).any(axis=1))[0]]))
    est = StateMoments(run.x_filt[-1], run.P_filt[-1])
    if now > t[-1]:
        est = obs.predict(est, u[-1], m[-1], float(now - t[-1]))
    units = tuple("degC" for _ in cm.model.network.state_names)
    if cm.disturbance is not None:
        units += (cm.disturbance.unit,)
    return StateEstimate(float(now), est.x, est.P, cm.state_names, units, len(t))
