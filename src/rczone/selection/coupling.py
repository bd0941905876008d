"""Coupled zones: joint identification compared with one zone driven by its neighbours' measurements.

Two ways of modelling a zone ``1`` next to a zone ``2`` (Bacher & Madsen 2011 [2]_ fit the target
zone the second way):

* **joint**: both rooms are states of one network, both temperatures are outputs, a resistor
  joins them; the likelihood is that of ``(y1, y2)``;
* **neighbour as input**: zone ``1`` alone, with the *measured* ``y2`` a boundary (a prescribed
  temperature); the likelihood is that of ``y1`` given ``y2``.

Their raw log-likelihoods are of different data and cannot be compared. Both models, however,
give a one-step predictive density of the *common* outputs ``y1_k`` given the same information
``F_k = {y1_j, j < k; y2_j, j <= k; inputs}``:

* the neighbour-input model: its own one-step density ``N(e_k; 0, S_k)`` (its filter's innovation
  and innovation covariance), whose log summed over the samples is its log-likelihood;
* the joint model: its filter gives the joint one-step density of ``(y1_k, y2_k)`` given the past,
  ``N(e_k; 0, S_k)``; conditioning a Gaussian on part of its coordinates [3]_ gives

  .. math::

      \\log p(y_{1,k} \\mid \\text{past}, y_{2,k}) = \\log N(e_k; 0, S_k) - \\log N(e_{2,k}; 0, S_{22,k}),

  that is ``log N(e_1 - S_12 S_22^-1 e_2; 0, S_11 - S_12 S_22^-1 S_21)``.

Summed over the same samples, each is a *conditional* (partial) log-likelihood of ``y1`` given
the neighbours' measurements (the prediction-error decomposition, Madsen [4]_), and the two are
comparable: the same variables, the same conditioning information. Missing values are handled
per sample: a missing neighbour value is not conditioned on, a sample without any target value
contributes nothing (to both models alike). With several candidates the *targets* are the outputs
every candidate measures and the *conditioning* outputs are all the others; each of these must
be, in every candidate that does not output it, one of its boundaries (else that candidate does
not use the measurement and its density is not of the same thing given the same information:
the set is refused).

The models are not nested (a neighbour's *measured* temperature is not a special case of a
modelled state), so a likelihood-ratio test does not apply. Vuong's test [1]_ compares two
non-nested models by the per-sample differences ``d_k = l_a,k - l_b,k`` of their log-densities:
under the null hypothesis that both are equally close (in Kullback-Leibler divergence) to the
truth, ``Z = sum_k d_k / sqrt(n w^2) -> N(0, 1)``; a large positive ``Z`` says ``a`` is closer,
a large negative one ``b``. The per-sample terms of a time series may be autocorrelated when the
models are misspecified, so ``w^2`` is the Newey-West (Bartlett kernel) long-run variance of
``d`` [5]_ [6]_ (Rivers & Vuong's extension of the test to dynamic models; for independent terms
it is the sample variance Vuong uses). Vuong's Schwarz-corrected statistic, with
``sum_k d_k - (k_a - k_b) log(n) / 2`` in the numerator, is reported beside it. AIC and BIC are
computed on the conditional log-likelihoods with each model's number of free parameters and
``n`` the number of observed target values.

Each model is evaluated at its own maximum-likelihood estimate: for the joint model, the maximum
of the joint likelihood, not of the conditional one. Under correct specification both estimate
the same parameters; otherwise the comparison is of the models *as fitted*, which is the
question asked (which fitted model predicts the target better given the neighbours).

References
----------
.. [1] Q. H. Vuong, "Likelihood ratio tests for model selection and non-nested hypotheses",
   Econometrica 57 (1989) 307-333.
.. [2] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522 (likelihood-ratio tests between nested models).
.. [3] T. W. Anderson, *An Introduction to Multivariate Statistical Analysis*, 3rd ed., Wiley
   2003, theorem 2.5.1 (conditional distribution of a multivariate normal).
.. [4] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007, sections 10.6-10.7 (the likelihood
   of a state-space model from the one-step prediction errors of the Kalman filter).
.. [5] D. Rivers, Q. Vuong, "Model selection tests for nonlinear dynamic models", Econometrics
   Journal 5 (2002) 1-39.
.. [6] W. K. Newey, K. D. West, "A simple, positive semi-definite, heteroskedasticity and
   autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703-708.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import ndtr

from rczone.calibration import Calibration, prepare
from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.engines import run_filter
from rczone.models import ZoneModel
from rczone.network import RCNetwork

_LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class Basis:
    """What the candidates' likelihoods are compared on.

    Attributes
    ----------
    targets : tuple of str
        The outputs every candidate measures: their one-step densities are compared.
    given : tuple of str
        Measured temperatures the densities are conditional on: outputs of some candidates,
        boundaries (inputs) of the others. Empty: the candidates measure the same outputs and
        their full likelihoods are compared.
    """

    targets: tuple[str, ...]
    given: tuple[str, ...] = ()

    @property
    def conditional(self) -> bool:
        return bool(self.given)

    def describe(self) -> str:
        """``"joint"`` or ``"conditional on T2"``."""
        return f"conditional on {', '.join(self.given)}" if self.given else "joint"


def comparison_basis(networks: Mapping[str, RCNetwork]) -> Basis:
    """The basis on which the likelihoods of ``networks`` (candidate name to network) compare.

    Raises
    ------
    ParameterError
        When they are not comparable: no output in common, or an output of one candidate that
        another neither measures nor uses as a boundary.
    """
    outs = {name: tuple(net.outputs) for name, net in networks.items()}
    first = next(iter(outs.values()))
    if all(o == first for o in outs.values()):
        return Basis(first)
    common = tuple(o for o in first if all(o in v for v in outs.values()))
    listing = "; ".join(f"{n}: {', '.join(o)}" for n, o in outs.items())
    if not common:
        raise ParameterError(
            f"the candidate models measure no output in common ({listing}); their likelihoods are"
            " of different data and cannot be compared"
        )
    given: list[str] = []
    for o in outs.values():
        given += [x for x in o if x not in common and x not in given]
    for name, net in networks.items():
        for g in given:
            if g not in outs[name] and g not in net.boundaries:
                raise ParameterError(
                    f"candidate {name!r} neither measures {g!r} nor takes it as a boundary, while"
                    f" another candidate measures it ({listing}); compare models of the same outputs,"
                    f" or give {name!r} the measured {g!r} as a boundary"
                )
    return Basis(common, tuple(given))


def _logpdf_batch(e: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``log N(e_k; 0, S_k)`` for stacked ``e`` (K, d) and ``S`` (K, d, d); zeros for ``d = 0``."""
    if e.shape[1] == 0:
        return np.zeros(e.shape[0])
    L = np.linalg.cholesky(S)
    z = np.linalg.solve(L, e[..., None])[..., 0]
    logdet = 2.0 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)
    return -0.5 * (e.shape[1] * _LOG_2PI + logdet + (z * z).sum(axis=1))


