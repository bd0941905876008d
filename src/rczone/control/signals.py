"""The test's signals: the comfort band by the thermostat's schedule, the price, and their forecasts.

Prices per kWh (``price`` in a closed-loop test; the cost is the price-weighted energy):

* ``flat``: 1 at every hour (the cost is the energy);
* ``tou``: a time-of-use price, :data:`PEAK_PRICE` times from noon to 6 pm (a summer on-peak
  window, when pre-cooling pays), known in advance;
* ``dr``: a demand-response event, :data:`DR_PRICE` times from 2 pm to 4 pm every day
  (:data:`DR_HOURS`), announced :data:`DR_NOTICE` ahead (a price or curtailment signal for a few
  afternoon hours, notified hours ahead, as described by Braun [1]_).

Comfort bands: the thermostat's (``normal``), or its occupied band narrowed to
:data:`TIGHT_BAND_K` about its centre (``tight``; the normal one is 1.8 K in summer, 1.1 K in
winter). Times are s from 6 pm.

References
----------
.. [1] J. E. Braun, "Load control using building thermal mass", J. Solar Energy Engineering
   125(3) (2003) 292-301 (pre-cooling ahead of an afternoon peak or event).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from rczone.virtual.control import ControllerConfig
from rczone.virtual.emulator import DAY

PRICES = ("flat", "tou", "dr")
PEAK_PRICE = 3.0
PEAK_HOURS = (18 * 3600.0, 24 * 3600.0)  # s after 6 pm: noon to 6 pm
DR_PRICE = 10.0
DR_HOURS = (20 * 3600.0, 22 * 3600.0)  # s after 6 pm: 2 pm to 4 pm
DR_NOTICE = 3 * 3600.0
BANDS = ("normal", "tight")
TIGHT_BAND_K = 0.8


class Band(NamedTuple):
    """The comfort band at some times: ``lower``, ``upper`` (degC) and ``occupied`` (bool)."""

    lower: np.ndarray
    upper: np.ndarray
    occupied: np.ndarray


def band(cfg: ControllerConfig, t: np.ndarray) -> Band:
    """The thermostat's band by its schedule at times ``t`` (s from 6 pm)."""
    unocc = np.array([cfg.unoccupied(float(x)) for x in np.atleast_1d(t)], dtype=bool)
    lower = np.where(unocc, cfg.heat_unocc, cfg.heat_occ)
    upper = np.where(unocc, cfg.cool_unocc, cfg.cool_occ)
    return Band(lower, upper, ~unocc)


def window(t: np.ndarray, hours: tuple[float, float]) -> np.ndarray:
    """Whether each of ``t`` falls in the daily window ``hours`` (s after 6 pm)."""
    tm = np.asarray(t, float) % DAY
    return (tm >= hours[0]) & (tm < hours[1])


def price_signal(kind: str, t: np.ndarray) -> np.ndarray:
    """Price per kWh at ``t`` (s from 6 pm): 1, :data:`PEAK_PRICE` in the peak window ("tou"),
    or :data:`DR_PRICE` in the demand-response event ("dr")."""
    if kind == "dr":
        return np.where(window(t, DR_HOURS), DR_PRICE, 1.0)
    return np.where(window(t, PEAK_HOURS) & (kind == "tou"), PEAK_PRICE, 1.0)


def forecast_price(kind: str, now: float, times: np.ndarray) -> np.ndarray:
    """The price at ``times`` as known at ``now`` (s from 6 pm).

    The time-of-use price is known in advance; a demand-response event only from its
    announcement, :data:`DR_NOTICE` before its start, on (the normal price before that).
    """
    p = price_signal(kind, times)
    if kind == "dr":
        starts = np.floor((np.asarray(times, float) - DR_HOURS[0]) / DAY) * DAY + DR_HOURS[0]
        p = np.where(now >= starts - DR_NOTICE, p, 1.0)
    return p


def tighten(cfg: ControllerConfig, width: float = TIGHT_BAND_K) -> ControllerConfig:
    """``cfg`` with its occupied band narrowed to ``width`` K about its centre (unoccupied band kept)."""
    mid = 0.5 * (cfg.heat_occ + cfg.cool_occ)
    return replace(cfg, heat_occ=mid - 0.5 * width, cool_occ=mid + 0.5 * width)
