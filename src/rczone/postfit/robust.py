"""Misspecification-robust standard errors of an ML fit: the sandwich (Huber--White) covariance.

The Hessian's covariance ``H^{-1}`` of a maximum-likelihood fit is right when the model is: it
rests on the information identity ``E[s s'] = H`` between the outer product of the scores and the
curvature. A model that misses dynamics (innovations that are not white) breaks it, and the
Hessian's standard errors are then too small -- the solar aperture of two identical test houses
``0.554 +- 0.031`` and ``2.712 +- 0.14`` m2. The quasi-ML (sandwich) covariance does not need the
identity (White 1982):

``cov_eta = H^{-1} G H^{-1}``,  ``G = sum_k s_k s_k'``,

with ``s_k`` the gradient in ``eta`` of the log-density of sample ``k`` given the past (the
Kalman filter's prediction-error decomposition, Harvey 1989, sec. 3.4:
``l_k = -0.5 (log det 2 pi S_k + e_k' S_k^{-1} e_k)`` over the observed outputs). This is
statsmodels' ``cov_type='robust'`` for state-space models (``MLEResults.cov_params_robust_approx``:
the same Hessian inverse on both sides of the outer product of the per-observation scores). The
scores here are central differences of ``l_k`` in ``eta`` (step :data:`SCORE_STEP`), one pair of
filter runs per free parameter; ``H^{-1}`` is the fit's own covariance in ``eta``, rebuilt from its
standard errors and correlation. Like statsmodels', it does not correct for correlation *between*
the scores of different samples (no HAC weighting), so it is still optimistic when the scores are
strongly autocorrelated.

References
----------
.. [1] H. White, "Maximum likelihood estimation of misspecified models", Econometrica 50(1), 1982.
.. [2] A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman Filter*,
   Cambridge University Press, 1989, sections 3.4 (prediction-error decomposition) and 4.5
   (quasi-maximum likelihood).
.. [3] statsmodels, ``statsmodels.tsa.statespace.mlemodel.MLEResults`` (``cov_type='robust'``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rczone.estimation.data import Dataset
from rczone.network import RCNetwork

#: Step in ``eta`` of the central-difference scores (about eps^(1/3), scaled by max(1, |eta|)).
SCORE_STEP = 1e-5


def sample_loglik(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, hold: str = "zoh"
) -> np.ndarray:
    """The log-density of each sample given the past, ``l_k`` (module notes); their sum is ``log L``.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Every parameter, the noise levels included (an ML fit's values).
    data : Dataset
    hold : {"zoh", "foh"}

    Returns
    -------
    ndarray, shape (N,)
        0 where no output is observed.
    """
    from rczone.estimation.engines import run_filter

    out = run_filter(network, values, data, hold)
    e_all, S_all = out.innovations, out.S
    ok = np.isfinite(e_all)
    full = ok.all(axis=1)
    ll = np.zeros(data.n_samples)
    if full.any():  # every output observed: one batched solve
        e, S = e_all[full], S_all[full]
        _, logdet = np.linalg.slogdet(2 * math.pi * S)
        ll[full] = -0.5 * (logdet + np.einsum("ki,ki->k", e, np.linalg.solve(S, e[..., None])[..., 0]))
    for k in np.flatnonzero(ok.any(axis=1) & ~full):  # some outputs missing: their marginal density
        e, S = e_all[k, ok[k]], S_all[k][np.ix_(ok[k], ok[k])]
        _, logdet = np.linalg.slogdet(2 * math.pi * S)
        ll[k] = -0.5 * (logdet + e @ np.linalg.solve(S, e))
    return ll


def sandwich(cov: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """``cov G cov`` with ``G = scores' scores``: the sandwich covariance from the inverse Hessian.

    Parameters
    ----------
    cov : ndarray, shape (d, d)
        Inverse Hessian of the negative log-likelihood (the model-based covariance).
    scores : ndarray, shape (N, d)
        Per-sample scores (gradients of the per-sample log-likelihood).

    Returns
    -------
    ndarray, shape (d, d), symmetric
    """
    g = scores.T @ scores
    out = cov @ g @ cov
    return 0.5 * (out + out.T)


@dataclass(frozen=True)
class RobustErrors:
    """Sandwich standard errors beside the Hessian's.

    Attributes
    ----------
    std_errors : dict of str to float
        Robust standard errors, SI units (NaN where the Hessian's are).
    hessian_std_errors : dict of str to float
        The fit's (Hessian) standard errors, for comparison.
    """

    std_errors: dict[str, float]
    hessian_std_errors: dict[str, float]

    def ratio(self, name: str) -> float:
        """Robust over Hessian standard error of ``name`` (NaN without both)."""
        h = self.hessian_std_errors.get(name, math.nan)
        return self.std_errors.get(name, math.nan) / h if h and math.isfinite(h) else math.nan

    def to_dict(self) -> dict:
        """JSON-ready: per parameter the robust and the Hessian standard error."""
        num = lambda v: float(v) if math.isfinite(v) else None  # noqa: E731
        return {
            n: {"robust": num(v), "hessian": num(self.hessian_std_errors.get(n, math.nan))}
            for n, v in self.std_errors.items()
        }


def _eta_covariance(result, names: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fit's covariance in eta over ``names``, their eta and log flags."""
    est = [result.parameters[n] for n in names]
    log = np.array([e.log_scale and e.value > 0 for e in est])
    value = np.array([e.value for e in est])
    sd = np.array([e.std_error / e.value if lg else e.std_error for e, lg in zip(est, log, strict=True)])
    idx = [list(result.names).index(n) for n in names]
    corr = np.asarray(result.correlation, dtype=float)[np.ix_(idx, idx)]
    eta = np.where(log, np.log(np.where(log, value, 1.0)), value)
    return corr * np.outer(sd, sd), eta, log


def scores(
    network: RCNetwork, result, data: Dataset, names: list[str], step: float = SCORE_STEP
) -> np.ndarray:
    """Per-sample scores ``d l_k / d eta`` of ``names`` at the fit's values, by central differences.

    Parameters
    ----------
    network : RCNetwork
    result : FitResult
        An ML fit (its estimates, fixed values and hold).
    data : Dataset
        The data it was fitted to.
    names : list of str
        Free parameters to differentiate.
    step : float
        Step in ``eta``, times ``max(1, |eta|)``.

    Returns
    -------
    ndarray, shape (N, len(names))
    """
    base = {**result.fixed, **result.estimates}
    _, eta, log = _eta_covariance(result, names)
    out = np.empty((data.n_samples, len(names)))
    for i, n in enumerate(names):
        h = step * max(1.0, abs(eta[i]))
        ll = []
        for sign in (1.0, -1.0):
            e = eta[i] + sign * h
            ll.append(sample_loglik(network, {**base, n: math.exp(e) if log[i] else e}, data, result.hold))
        out[:, i] = (ll[0] - ll[1]) / (2 * h)
    return out


def robust_errors(network: RCNetwork, result, data: Dataset) -> RobustErrors | None:
    """The sandwich standard errors of an ML fit (module notes); None for another method or no Hessian.

    Parameters
    ----------
    network : RCNetwork
    result : FitResult
        The fit (``method == "ml"``) to ``data``.
    data : Dataset

    Returns
    -------
    RobustErrors or None
    """
    if result.method != "ml":
        return None
    hess = dict(result.std_errors)
    names = [n for n in result.names if math.isfinite(hess.get(n, math.nan)) and hess[n] > 0]
    if not names:
        return None
    cov, _, log = _eta_covariance(result, names)
    if not np.isfinite(cov).all():
        return None
    robust = sandwich(cov, scores(network, result, data, names))
    sd = np.sqrt(np.clip(np.diag(robust), 0.0, None))
    values = np.array([result.parameters[n].value for n in names])
    se = np.where(log, sd * values, sd)
    out = {n: math.nan for n in result.names}
    out.update(dict(zip(names, map(float, se), strict=True)))
    return RobustErrors(out, {n: float(v) for n, v in hess.items()})


def robust_lines(robust: RobustErrors | None, result) -> list[str]:
    """The console line of the robust standard errors beside the Hessian's (empty without them).

    Parameters
    ----------
    robust : RobustErrors or None
    result : FitResult
    """
    from rczone.results.fit_text import esc

    if robust is None:
        return []
    parts = []
    for n, e in result.parameters.items():
        se = robust.std_errors.get(n, math.nan)
        if math.isfinite(se) and math.isfinite(e.std_error):
            parts.append(f"{esc(n)} ±{se:.3g} ({e.std_error:.3g})")
    if not parts:
        return []
    return ["robust (sandwich) standard errors, the Hessian's in brackets: " + ", ".join(parts)]
