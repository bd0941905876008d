"""Distinct sampling intervals: the ``(dt, m)`` pairs a discretization depends on.

An interval's discrete matrices depend only on its length and the flows held over it, so
every discretization is computed once per distinct pair. Finding them with
``np.unique(key, axis=0)`` sorts a structured view (about 0.6 ms for one night of 720
samples, paid by every simulation and likelihood); sorting the columns with
:func:`numpy.lexsort` and comparing neighbours gives the same groups in a few tens of
microseconds.
"""

from __future__ import annotations

import numpy as np


def unique_rows(key: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distinct rows of a float array, as ``np.unique(key, axis=0, return_index=True, return_inverse=True)``.

    Parameters
    ----------
    key : ndarray, shape (K, c)
        Finite values (rows equal when every entry compares equal, so ``-0.0 == 0.0``).

    Returns
    -------
    uniq : ndarray, shape (G, c)
        Distinct rows in lexicographic order (first column first).
    first : ndarray of int64, shape (G,)
        Index of each distinct row's first occurrence in ``key``.
    inverse : ndarray of int64, shape (K,)
        ``uniq[inverse] == key``.
    """
    key = np.asarray(key, dtype=np.float64)
    if key.ndim != 2:
        raise ValueError(f"key must be 2-D, got shape {key.shape}")
    n = key.shape[0]
    if n == 0 or key.shape[1] == 0:
        g = min(n, 1)
        return key[:g], np.zeros(g, dtype=np.int64), np.zeros(n, dtype=np.int64)
    order = np.lexsort(key.T[::-1])  # stable: equal rows keep their order, the first one leads
    ranked = key[order]
    new = np.empty(n, dtype=bool)
    new[0] = True
    np.any(ranked[1:] != ranked[:-1], axis=1, out=new[1:])
    inverse = np.empty(n, dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return ranked[new], order[new].astype(np.int64), inverse


def interval_keys(t: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``(dt, m)`` of every interval, shape (N - 1, 1 + n_flows)."""
    return np.column_stack([np.diff(t), np.asarray(m)[:-1]])
