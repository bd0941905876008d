"""Exact discretization of LTI state spaces through the matrix exponential.

* zero-order hold (inputs constant over a sample),
* first-order hold (inputs linear between samples),
* the discrete process-noise covariance of a continuous white-noise input (Van Loan).

All functions are pure over arrays.

References
----------
.. [1] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of Dynamic Systems*,
   3rd ed., 1998, sections 6.3 (ZOH) and 6.3.2 (triangle hold / FOH).
.. [2] C. F. Van Loan, "Computing integrals involving the matrix exponential",
   IEEE Trans. Automatic Control 23(3), 1978.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm


def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretization: ``x[k+1] = Phi x[k] + Gamma u[k]``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, p)
    dt : float
        Sample interval, s.

    Returns
    -------
    Phi : ndarray, shape (n, n)
    Gamma : ndarray, shape (n, p)
    """
    n, p = B.shape
    blk = np.zeros((n + p, n + p))
    blk[:n, :n] = A * dt
    blk[:n, n:] = B * dt
    E = expm(blk)
    return E[:n, :n], E[:n, n:]


def foh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-order-hold discretization: ``x[k+1] = Phi x[k] + G0 u[k] + G1 u[k+1]``.

    The input is linear between the samples ``u[k]`` and ``u[k+1]``.

    Returns
    -------
    Phi : ndarray, shape (n, n)
    G0, G1 : ndarray, shape (n, p)
    """
    n, p = B.shape
    blk = np.zeros((n + 2 * p, n + 2 * p))
    blk[:n, :n] = A * dt
    blk[:n, n : n + p] = B * dt
    blk[n : n + p, n + p :] = np.eye(p)
    E = expm(blk)
    gz, gr = E[:n, n : n + p], E[:n, n + p :]
    return E[:n, :n], gz - gr, gr


def van_loan(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """Discrete covariance ``Qd = int_0^dt e^{A s} Qc e^{A' s} ds`` of continuous white noise.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    Qc : ndarray, shape (n, n)
        Continuous-time noise intensity (``sigma sigma'``), units of x^2/s.
    dt : float

    Returns
    -------
    Qd : ndarray, shape (n, n), symmetric
    """
    n = A.shape[0]
    blk = np.zeros((2 * n, 2 * n))
    blk[:n, :n] = -A * dt
    blk[:n, n:] = Qc * dt
    blk[n:, n:] = A.T * dt
    E = expm(blk)
    Phi_T = E[n:, n:]
    Qd = Phi_T.T @ E[:n, n:]
    return 0.5 * (Qd + Qd.T)
