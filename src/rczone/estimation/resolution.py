"""The resolution of a measured series, and the measurement-noise floor it implies.

Building trend logs are quantized: a BMS stores 0.1 degF or 0.5 degC steps, and a unit
conversion keeps the grid. The quantization error of one reading is uniform over one step ``q``,
with standard deviation ``q / sqrt(12)`` [1]_. The lower bound of the measurement-noise level is
derived from that scale instead of a fixed value (1e-4 K binds in most real fits, and means
nothing for a logger with a 0.5 K step or a laboratory sensor with 1 mK): a tenth of
``q / sqrt(12)`` for a quantized series, a small fraction of the typical sample-to-sample change
otherwise.

Why a tenth and not the full quantization error: a slowly varying temperature read on a grid
keeps the same rounding error over many samples, so most of the quantization error is
correlated in time and the likelihood of a continuous-discrete model rightly assigns it to the
process noise, leaving a white measurement noise well below ``q / sqrt(12)``. Forcing the
measurement noise up to the full value makes the model absorb the correlated error in its
R and C instead: on the virtual building's forced nights (0.05 K sensor noise, 0.1 degF trend
resolution) the ML estimate of the white part is about 0.006 K against ``q / sqrt(12)`` = 0.016 K,
and bounding it at 0.016 K sent the wall resistance of one night in three to its upper bound.
An estimate at this floor says the white measurement noise is negligible; it is reported as a
note, not as a problem.

References
----------
.. [1] B. Widrow, I. Kollar, *Quantization Noise*, Cambridge University Press, 2008, ch. 4
   (the uniform model of quantization error, variance q^2/12).
"""

from __future__ import annotations

import math

import numpy as np

#: The floor of a quantized series as a fraction of its quantization error ``q / sqrt(12)``.
QUANTIZATION_FRACTION = 0.1
#: Fraction of distinct-value steps that must be whole multiples of the smallest one.
GRID_FRACTION = 0.95
#: Floor of an unquantized series, as a fraction of its median absolute sample-to-sample change.
CONTINUOUS_FRACTION = 1e-3
#: Smallest floor in any case, K.
ABSOLUTE_FLOOR = 1e-6


def resolution(y: np.ndarray) -> float | None:
    """The step ``q`` of the grid the values of ``y`` lie on, or None when they lie on no grid.

    Parameters
    ----------
    y : ndarray, shape (N,)
        Measured values; NaN ignored.
    """
    v = np.asarray(y, dtype=float).reshape(-1)
    v = v[np.isfinite(v)]
    u = np.unique(v)
    if u.size < 3:
        return None
    d = np.diff(u)
    scale = max(float(np.max(np.abs(u))), 1.0)
    q = float(np.min(d))
    if not q > 1e-9 * scale:
        return None
    r = d / q
    on_grid = np.abs(r - np.round(r)) < 0.02
    return q if np.mean(on_grid) >= GRID_FRACTION else None


def noise_floor(y: np.ndarray) -> float:
    """Lower bound of the measurement-noise standard deviation for series ``y``, same unit as ``y``.

    :data:`QUANTIZATION_FRACTION` times ``q / sqrt(12)`` for a series on a grid of step ``q``
    (:func:`resolution`), else
    :data:`CONTINUOUS_FRACTION` times the median absolute change between samples, and never below
    :data:`ABSOLUTE_FLOOR`.
    """
    q = resolution(y)
    if q is not None:
        return max(QUANTIZATION_FRACTION * q / math.sqrt(12.0), ABSOLUTE_FLOOR)
    v = np.asarray(y, dtype=float).reshape(-1)
    dv = np.abs(np.diff(v))
    dv = dv[np.isfinite(dv) & (dv > 0)]
    typical = float(np.median(dv)) if dv.size else 0.0
    return max(CONTINUOUS_FRACTION * typical, ABSOLUTE_FLOOR)
