"""k-step-ahead predictions from the filtered states: one compiled pass over every origin.

From the filtered mean and covariance ``x_j|j, P_j|j`` at an origin ``j`` the prediction ``k``
steps on is propagated with the known inputs and the process noise [1]_:

``x_j+i+1|j = Phi_w x_j+i|j + d_j+i``, ``P_j+i+1|j = Phi_w P_j+i|j Phi_w' + Qd_w``,

read off as ``y = C x + D u`` with the variance ``diag(C P C') + r`` after each requested number of
steps. Written as loops over small matrices: the NumPy version (stacked matrix products over the
origins, one step at a time) spent most of a batch zone's band calibration allocating the stacks.

References
----------
.. [1] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007, section 10.3 (k-step prediction
   with the Kalman filter).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class Propagation(NamedTuple):
    """How the state moves between samples: ``x+ = Phi[w] x + drive``, ``P+ = Phi[w] P Phi[w]' + Qd[w]``."""

    Phi: np.ndarray  #: (K, n, n)
    Qd: np.ndarray  #: (K, n, n)
    which: np.ndarray  #: (N - 1,) int64, interval ``t`` uses the matrices ``which[t]``
    drive: np.ndarray  #: (N - 1, n) the inputs' contribution over interval ``t``


class Readout(NamedTuple):
    """``y = C x + Du`` with the measurement variances ``r``."""

    C: np.ndarray  #: (ny, n)
    Du: np.ndarray  #: (N, ny) the direct feed-through ``D u`` per sample
    r: np.ndarray  #: (ny,) K^2


class Origins(NamedTuple):
    """Where the predictions start and after how many steps they are read."""

    x: np.ndarray  #: (N, n) filtered means
    P: np.ndarray  #: (N, n, n) filtered covariances
    start: np.ndarray  #: (M,) int64, increasing sample indices
    slot: np.ndarray  #: (kmax + 1,) int64, output slot of ``k`` steps ahead, -1 where not asked


@njit(cache=True)
def k_step_moments(
    prop: Propagation, out: Readout, orig: Origins
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """k-step predictions and their variances, shape (S, N, ny) each (NaN where none)."""
    N, n = orig.x.shape
    ny = out.C.shape[0]
    kmax = orig.slot.shape[0] - 1
    S = 0
    for k in range(kmax + 1):
        if orig.slot[k] >= 0:
            S += 1
    y_hat = np.full((S, N, ny), np.nan)
    var = np.full((S, N, ny), np.nan)
    x = np.empty(n)
    xn = np.empty(n)
    P = np.empty((n, n))
    T = np.empty((n, n))
    for o in orig.start:
        for a in range(n):
            x[a] = orig.x[o, a]
            for b in range(n):
                P[a, b] = orig.P[o, a, b]
        for i in range(kmax):
            t = o + i
            if t + 1 >= N:
                break
            w = prop.which[t]
            F = prop.Phi[w]
            for a in range(n):
                s = prop.drive[t, a]
                for b in range(n):
                    s += F[a, b] * x[b]
                xn[a] = s
            for a in range(n):
                x[a] = xn[a]
                for b in range(n):
                    s = 0.0
                    for c in range(n):
                        s += F[a, c] * P[c, b]
                    T[a, b] = s
            for a in range(n):
                for b in range(a, n):
                    s = prop.Qd[w, a, b]
                    for c in range(n):
                        s += T[a, c] * F[b, c]
                    P[a, b] = s
                    P[b, a] = s
            j = orig.slot[i + 1]
            if j < 0:
                continue
            for m in range(ny):
                s = out.Du[t + 1, m]
                v = out.r[m]
                for a in range(n):
                    s += out.C[m, a] * x[a]
                    ca = out.C[m, a]
                    if ca != 0.0:
                        for b in range(n):
                            v += ca * P[a, b] * out.C[m, b]
                y_hat[j, t + 1, m] = s
                var[j, t + 1, m] = v
    return y_hat, var