def conditional_terms(
    e: np.ndarray, S: np.ndarray, targets: Sequence[int], given: Sequence[int]
) -> np.ndarray:
    """Per-sample ``log p(y_targets,k | past, y_given,k)`` from one-step innovations.

    ``log N(e_{T+G}; 0, S_{T+G}) - log N(e_G; 0, S_GG)`` on the observed coordinates of each
    sample (Gaussian conditioning, see the module notes).

    Parameters
    ----------
    e : ndarray, shape (N, ny)
        One-step innovations, K; NaN where the output is missing.
    S : ndarray, shape (N, ny, ny)
        Their covariances, K^2.
    targets, given : sequence of int
        Disjoint output indices: the coordinates whose density is wanted, those it is conditional on.

    Returns
    -------
    ndarray, shape (N,)
        0 where no target is observed.
    """
    e = np.asarray(e, dtype=float)
    S = np.asarray(S, dtype=float)
    if e.ndim != 2 or S.shape != (*e.shape, e.shape[1]):
        raise ParameterError(f"e must be (N, ny) and S (N, ny, ny), got {e.shape} and {S.shape}")
    targets, given = list(targets), list(given)
    if set(targets) & set(given) or not targets:
        raise ParameterError(f"targets {targets} must be non-empty and disjoint from given {given}")
    obs = np.isfinite(e)
    out = np.zeros(e.shape[0])
    patterns, which = np.unique(obs, axis=0, return_inverse=True)
    for p, pattern in enumerate(patterns):
        t = [j for j in targets if pattern[j]]
        if not t:
            continue
        g = [j for j in given if pattern[j]]
        rows = np.flatnonzero(which.reshape(-1) == p)
        both = t + g
        out[rows] = _logpdf_batch(e[np.ix_(rows, both)], S[np.ix_(rows, both, both)]) - _logpdf_batch(
            e[np.ix_(rows, g)], S[np.ix_(rows, g, g)]
        )
    return out


