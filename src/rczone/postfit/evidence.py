"""Held-out evidence for the verdict: band coverage per horizon, the baselines, the innovations.

A fit can be flagged by nothing of its own (no estimate at a bound, a positive definite Hessian)
and still predict data it has not seen badly. ``rczone fit --holdout`` scores the fitted model on
the held-out part (:func:`rczone.calibration.horizons.holdout_scores`); this module turns those
scores into three checks, each passed, failed or not judged, and the failed ones into reasons of
the one :class:`~rczone.results.verdict.Verdict` (exit code 3):

* **coverage** -- at every horizon and output, the share of held-out measurements inside the
  model's 2-sigma band is at least :data:`COVERAGE_MIN` (80 %). The nominal share is 95.4 %;
  held-out errors are correlated over hours, so the share of a few days scatters by several per
  cent even for a correct band (Ljung 1999, sec. 16.6), and 80 % allows for that. A band covering
  less misses more than four times as often as it says (20 % against 4.6 %): its uncertainty, and
  the standard errors behind it, cannot be used.
* **baselines** -- at no horizon does a *stable* baseline (persistence, or the ARX model fitted
  on the same calibration data; :mod:`rczone.estimation.baselines`) predict with an RMSE more than
  :data:`BASELINE_MARGIN` (10 %, the verdict margin of the identifiability analysis) below the
  model's. A physical model that a black-box or a "nothing changes" predictor beats on unseen data
  has not captured the dynamics it claims (Ljung 1999, sec. 16.6). An unstable ARX is not ranked.
* **innovations** -- the one-step prediction errors on the held-out part (the filter's
  innovations there; the calibration's when the model predicts open loop only) are tested for
  whiteness: the check fails when Ljung-Box rejects at :data:`WHITENESS_ALPHA` (1 %) *and* the
  largest autocorrelation over the tested lags exceeds :data:`ACF_MAX` (0.2). With thousands of
  samples Ljung-Box rejects correlations far too small to matter (0.006 at one lag on the
  Bacher--Madsen house); an autocorrelation of 0.2 leaves 4 % of the next error's variance
  predictable from the past, a structure the model should have carried. Non-white innovations
  also make the Hessian's standard errors too small: the verdict then reads the robust
  (sandwich) ones (:mod:`rczone.postfit.robust`).

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 16.6 (model validation: cross-validation, residual analysis, comparison with simple models).
.. [2] G. M. Ljung, G. E. P. Box, "On a measure of lack of fit in time series models",
   Biometrika 65(2), 1978.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from rczone.postfit.innovations import acf, ljung_box_lags, ljung_box_q

#: Names of the predictors in a score table (:class:`~rczone.calibration.horizons.HorizonScores`),
#: its JSON and the report.
MODEL, PERSISTENCE, ARX_NAME = "model", "persistence", "arx"


class HorizonScores(Protocol):
    """What the checks read of held-out scores (:class:`rczone.calibration.horizons.HorizonScores`).

    Attributes
    ----------
    table : DataFrame
        One row per horizon, predictor and output (``predictor``, ``horizon``, ``output``,
        ``rmse_K``, ``coverage_2sigma``, ``stable``).
    measured : ndarray, shape (N, ny)
    predicted : dict
        Predictor name to its predictions, shape (H, N, ny).
    horizons : tuple
        Steps ahead (None: open loop).
    outputs : tuple of str
    unstable : dict
        Baselines whose predictor is unstable, with the largest modulus of their poles.
    data_label : str
    """

    table: Any
    measured: np.ndarray
    predicted: dict
    horizons: tuple
    outputs: tuple[str, ...]
    unstable: dict
    data_label: str


#: Least share of held-out measurements inside the model's 2-sigma band, at every horizon.
COVERAGE_MIN = 0.80
#: A stable baseline whose RMSE is below the model's by more than this fraction beats the model.
BASELINE_MARGIN = 0.10
#: Ljung-Box level below which the innovations may fail the whiteness check ...
WHITENESS_ALPHA = 0.01
#: ... when their largest autocorrelation over the tested lags also exceeds this.
ACF_MAX = 0.2
#: Outcomes of a check.
PASSED, FAILED, NOT_JUDGED = "passed", "failed", "not judged"


@dataclass(frozen=True)
class EvidenceCheck:
    """One check of the held-out evidence.

    Attributes
    ----------
    name : {"coverage", "baselines", "innovations"}
    outcome : {"passed", "failed", "not judged"}
    detail : str
        What was found, one sentence (the failures name the horizon and output).
    """

    name: str
    outcome: str
    detail: str

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {"outcome": self.outcome, "detail": self.detail}


@dataclass(frozen=True)
class HeldOutEvidence:
    """The three checks of a held-out part, as the verdict reads them.

    Attributes
    ----------
    checks : tuple of EvidenceCheck
    data_label : str
        The held-out data's name.
    """

    checks: tuple[EvidenceCheck, ...]
    data_label: str = "held-out data"

    @property
    def failed(self) -> tuple[str, ...]:
        """Names of the failed checks."""
        return tuple(c.name for c in self.checks if c.outcome == FAILED)

    @property
    def reasons(self) -> tuple[str, ...]:
        """One reason per failed check, for the verdict."""
        return tuple(f"held out, {c.name} failed: {c.detail}" for c in self.checks if c.outcome == FAILED)

    @property
    def notes(self) -> tuple[str, ...]:
        """The checks passed or not judged, for the verdict's notes."""
        return tuple(
            f"held out, {c.name} {c.outcome}: {c.detail}" for c in self.checks if c.outcome != FAILED
        )

    @property
    def innovations_white(self) -> bool | None:
        """Whether the innovations passed (None: not judged)."""
        c = next((c for c in self.checks if c.name == "innovations"), None)
        return None if c is None or c.outcome == NOT_JUDGED else c.outcome == PASSED

    def to_dict(self) -> dict:
        """JSON-ready: each check's outcome and detail, and the thresholds."""
        return {
            **{c.name: c.to_dict() for c in self.checks},
            "failed": list(self.failed),
            "thresholds": {
                "coverage_min": COVERAGE_MIN,
                "baseline_margin": BASELINE_MARGIN,
                "whiteness_alpha": WHITENESS_ALPHA,
                "acf_max": ACF_MAX,
            },
        }


