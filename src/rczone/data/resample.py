"""Resampling of irregular, unaligned trend logs onto a uniform time grid.

BMS trend logs are rarely uniform: points are logged on change of value or on their own
intervals, and two points seldom share time stamps. Models are simulated on one uniform
grid, so each channel is resampled separately from its own finite samples:

* **temperatures and heat inputs** -- time-weighted linear interpolation between the two
  samples that bracket a grid time, ``x(g) = (x_i (t_{i+1} - g) + x_{i+1} (g - t_i)) /
  (t_{i+1} - t_i)``; a linear signal is therefore reproduced exactly on the grid;
* **flows** (``quantity = "flow"``) -- previous-value hold, ``x(g) = x_i`` for
  ``t_i <= g < t_{i+1}``, because a VAV flow is a command that stays at its set value
  until the next one (and the simulator holds it constant over each interval too).

A grid time whose bracketing samples are more than ``max_gap`` seconds apart gets NaN:
nothing is ever interpolated or held across a long gap. Grid times before the first or
after the last finite sample are NaN too; a grid time equal to a sample time takes that
sample. The grid is aligned to integer multiples of ``step`` in UTC epoch seconds (a
300 s grid falls on :00, :05, ...), from the first to the last time stamp of the record.
"""

from __future__ import annotations

import math

import numpy as np

from rczone.errors import DataError

MAX_SAMPLES = 2_000_000
"""Most grid times a record is resampled onto (23 days at 1 s, 3.8 years at 1 min)."""


def uniform_grid(t_first: float, t_last: float, step: float) -> np.ndarray:
    """Multiples of ``step`` within ``[t_first, t_last]`` (s), in increasing order.

    Raises
    ------
    DataError
        If the grid would have more than :data:`MAX_SAMPLES` times.
    """
    k0 = math.ceil(t_first / step - 1e-9)
    k1 = math.floor(t_last / step + 1e-9)
    if k1 - k0 + 1 > MAX_SAMPLES:
        raise DataError(
            f"[resample] step = {step:g} s over {t_last - t_first:g} s of data gives {k1 - k0 + 1:,} samples,"
            f" more than the limit of {MAX_SAMPLES:,} (rczone.data.resample.MAX_SAMPLES); use a larger step"
        )
    return np.arange(k0, k1 + 1, dtype=float) * step


def _bracket(t: np.ndarray, x: np.ndarray, grid: np.ndarray):
    ok = np.isfinite(x)
    tt, xx = np.asarray(t, dtype=float)[ok], np.asarray(x, dtype=float)[ok]
    i = np.searchsorted(tt, grid, side="right") - 1
    return tt, xx, i


def interpolate_linear(t: np.ndarray, x: np.ndarray, grid: np.ndarray, max_gap: float) -> np.ndarray:
    """Linear interpolation of ``x(t)`` onto ``grid``, NaN across gaps longer than ``max_gap``.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Strictly increasing sample times (s).
    x : ndarray, shape (N,)
        Samples; NaN samples are skipped.
    grid : ndarray, shape (G,)
        Times to evaluate at (s).
    max_gap : float
        Longest spacing (s) of bracketing samples that may be interpolated across.

    Returns
    -------
    ndarray, shape (G,)
    """
    tt, xx, i = _bracket(t, x, grid)
    out = np.full(grid.shape, np.nan)
    n = tt.size
    if n == 0:
        return out
    exact = (i >= 0) & (tt[np.clip(i, 0, n - 1)] == grid)
    out[exact] = xx[i[exact]]
    inner = (i >= 0) & (i < n - 1) & ~exact
    a = i[inner]
    t0, t1, g = tt[a], tt[a + 1], grid[inner]
    span = t1 - t0
    val = (xx[a] * (t1 - g) + xx[a + 1] * (g - t0)) / span
    out[inner] = np.where(span <= max_gap, val, np.nan)
    return out


def hold_previous(t: np.ndarray, x: np.ndarray, grid: np.ndarray, max_gap: float) -> np.ndarray:
    """Previous-value hold of ``x(t)`` onto ``grid``, NaN across gaps longer than ``max_gap``.

    Same arguments as :func:`interpolate_linear`.
    """
    tt, xx, i = _bracket(t, x, grid)
    out = np.full(grid.shape, np.nan)
    n = tt.size
    if n == 0:
        return out
    exact = (i >= 0) & (tt[np.clip(i, 0, n - 1)] == grid)
    out[exact] = xx[i[exact]]
    inner = (i >= 0) & (i < n - 1) & ~exact
    a = i[inner]
    out[inner] = np.where(tt[a + 1] - tt[a] <= max_gap, xx[a], np.nan)
    return out