def conditional_loglik(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, basis: Basis, hold: str = "zoh"
) -> np.ndarray:
    """Per-sample conditional log-density of the basis' targets under a fitted stochastic model.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Parameter, noise and initial-state values (those of an ML fit: its fixed values and estimates).
    data : Dataset
        The model's data.
    basis : Basis
        Every target must be an output of ``network``; its other outputs must be in ``basis.given``.
    hold : {"zoh", "foh"}

    Returns
    -------
    ndarray, shape (N,)
        ``log p(y_targets,k | past, y_given,k)``, 0 where no target is measured. Without
        conditioning outputs, the terms sum to the model's log-likelihood.
    """
    outs = list(network.outputs)
    missing = [o for o in basis.targets if o not in outs]
    extra = [o for o in outs if o not in basis.targets and o not in basis.given]
    if missing or extra:
        raise ParameterError(
            f"model {network.name!r} measures {', '.join(outs)}; the basis needs {', '.join(basis.targets)}"
            + (f" given {', '.join(basis.given)}" if basis.given else "")
        )
    f = run_filter(network, values, data, hold)
    return conditional_terms(
        f.innovations,
        f.S,
        [outs.index(o) for o in basis.targets],
        [outs.index(o) for o in basis.given if o in outs],
    )


def newey_west_variance(d: np.ndarray, lags: int | None = None) -> float:
    """Long-run variance of a series (Bartlett kernel), ``lags`` default ``floor(4 (n/100)^(2/9))``."""
    d = np.asarray(d, dtype=float)
    n = d.size
    if lags is None:
        lags = int(4.0 * (n / 100.0) ** (2.0 / 9.0))
    x = d - d.mean()
    v = float(x @ x) / n
    for j in range(1, min(lags, n - 1) + 1):
        v += 2.0 * (1.0 - j / (lags + 1.0)) * float(x[j:] @ x[:-j]) / n
    return v


@dataclass(frozen=True)
class VuongTest:
    """Vuong's test of two non-nested models on the same per-sample log-densities.

    Attributes
    ----------
    a, b : str
    basis : str
        What the log-densities are of (:meth:`Basis.describe`).
    n : int
        Samples with a target value.
    loglik_ratio : float
        ``sum_k (l_a,k - l_b,k)``.
    statistic : float
        ``loglik_ratio / sqrt(n w^2)`` (``w^2``: Newey-West long-run variance of the differences).
    p_value : float
        Two-sided, ``2 P(N(0,1) > |statistic|)``.
    statistic_bic, p_value_bic : float
        The same with Vuong's Schwarz correction ``- (k_a - k_b) log(n) / 2`` of the ratio.
    lags : int
        Lags of the long-run variance.
    """

    a: str
    b: str
    basis: str
    n: int
    loglik_ratio: float
    statistic: float
    p_value: float
    statistic_bic: float
    p_value_bic: float
    lags: int

    def closer(self, alpha: float) -> str | None:
        """The model closer to the truth at level ``alpha`` (two-sided), None when they cannot be told apart."""
        if self.p_value >= alpha:
            return None
        return self.a if self.statistic > 0 else self.b

    def to_dict(self, alpha: float) -> dict:
        return {
            "kind": "vuong",
            "a": self.a,
            "b": self.b,
            "basis": self.basis,
            "n": self.n,
            "loglik_ratio": self.loglik_ratio,
            "statistic": self.statistic,
            "p_value": self.p_value,
            "statistic_bic": self.statistic_bic,
            "p_value_bic": self.p_value_bic,
            "lags": self.lags,
            "closer": self.closer(alpha),
        }


