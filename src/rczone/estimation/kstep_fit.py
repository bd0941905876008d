"""A fit by the k-step criterion: the likelihood fit's global search, then the criterion, the noise scale and the sandwich.

The estimator of :mod:`rczone.estimation.kstep`, in three steps:

1. the maximum-likelihood fit of the same structure (:func:`rczone.estimation.fit.fit`, its global
   search and its flags), the start;
2. a local search (L-BFGS-B on the log of every positive parameter, the exact gradient of
   :func:`~rczone.estimation.kstep.kstep_cost`) of the criterion over the likelihood fit's free
   parameters, except the measurement noise, which stays at its likelihood value: the criterion
   sees the noise levels' ratios only (the module notes of :mod:`~rczone.estimation.kstep`);
3. every noise level multiplied by :func:`~rczone.estimation.kstep.noise_scale` (the gains and
   predictions do not move), and the estimates' covariance by the sandwich
   :func:`~rczone.estimation.kstep.sandwich_covariance` (the criterion is not a likelihood).

Its bounds are the likelihood fit's. The method ``kstep``
(:mod:`rczone.estimation.methods.kstep`, ``--method kstep --option horizons=1,12,72``) wraps it.

References
----------
.. [1] M. S. Shook, C. Mohtadi, S. L. Shah, "Identification for long-range predictive control",
   IEE Proceedings D 138 (1991) 75-84.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.kstep import check_horizons, kstep_cost, noise_scale, sandwich_covariance
from rczone.estimation.result import FitResult
from rczone.network import RCNetwork
from rczone.network.stochastic import INITIAL_STATE, MEASUREMENT_NOISE, is_noise_name, kind_of
from rczone.results import Result


@dataclass(frozen=True, eq=False, repr=False)
class KStepFit(Result):
    """The estimates of a k-step fit.

    Attributes
    ----------
    values : dict
        Every parameter value and noise level (the noise scaled for the band).
    std_error : dict
        Sandwich standard errors of the criterion's free parameters (NaN: none).
    horizons : tuple of int
        Steps ahead of the criterion.
    objective : float
        The criterion at the estimate, K^2.
    objective_ml : float
        The criterion at the likelihood fit's estimate, K^2.
    noise_scale : float
        The factor every noise level was multiplied by.
    converged : bool
        Whether the local search reported convergence.
    n_evals : int
    ml : FitResult
        The likelihood fit it started from.
    notes : tuple of str
    """

    values: dict
    std_error: dict
    horizons: tuple[int, ...]
    objective: float
    objective_ml: float
    noise_scale: float
    converged: bool
    n_evals: int
    ml: FitResult
    notes: tuple[str, ...] = field(default=())

    def _repr_line(self) -> str:
        return f"k-step fit at {', '.join(map(str, self.horizons))} steps, J {self.objective:.4g} K^2"

    def to_frame(self) -> pd.DataFrame:
        """One row per free parameter: the k-step and likelihood estimates and the sandwich standard error."""
        return pd.DataFrame(
            [
                {
                    "name": n,
                    "kstep": self.values[n],
                    "std_error": se,
                    "ml": self.ml.parameters[n].value,
                }
                for n, se in self.std_error.items()
            ]
        )

    def summary_lines(self) -> list:
        """The estimates next to the likelihood fit's, then the criterion's change."""
        from rczone.results.fit_text import esc

        lines = [
            f"k-step fit (horizons {', '.join(map(str, self.horizons))} steps): criterion {self.objective:.5g} K^2"
            f" (the likelihood fit's estimate: {self.objective_ml:.5g} K^2); noise levels x {self.noise_scale:.3g}"
            f"{'' if self.converged else '; NOT converged'}"
        ]
        for r in self.to_frame().itertuples():
            lines.append(f"  {esc(r.name)}: {r.kstep:.4g} ± {r.std_error:.2g} (ML {r.ml:.4g})")
        lines += [esc(n) for n in self.notes]
        return lines

    def to_dict(self) -> dict:
        """JSON-ready."""
        from rczone.results.protocol import json_number

        return {
            "method": "kstep",
            "horizons": list(self.horizons),
            "values": {k: json_number(v) for k, v in self.values.items()},
            "std_error": {k: json_number(v) for k, v in self.std_error.items()},
            "objective_K2": json_number(self.objective),
            "objective_ml_K2": json_number(self.objective_ml),
            "noise_scale": self.noise_scale,
            "converged": self.converged,
            "n_evals": self.n_evals,
            "notes": list(self.notes),
        }


def fit_kstep(
    network: RCNetwork,
    data: Dataset,
    *,
    horizons: Sequence[int],
    ml: FitResult | None = None,
    hold: str = "zoh",
    rng: np.random.Generator | None = None,
    max_evals: int = 200,
    progress: Any = None,
) -> KStepFit:
    """Fit ``network`` to ``data`` by the k-step criterion over ``horizons`` (see the module notes).

    Parameters
    ----------
    network : RCNetwork
    data : Dataset
    horizons : sequence of int
        Steps ahead, e.g. ``(1, 12, 72)``.
    ml : FitResult, optional
        The likelihood fit to start from (method ``"ml"``); default one by
        :func:`rczone.estimation.fit.fit`.
    hold : {"zoh", "foh"}
    rng : numpy.random.Generator, optional
        For the likelihood fit's global search.
    max_evals : int
        Most criterion evaluations of the local search.
    progress : object, optional
        Told the stage (``progress("...")``, when callable) and ``progress.advance(done, max_evals)``
        after each evaluation of the criterion (the likelihood fit reports its own search); None:
        nothing.

    Returns
    -------
    KStepFit
    """
    from scipy.optimize import minimize

    from rczone.estimation.fit import fit

    hs = check_horizons(horizons)
    if ml is None:
        ml = fit(network, data, method="ml", hold=hold, rng=rng)
    elif ml.method != "ml":
        raise ParameterError(f"a k-step fit starts from a maximum-likelihood fit, got method {ml.method!r}")
    base = {**ml.fixed, **{n: e.value for n, e in ml.parameters.items()}}
    names = [n for n in ml.parameters if kind_of(n) not in (MEASUREMENT_NOISE, INITIAL_STATE)]
    if any(ml.parameters[n].value <= 0 for n in names):
        raise ParameterError(
            "a k-step fit searches the log of positive parameters; a free one is not positive"
        )
    lo = np.log([max(ml.parameters[n].lower, 1e-300) for n in names])
    hi = np.log([ml.parameters[n].upper for n in names])
    j0 = kstep_cost(network, base, data, hs, hold=hold).value
    count = [0]

    if callable(progress):
        progress(f"k-step criterion at horizons {', '.join(map(str, hs))} from the ML fit")
    advance = getattr(progress, "advance", None)

    def f(eta: np.ndarray) -> tuple[float, np.ndarray]:
        count[0] += 1
        if advance is not None:
            advance(min(count[0], max_evals), max_evals)
        theta = np.exp(eta)
        try:
            c = kstep_cost(network, {**base, **dict(zip(names, theta))}, data, hs, wrt=names, hold=hold)
        except (ParameterError, np.linalg.LinAlgError, ValueError):
            return math.inf, np.zeros(eta.size)
        if not math.isfinite(c.value):
            return math.inf, np.zeros(eta.size)
        return c.value / j0, c.gradient * theta / j0

    eta0 = np.clip(np.log([ml.parameters[n].value for n in names]), lo, hi)
    res = minimize(
        f, eta0, jac=True, method="L-BFGS-B", bounds=list(zip(lo, hi)), options={"maxfun": max_evals}
    )
    values = {**base, **dict(zip(names, np.exp(res.x)))}
    at = kstep_cost(network, values, data, hs, wrt=names, hold=hold)
    scale = noise_scale(network, values, data, hold)
    values = {k: (v * scale if is_noise_name(k) else v) for k, v in values.items()}
    cov = sandwich_covariance(at, hs[-1])
    se = {
        n: (scale if is_noise_name(n) else 1.0) * math.sqrt(cov[i, i]) if cov[i, i] >= 0 else math.nan
        for i, n in enumerate(names)
    }
    notes = []
    near = [n for n, e, a, b in zip(names, res.x, lo, hi) if e - a < 1e-3 or b - e < 1e-3]
    if near:
        notes.append(f"at a bound of the likelihood fit's box: {', '.join(near)}")
    return KStepFit(
        values, se, hs, float(at.value), float(j0), scale, bool(res.success), count[0], ml, tuple(notes)
    )
