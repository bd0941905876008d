"""A band calibrated per horizon on the calibration data's own k-step errors.

A likelihood fit's noise levels make the one-step band right by construction: the filter's
innovations are standardized by them. Beyond one step the band is the model's own extrapolation
of that noise, and a misspecified model (autocorrelated innovations: a 2-state model of a real
house) errs far more than it says: on the Bacher & Madsen house the default TiTe fit's 2-sigma band
holds 72 % of the measurements 1 h ahead and 45 % 6 h ahead. The fix used here is empirical and
says so: after the fit, the k-step errors on the calibration data, standardized by the model's own
k-step standard deviation, give per horizon the factor by which the band must be widened (or
narrowed) so that it holds the nominal 95.45 % of them (a quantile calibration of the predictive
distribution, Gneiting, Balabdaoui and Raftery 2007; the split-conformal interval of Lei et al.
2018 without the split). The factors are saved with the fitted model (provenance ``band_scale``)
and applied to the noise part of every later band; the held-out coverage, reported per horizon by
``rczone predict --horizons``, says how far they carry over (docs/validation.md).

References
----------
.. [1] T. Gneiting, F. Balabdaoui, A. E. Raftery, "Probabilistic forecasts, calibration and
   sharpness", Journal of the Royal Statistical Society B 69 (2007) 243-268.
.. [2] J. Lei, M. G'Sell, A. Rinaldo, R. J. Tibshirani, L. Wasserman, "Distribution-free predictive
   inference for regression", Journal of the American Statistical Association 113 (2018) 1094-1111.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rczone.errors import DataError
from rczone.estimation.data import Dataset
from rczone.network import RCNetwork

#: Steps ahead at which a fit calibrates its band (those shorter than a quarter of the data).
CALIBRATION_STEPS = (1, 2, 3, 6, 12, 24, 48, 72, 144, 288)

#: Probability of a normal variable within two standard deviations: a 2-sigma band's nominal coverage.
TWO_SIGMA_COVERAGE = 0.9545

#: Fewest standardized errors a factor is computed from.
MIN_ERRORS = 50

#: Most prediction origins the factors are computed from (evenly spaced): bounds the memory of the
#: propagated covariances on long records (a year of 5-min samples) at no loss of precision.
MAX_ORIGINS = 5000


@dataclass(frozen=True)
class BandScale:
    """Factors on the noise standard deviation per horizon, calibrated on the fit's data.

    Attributes
    ----------
    horizon_s : tuple of float
        Horizons, s, increasing.
    scale : tuple of float
        Factor at each horizon.
    open_loop : float or None
        Factor of the open-loop band (None: not calibrated).
    """

    horizon_s: tuple[float, ...]
    scale: tuple[float, ...]
    open_loop: float | None = None

    def at(self, horizon_s: float | None) -> float:
        """The factor at a horizon (s; None for open loop), linear in log-horizon between the calibrated ones.

        Beyond the calibrated range the nearest end's factor is used; open loop without its own
        factor takes the longest horizon's.

        Parameters
        ----------
        horizon_s : float or None
            Horizon, s.
        """
        if horizon_s is None:
            return self.open_loop if self.open_loop is not None else self.scale[-1]
        return float(np.interp(math.log(horizon_s), np.log(self.horizon_s), self.scale))

    def to_dict(self) -> dict:
        """JSON-ready, as saved in a fitted model's provenance."""
        return {"horizon_s": list(self.horizon_s), "scale": list(self.scale), "open_loop": self.open_loop}

    @classmethod
    def from_dict(cls, d: object) -> BandScale:
        """The inverse of :meth:`to_dict`; a malformed entry (a model file is untrusted) is a DataError.

        Parameters
        ----------
        d : dict
            ``{"horizon_s": [...], "scale": [...], "open_loop": float or None}``.
        """
        try:
            h = tuple(float(v) for v in d["horizon_s"])  # type: ignore[index]
            s = tuple(float(v) for v in d["scale"])  # type: ignore[index]
            ol = d.get("open_loop")  # type: ignore[union-attr]
            ol = None if ol is None else float(ol)
            good = len(h) == len(s) > 0 and all(v > 0 and math.isfinite(v) for v in (*h, *s))
            if not good or np.any(np.diff(h) <= 0) or (ol is not None and not (ol > 0 and math.isfinite(ol))):
                raise ValueError
        except (KeyError, TypeError, ValueError, AttributeError):
            raise DataError(
                "the model's saved band calibration (band_scale) is malformed: expected increasing positive"
                " horizon_s, positive scale factors of the same length and an optional open_loop factor;"
                " fit the model again"
            ) from None
        return cls(h, s, ol)


def quantile_scale(error: np.ndarray, sd: np.ndarray) -> float | None:
    """The factor on ``sd`` that puts the nominal 95.45 % of ``error`` inside plus or minus two ``sd``.

    Parameters
    ----------
    error, sd : ndarray
        Errors and the model's standard deviations, same shape (NaN entries skipped).

    Returns
    -------
    float or None
        None with fewer than :data:`MIN_ERRORS` usable entries.
    """
    z = np.abs(np.asarray(error, dtype=float) / np.asarray(sd, dtype=float))
    z = z[np.isfinite(z)]
    if z.size < MIN_ERRORS:
        return None
    return max(float(np.quantile(z, TWO_SIGMA_COVERAGE)) / 2.0, 1e-3)


def calibrate_band(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> BandScale | None:
    """Per-horizon factors of a stochastic model's band from its k-step and open-loop errors on ``data``.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        The fitted values and noise levels.
    data : Dataset
        The calibration data.
    hold : {"zoh", "foh"}

    Returns
    -------
    BandScale or None
        None when the data are too short for any horizon.
    """
    from rczone.estimation.forecast import k_step_bands, open_loop_band

    N = data.n_samples
    steps = [k for k in CALIBRATION_STEPS if k <= N // 4]
    if not steps:
        return None
    dt = float(np.median(np.diff(data.t)))
    origins = np.unique(np.linspace(0, N - 1, min(N, MAX_ORIGINS)).round().astype(int))
    bands = k_step_bands(network, values, data, steps, hold, origins=origins)
    horizons, factors = [], []
    for k in steps:
        f = quantile_scale(data.y - bands[k].y_hat, bands[k].sd)
        if f is not None:
            horizons.append(k * dt)
            factors.append(f)
    if not factors:
        return None
    y_ol, sd_ol = open_loop_band(network, values, data, hold)
    return BandScale(tuple(horizons), tuple(factors), quantile_scale((data.y - y_ol)[1:], sd_ol[1:]))
