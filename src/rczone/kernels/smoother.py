"""The Rauch-Tung-Striebel smoother: a backward pass over what the Kalman filter kept.

The filter (:func:`rczone.kernels.kalman.kalman_filter`) runs forward and keeps, per sample, the
predicted mean and covariance ``x_k|k-1, P_k|k-1`` and the filtered ones ``x_k|k, P_k|k``
(:class:`rczone.kernels.arrays.FilterTrace`). The smoother [1]_ then runs backward from the last
sample, where smoothed and filtered estimates coincide, with the transition matrix ``Phi`` of each
step:

``J_k = P_k|k Phi_k' P_k+1|k^-1``,
``x_k|N = x_k|k + J_k (x_k+1|N - x_k+1|k)``,
``P_k|N = P_k|k + J_k (P_k+1|N - P_k+1|k) J_k'``.

The inputs need not be known to the backward pass: they entered ``x_k+1|k`` already. The gain is
computed by solving ``P_k+1|k J_k' = Phi_k P_k|k`` (LU with pivoting, no explicit inverse); a
singular predicted covariance (a state without any noise) falls back to its pseudo-inverse,
which gives the minimum-norm gain [2]_.

References
----------
.. [1] H. E. Rauch, F. Tung, C. T. Striebel, "Maximum likelihood estimates of linear dynamic
   systems", AIAA Journal 3(8), 1965, 1445-1450.
.. [2] S. Särkkä, *Bayesian Filtering and Smoothing*, Cambridge University Press, 2013,
   theorem 8.2 (the Rauch-Tung-Striebel smoother).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rczone.kernels.arrays import StateMoments


@njit(cache=True, error_model="numpy")
def smoother_gain(Pf: np.ndarray, Phi: np.ndarray, Pp_next: np.ndarray) -> np.ndarray:
    """``J = Pf Phi' Pp_next^-1``, shape (n, n), from one linear solve.

    Parameters
    ----------
    Pf : ndarray, shape (n, n)
        Filtered covariance at ``k``.
    Phi : ndarray, shape (n, n)
        Transition from ``k`` to ``k + 1``.
    Pp_next : ndarray, shape (n, n)
        Predicted covariance at ``k + 1``.

    Returns
    -------
    ndarray, shape (n, n)
    """
    G = Phi @ Pf
    try:
        Jt = np.linalg.solve(Pp_next, G)
    except Exception:  # a singular prediction: the minimum-norm gain
        Jt = np.linalg.pinv(Pp_next) @ G
    return Jt.T.copy()


@njit(cache=True, error_model="numpy")
def smooth_step(
    xf: np.ndarray, Pf: np.ndarray, Phi: np.ndarray, predicted_next: StateMoments, smoothed_next: StateMoments
) -> StateMoments:
    """One backward step: the smoothed mean and covariance at ``k`` from those at ``k + 1``.

    Parameters
    ----------
    xf : ndarray, shape (n,)
        Filtered mean at ``k``.
    Pf : ndarray, shape (n, n)
        Filtered covariance at ``k``.
    Phi : ndarray, shape (n, n)
        Transition from ``k`` to ``k + 1``.
    predicted_next : StateMoments
        The filter's prediction at ``k + 1`` (``x`` of shape (n,), ``P`` of shape (n, n)).
    smoothed_next : StateMoments
        The smoothed mean and covariance at ``k + 1``.

    Returns
    -------
    StateMoments
        ``x`` of shape (n,), ``P`` of shape (n, n), exactly symmetric.
    """
    J = smoother_gain(Pf, Phi, predicted_next.P)
    x = xf + J @ (smoothed_next.x - predicted_next.x)
    P = Pf + J @ (smoothed_next.P - predicted_next.P) @ J.T
    return StateMoments(x, 0.5 * (P + P.T))


@njit(cache=True, error_model="numpy")
def rts_smoother(
    Phi: np.ndarray, which: np.ndarray, predicted: StateMoments, filtered: StateMoments
) -> StateMoments:
    """The backward pass over all samples.

    Parameters
    ----------
    Phi : ndarray, shape (K, n, n)
        Transition matrices of the distinct intervals.
    which : ndarray, shape (N - 1,)
        Step ``k`` uses ``Phi[which[k]]``.
    predicted : StateMoments
        The filter's predicted means (N, n) and covariances (N, n, n).
    filtered : StateMoments
        The filter's filtered means (N, n) and covariances (N, n, n).

    Returns
    -------
    StateMoments
        Means (N, n) and covariances (N, n, n); the last sample's are the filter's.
    """
    N = filtered.x.shape[0]
    xs = np.empty_like(filtered.x)
    Ps = np.empty_like(filtered.P)
    xs[N - 1] = filtered.x[N - 1]
    Ps[N - 1] = filtered.P[N - 1]
    for k in range(N - 2, -1, -1):
        step = smooth_step(
            filtered.x[k],
            filtered.P[k],
            Phi[which[k]],
            StateMoments(predicted.x[k + 1], predicted.P[k + 1]),
            StateMoments(xs[k + 1], Ps[k + 1]),
        )
        xs[k] = step.x
        Ps[k] = step.P
    return StateMoments(xs, Ps)