def coverage_check(scores: HorizonScores) -> EvidenceCheck:
    """Every horizon's 2-sigma band covers at least :data:`COVERAGE_MIN` of the held-out measurements.

    Parameters
    ----------
    scores : HorizonScores
    """
    rows = scores.table[scores.table.predictor == MODEL]
    judged = rows[np.isfinite(rows.coverage_2sigma.to_numpy(float))]
    if judged.empty:
        return EvidenceCheck(
            "coverage", NOT_JUDGED, "the model has no band (no noise levels or standard errors)"
        )
    many = len(scores.outputs) > 1
    low = judged[judged.coverage_2sigma < COVERAGE_MIN]
    where = lambda r: f"{r.horizon}{f' ({r.output})' if many else ''}"  # noqa: E731
    if low.empty:
        worst = judged.loc[judged.coverage_2sigma.idxmin()]
        return EvidenceCheck(
            "coverage",
            PASSED,
            f"every horizon's 2-sigma band covers at least {COVERAGE_MIN:.0%} (lowest {worst.coverage_2sigma:.0%}"
            f" at {where(worst)})",
        )
    parts = ", ".join(f"{r.coverage_2sigma:.0%} at {where(r)}" for r in low.itertuples())
    return EvidenceCheck(
        "coverage",
        FAILED,
        f"the 2-sigma band covers {parts} (at least {COVERAGE_MIN:.0%} expected, 95% nominal)",
    )


