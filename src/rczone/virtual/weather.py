"""Outdoor temperature of the virtual building's nights (Gainesville, Florida climate).

A smooth diurnal curve plus seeded noise:

``To(h) = mean + amp * cos(2 pi (h - 15) / 24) + offset + e(h)``

with ``h`` the clock hour (maximum at 15:00, minimum near 03:00-06:00), ``offset ~
N(0, 0.7 K)`` per night and ``e`` a first-order autoregressive (Ornstein-Uhlenbeck)
process with standard deviation 0.3 K and correlation time 1 h. Seasonal mean and
amplitude give the night ranges of Gainesville's climate (NOAA 1991-2020 normals:
August daily min/max about 22/33 degC, December about 6/21 degC, late October about
14/27 degC), moderated for the 6 pm to 6 am window: summer about 24-29 degC, winter about
2-12 degC, autumn about 12-20 degC.

References
----------
.. [1] NOAA NCEI, U.S. climate normals 1991-2020, Gainesville Regional Airport, FL.
"""

from __future__ import annotations

import numpy as np

from rczone.errors import ParameterError, did_you_mean

#: Season -> (mean, amplitude) of the diurnal curve, degC.
DIURNAL = {"summer": (26.5, 2.5), "winter": (7.0, 5.0), "autumn": (16.0, 4.0)}
#: Night-to-night offset standard deviation, K.
OFFSET_STD = 0.7
#: Fast weather noise: standard deviation (K) and correlation time (s).
NOISE_STD = 0.3
NOISE_TAU = 3600.0
#: Clock hour of time 0 (6 pm).
NIGHT_START_HOUR = 18.0


def check_season(season: str) -> str:
    """Validate a season name."""
    if season not in DIURNAL:
        raise ParameterError(f"unknown season {season!r}; " + did_you_mean(season, DIURNAL))
    return season


def diurnal_curve(season: str, t: np.ndarray) -> np.ndarray:
    """The smooth part ``mean + amp cos(2 pi (h - 15)/24)`` at ``t`` (s from 6 pm), degC: a forecast."""
    mean, amp = DIURNAL[check_season(season)]
    h = NIGHT_START_HOUR + np.asarray(t, dtype=float) / 3600.0
    return mean + amp * np.cos(2 * np.pi * (h - 15.0) / 24.0)


def outdoor_temperature(season: str, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Outdoor temperature at times ``t`` (s from 6 pm, equally spaced), degC.

    Parameters
    ----------
    season : {"summer", "winter", "autumn"}
    t : ndarray, shape (N,)
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (N,)
    """
    t = np.asarray(t, dtype=float)
    base = diurnal_curve(season, t) + rng.normal(0.0, OFFSET_STD)
    dt = float(t[1] - t[0]) if t.size > 1 else 60.0
    a = np.exp(-dt / NOISE_TAU)
    w = rng.normal(0.0, NOISE_STD * np.sqrt(1 - a * a), size=t.size)
    e = np.empty(t.size)
    e[0] = rng.normal(0.0, NOISE_STD)
    for k in range(1, t.size):
        e[k] = a * e[k - 1] + w[k]
    return base + e
