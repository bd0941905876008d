"""Checks after a fit: is the estimate one the data actually pin down?

A fit always returns numbers. These checks say which of them to believe:

* **profile flatness**: the cost re-minimized over the other parameters with one parameter
  held at values from ten times smaller to ten times larger. The rise is counted in
  log-likelihood units of *effective* independent samples (one per error correlation time, as
  in :func:`rczone.diagnostics.diagnose`); if it stays below ``chi2(1, 0.95) / 2 = 1.92`` at
  either end, the data cannot rule out a value ten times off;
* **estimates at a bound** of the search box;
* **estimates far from the construction values** (more than a factor ``far`` off);
* **disagreement between fits to different data sets**: two estimates whose log-ratio exceeds
  twice its standard error and a factor ``tolerance``.

References
----------
.. [1] A. Raue et al., "Structural and practical identifiability analysis of partially observed
   dynamical models by exploiting the profile likelihood", Bioinformatics 25(15), 2009.
.. [2] Lin, Middelkoop, Barooah, IEEE CDC 2012, section IV (a fit to closed-loop data that
   fits yet is grossly wrong).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.special import chdtri

from rczone.errors import ParameterError
from rczone.estimation import FitResult
from rczone.estimation.costs import MAP_CORRELATION_TIME, PRIOR_SPREAD, Objective, auto_initial_state
from rczone.estimation.data import Dataset
from rczone.estimation.methods import method_of
from rczone.estimation.parameters import make_spec
from rczone.estimation.uncertainty import profile
from rczone.models import ZoneModel, load_model
from rczone.network import RCNetwork
from rczone.network.stochastic import initial_state_name, is_reserved

#: Rise of the tempered negative log-likelihood that a 95 % profile interval allows.
PROFILE_THRESHOLD = 0.5 * float(chdtri(1, 0.05))  # chi2(1) 95 % quantile


@dataclass(frozen=True)
class ProfileCheck:
    """The profile of one parameter and what it says.

    Attributes
    ----------
    name : str
    values : ndarray
        Grid of the parameter (SI).
    rise : ndarray
        Rise of the tempered negative log-likelihood above its minimum along the grid.
    interval : tuple of float
        95 % profile interval (NaN where the grid does not reach the threshold: open).
    flat_low, flat_high : bool
        The profile stays below the threshold down to ``estimate / factor`` (up to
        ``estimate * factor``).
    """

    name: str
    values: np.ndarray
    rise: np.ndarray
    interval: tuple[float, float]
    flat_low: bool
    flat_high: bool

    @property
    def flat(self) -> bool:
        return self.flat_low or self.flat_high

    def to_dict(self) -> dict:
        return {
            "values": self.values.tolist(),
            "rise": self.rise.tolist(),
            "interval": list(self.interval),
            "flat_low": self.flat_low,
            "flat_high": self.flat_high,
        }


@dataclass(frozen=True)
class Disagreement:
    """One parameter estimated on two data sets."""

    name: str
    data_a: str
    data_b: str
    estimate_a: float
    estimate_b: float
    z: float
    disagree: bool

    def to_dict(self) -> dict:
        return {k: v for k, v in vars(self).items() if k != "name"}


class PreparedLike(Protocol):
    """Prepared data (:class:`rczone.calibration.PreparedData`): what a profile reads of it."""

    dataset: Dataset


def data_set(data: Dataset | PreparedLike) -> Dataset:
    """The data set of ``data`` (a :class:`Dataset` as it is, or prepared data's)."""
    if isinstance(data, Dataset):
        return data
    found = getattr(data, "dataset", None)
    if isinstance(found, Dataset):
        return found
    raise ParameterError(
        f"profile_checks needs the data set the fit used, got a {type(data).__name__}; pass the"
        " calibration's data (cal.data) or rczone.calibration.prepare(model, frame)"
    )


def correlation_time(res: FitResult) -> float:
    """The output error's correlation time the fit assumed, s (a MAP fit's option, else the default)."""
    return float(res.options.get("correlation_time_s", MAP_CORRELATION_TIME))


def _inside(value: float, lo: float, hi: float) -> float:
    """An estimate at (or, by rounding, just past) a bound, moved a hair inside it: a start must be."""
    eps = 1e-9 * (hi - lo)
    return float(min(max(value, lo + eps), hi - eps))


def _objective(network: RCNetwork, data: Dataset, res: FitResult) -> tuple[Objective, float]:
    ss0 = network.state_space()
    x0a = auto_initial_state(ss0, data.u[0], data.m[0], data.y[0])
    x0_auto = {initial_state_name(s): float(v) for s, v in zip(ss0.state_names, x0a)}
    fixed = {
        k: v for k, v in res.fixed.items() if k not in network.parameters or not network.parameters[k].is_tied
    }
    spec = make_spec(
        network,
        res.names,
        bounds={n: (e.lower, e.upper) for n, e in res.parameters.items()},
        start={n: _inside(e.value, e.lower, e.upper) for n, e in res.parameters.items()},
        fixed=fixed,
        x0_auto=x0_auto,
    )
    dt = float(np.median(np.diff(data.t)))
    w = min(1.0, dt / correlation_time(res))
    obj = Objective(
        network,
        data,
        spec,
        res.method,
        res.hold,
        prior_spread=float(res.options.get("prior_spread", PRIOR_SPREAD)),
        likelihood_weight=w if method_of(res.method).prior else 1.0,
    )
    return obj, w


def profile_checks(
    network: RCNetwork | ZoneModel,
    data: Dataset | PreparedLike,
    res: FitResult,
    names: Sequence[str] | None = None,
    factor: float = 10.0,
    n_points: int = 9,
) -> dict[str, ProfileCheck]:
    """Profile each free resistance and capacitance of a fit over ``[est / factor, est * factor]``.

    Parameters
    ----------
    network : RCNetwork or ZoneModel
        The fitted structure.
    data : Dataset or PreparedData
        The calibration data set, as the fit used it (:attr:`Calibration.data
        <rczone.calibration.Calibration.data>`, or :func:`rczone.calibration.prepare` of a frame).
    res : FitResult
    names : sequence of str, optional
        Parameters to profile; default every free resistance and capacitance.
    factor : float
        Half-width of the grid as a factor around the estimate.
    n_points : int
        Grid points (odd, so the estimate is one of them).

    Returns
    -------
    dict of str to ProfileCheck
    """
    if not factor > 1 or n_points < 3:
        raise ParameterError(f"profile needs factor > 1 and n_points >= 3, got {factor}, {n_points}")
    obj, w = _objective(load_model(network).network, data_set(data), res)
    network = obj.network
    if names is None:
        names = [
            n
            for n in res.names
            if n in network.parameters and network.parameters[n].kind in ("resistance", "capacitance")
        ]
    theta_hat = np.array([res.estimates[n] for n in obj.spec.names])
    n_eff = (obj.data.t[-1] - obj.data.t[0]) / correlation_time(res)
    out = {}
    for name in names:
        est = res.estimates[name]
        grid = est * factor ** np.linspace(-1.0, 1.0, n_points)
        lo, hi = res.parameters[name].lower, res.parameters[name].upper
        grid = grid[(grid > lo) & (grid < hi)]
        if grid.size < 2:
            continue
        pr = profile(obj, theta_hat, name, grid, optimizer="nelder-mead")
        kind = method_of(res.method)
        if not kind.stochastic:  # Gaussian errors, variance concentrated out, n_eff samples
            rise = 0.5 * max(n_eff, 1.0) * np.log(pr.cost / pr.cost.min())
        elif not kind.prior:
            rise = w * (pr.cost - pr.cost.min())
        else:  # MAP: the objective is already tempered
            rise = pr.cost - pr.cost.min()
        interval = _interval(grid, rise)
        # (a grid cut by a bound is flat if it stays low all the way to the bound)
        flat_low, flat_high = bool(rise[0] < PROFILE_THRESHOLD), bool(rise[-1] < PROFILE_THRESHOLD)
        out[name] = ProfileCheck(name, grid, rise, interval, flat_low, flat_high)
    return out


def _interval(x: np.ndarray, rise: np.ndarray) -> tuple[float, float]:
    k0 = int(np.argmin(rise))
    lo = hi = math.nan
    for k in range(k0, 0, -1):
        if rise[k - 1] >= PROFILE_THRESHOLD > rise[k]:
            lo = float(np.exp(np.interp(PROFILE_THRESHOLD, [rise[k], rise[k - 1]], np.log([x[k], x[k - 1]]))))
            break
    for k in range(k0, x.size - 1):
        if rise[k + 1] >= PROFILE_THRESHOLD > rise[k]:
            hi = float(np.exp(np.interp(PROFILE_THRESHOLD, [rise[k], rise[k + 1]], np.log([x[k], x[k + 1]]))))
            break
    return lo, hi


def compare_fits(
    fits: Mapping[str, FitResult], names: Sequence[str] | None = None, tolerance: float = 1.5
) -> list[Disagreement]:
    """Compare the estimates of the same parameters fitted to different data sets.

    Two estimates disagree when ``|log(a / b)|`` exceeds both twice its standard error (from
    the fits' standard errors, in log space) and ``log(tolerance)``.

    Parameters
    ----------
    fits : mapping of data-set name to FitResult
    names : sequence of str, optional
        Parameters to compare; default those free in every fit.
    tolerance : float
        Factor below which two estimates are never called different.
    """
    if not tolerance >= 1:
        raise ParameterError(f"tolerance must be >= 1, got {tolerance}")
    keys = list(fits)
    if names is None and keys:
        common = set.intersection(*(set(f.names) for f in fits.values()))
        names = [n for n in fits[keys[0]].names if n in common and not is_reserved(n)]
    out = []
    for i, a in enumerate(keys):
        for b in keys[i + 1 :]:
            fa, fb = fits[a], fits[b]
            for n in names:
                ea, eb = fa.estimates[n], fb.estimates[n]
                lr = math.log(ea / eb)
                sa, sb = fa.std_errors[n] / ea, fb.std_errors[n] / eb
                se = math.sqrt(sa * sa + sb * sb) if math.isfinite(sa) and math.isfinite(sb) else math.inf
                z = abs(lr) / se if se > 0 else math.inf
                out.append(Disagreement(n, a, b, ea, eb, z, bool(z > 2 and abs(lr) > math.log(tolerance))))
    return out


def far_from_construction(res: FitResult, factor: float = 3.0) -> dict[str, float]:
    """Free R and C whose estimate is more than ``factor`` away from its construction value (the ratios)."""
    out = {}
    for n, e in res.parameters.items():
        c = e.construction
        if math.isfinite(c) and c > 0:
            r = e.value / c
            if r > factor or r < 1 / factor:
                out[n] = r
    return out