def baseline_check(scores: HorizonScores) -> EvidenceCheck:
    """No stable baseline beats the model by more than :data:`BASELINE_MARGIN` at any horizon.

    Parameters
    ----------
    scores : HorizonScores
    """
    t = scores.table
    model = t[t.predictor == MODEL].set_index(["horizon", "output"]).rmse_K
    others = t[(t.predictor != MODEL) & t.stable]
    if others.empty or not np.isfinite(others.rmse_K.to_numpy(float)).any():
        skipped = ", ".join(scores.unstable) or "none"
        return EvidenceCheck(
            "baselines", NOT_JUDGED, f"no stable baseline to compare with (unstable: {skipped})"
        )
    many = len(scores.outputs) > 1
    beaten = []
    for r in others.itertuples():
        m = model.get((r.horizon, r.output), math.nan)
        if math.isfinite(r.rmse_K) and math.isfinite(m) and r.rmse_K < (1 - BASELINE_MARGIN) * m:
            beaten.append(
                f"{r.predictor} at {r.horizon}{f' ({r.output})' if many else ''}: RMSE {r.rmse_K:.3f} against"
                f" the model's {m:.3f} K"
            )
    unstable = f"; not ranked (unstable): {', '.join(scores.unstable)}" if scores.unstable else ""
    if beaten:
        return EvidenceCheck("baselines", FAILED, "beaten by " + "; ".join(beaten) + unstable)
    names = ", ".join(dict.fromkeys(others.predictor))
    return EvidenceCheck(
        "baselines",
        PASSED,
        f"no baseline ({names}) beats the model by more than {BASELINE_MARGIN:.0%} at any horizon{unstable}",
    )


def _whiteness(e: np.ndarray) -> tuple[float, float, int]:
    """``(Ljung-Box p, largest |autocorrelation|, lags)`` of one series (NaN skipped as gaps)."""
    from scipy.stats import chi2

    n = int(np.isfinite(e).sum())
    lags = ljung_box_lags(n)
    r = acf(e, lags)
    q = ljung_box_q(r[1:], n)
    return float(chi2.sf(q, lags)), float(np.max(np.abs(r[1:]))), lags


def innovation_check(scores: HorizonScores, calibration_innovations=None) -> EvidenceCheck:
    """The held-out one-step errors (else the calibration's innovations) are white enough.

    Parameters
    ----------
    scores : HorizonScores
        Scores with a one-step horizon (a model fitted by ML or MAP).
    calibration_innovations : ResidualAnalysis, optional
        The fit's innovations, used when the held-out part has no one-step horizon.
    """
    if 1 in scores.horizons:
        h = scores.horizons.index(1)
        err = scores.measured - scores.predicted[MODEL][h]
        where = "held-out one-step errors"
        series = [(o, err[:, j]) for j, o in enumerate(scores.outputs)]
    elif calibration_innovations is not None and calibration_innovations.kind == "innovations":
        where = "calibration innovations (the model predicts open loop only on the held-out part)"
        series = [(o.output, o.residuals) for o in calibration_innovations.outputs]
    else:
        return EvidenceCheck(
            "innovations",
            NOT_JUDGED,
            "no innovations (a model fitted by LS predicts open loop only; fit by ML)",
        )
    found = []
    for o, e in series:
        if np.isfinite(e).sum() < 20:
            continue
        p, worst, lags = _whiteness(e)
        found.append((o, p, worst, lags))
    if not found:
        return EvidenceCheck("innovations", NOT_JUDGED, f"too few {where} to test")
    bad = [f for f in found if f[1] < WHITENESS_ALPHA and f[2] > ACF_MAX]
    words = "; ".join(
        f"{o}: Ljung-Box p {p:.2g} over {lags} lags, largest autocorrelation {w:.2f}"
        for o, p, w, lags in found
    )
    if bad:
        return EvidenceCheck(
            "innovations",
            FAILED,
            f"the {where} are not white ({words}; a failure needs p < {WHITENESS_ALPHA:g} and an autocorrelation"
            f" above {ACF_MAX:g}): the model misses dynamics, and the Hessian's standard errors are too small",
        )
    return EvidenceCheck("innovations", PASSED, f"{where}: {words}")


def held_out_evidence(scores: HorizonScores, calibration_innovations=None) -> HeldOutEvidence:
    """The three checks of a held-out part (module notes).

    Parameters
    ----------
    scores : HorizonScores
        The held-out scores (:func:`rczone.calibration.horizons.holdout_scores`).
    calibration_innovations : ResidualAnalysis, optional
        The fit's innovations (:attr:`rczone.calibration.Calibration.innovations`).

    Returns
    -------
    HeldOutEvidence
    """
    checks = (
        coverage_check(scores),
        baseline_check(scores),
        innovation_check(scores, calibration_innovations),
    )
    return HeldOutEvidence(checks, scores.data_label)
