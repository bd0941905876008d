"""Compiled state propagation ``x[k+1] = Phi[w] x[k] + G0[w] u[k] + G1[w] u[k+1]``.

The compiled twin of the plain NumPy loop of the tests (``tests/oracles.py``): explicit
loops over the small matrices, so a step costs ``n (n + 2 p)`` multiply-adds and no
Python or BLAS call overhead.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rczone.kernels.arrays import writable


@njit(cache=True, error_model="numpy")
def propagate_kernel(
    Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray, x0: np.ndarray
) -> np.ndarray:
    """Step the discretized model through all samples.

    Parameters
    ----------
    Phi : ndarray, shape (K, n, n)
    G0, G1 : ndarray, shape (K, n, p)
    which : ndarray of int64, shape (N-1,)
        Index of the discretization used on each interval.
    u : ndarray, shape (N, p)
    x0 : ndarray, shape (n,)

    Returns
    -------
    x : ndarray, shape (N, n)
    """
    N, p = u.shape
    n = x0.shape[0]
    x = np.empty((N, n))
    for i in range(n):  # a loop: slice assignment costs seconds of numba compile time
        x[0, i] = x0[i]
    for k in range(N - 1):
        w = which[k]
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += Phi[w, i, j] * x[k, j]
            for j in range(p):
                acc += G0[w, i, j] * u[k, j] + G1[w, i, j] * u[k + 1, j]
            x[k + 1, i] = acc
    return x


def propagate(
    Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray, x0: np.ndarray
) -> np.ndarray:
    """:func:`propagate_kernel` on contiguous float64 copies of the arguments (shapes as there)."""
    # writable copies where needed: read-only inputs would compile a second specialization
    f = writable
    return propagate_kernel(f(Phi), f(G0), f(G1), f(which, np.int64), f(u), f(x0))