def vuong_test(
    a: str,
    b: str,
    terms_a: np.ndarray,
    terms_b: np.ndarray,
    k_a: int,
    k_b: int,
    basis: str = "joint",
    mask: np.ndarray | None = None,
) -> VuongTest:
    """Vuong's test from per-sample log-densities of two models on the same samples (see the module notes).

    Parameters
    ----------
    a, b : str
        Model names.
    terms_a, terms_b : ndarray, shape (N,)
        Per-sample log-densities (:func:`conditional_loglik`).
    k_a, k_b : int
        Free parameters of each model.
    basis : str
        What the densities are of (for the record).
    mask : ndarray of bool, shape (N,), optional
        Samples that carry a target value (default: all).
    """
    la, lb = np.asarray(terms_a, dtype=float), np.asarray(terms_b, dtype=float)
    if la.shape != lb.shape or la.ndim != 1:
        raise ParameterError(f"per-sample terms must have one equal length, got {la.shape} and {lb.shape}")
    d = la - lb if mask is None else (la - lb)[np.asarray(mask, dtype=bool)]
    n = d.size
    if n < 10:
        raise ParameterError(f"Vuong's test needs at least 10 samples, got {n}")
    lags = int(4.0 * (n / 100.0) ** (2.0 / 9.0))
    w2 = newey_west_variance(d, lags)
    lr = float(d.sum())
    sd = math.sqrt(n * w2) if w2 > 0 else math.inf
    z = lr / sd if sd > 0 else 0.0
    z_bic = (lr - 0.5 * (k_a - k_b) * math.log(n)) / sd
    return VuongTest(
        a,
        b,
        basis,
        n,
        lr,
        z,
        float(2.0 * ndtr(-abs(z))),
        z_bic,
        float(2.0 * ndtr(-abs(z_bic))),
        lags,
    )


def check_measured(models: Mapping[str, ZoneModel], frame: pd.DataFrame, constants, basis: Basis) -> None:
    """Refuse a candidate that takes a conditioning temperature as a boundary but not from its measured column.

    A boundary held constant (``--const``, a model default) or taken as a mean of other columns is
    not the neighbour's measurement the other candidates model, so the densities would not be
    conditional on the same information.
    """
    for name, zm in models.items():
        held = zm.constants_used(frame, constants)
        for g in basis.given:
            if g in zm.network.boundaries and (g in held or g not in frame):
                raise ParameterError(
                    f"candidate {name!r} takes {g!r} as a boundary but not from the data's {g!r} column"
                    f" (held constant or derived); the comparison is conditional on the measured {g!r}"
                )


def conditional_logliks(
    calibrations: Mapping[str, Calibration],
    frame: pd.DataFrame,
    basis: Basis,
    constants: Mapping[str, float] | None = None,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Per-sample conditional log-densities of the basis' targets under each fitted candidate.

    Parameters
    ----------
    calibrations : mapping of str to Calibration
        ML fits of the candidates, on ``frame``.
    frame : DataFrame
        The samples every candidate was fitted on (every input of every candidate known).
    basis : Basis
        From :func:`comparison_basis`.
    constants : mapping, optional
        Inputs held constant in the fits.

    Returns
    -------
    terms : dict of str to ndarray, shape (N,)
        :func:`conditional_loglik` of each candidate at its estimate.
    measured : ndarray of bool, shape (N,)
        Samples with at least one target value (the others contribute 0 to every candidate).
    """
    terms: dict[str, np.ndarray] = {}
    t_ref = None
    measured = None
    for name, cal in calibrations.items():
        data = prepare(cal.model, frame, constants).dataset
        if t_ref is None:
            t_ref = data.t
            cols = [list(data.output_names).index(o) for o in basis.targets]
            measured = np.isfinite(data.y[:, cols]).any(axis=1)
        elif data.t.shape != t_ref.shape or not np.array_equal(data.t, t_ref):
            raise ParameterError(
                f"candidate {name!r} is not on the same samples as the others; fit every candidate on"
                " the stretch where all their inputs are known"
            )
        res = cal.result
        values = {**res.fixed, **res.estimates}
        terms[name] = conditional_loglik(cal.model.network, values, data, basis, res.hold)
    return terms, measured
