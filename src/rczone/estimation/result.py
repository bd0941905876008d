"""The frozen result of a fit: one :class:`~rczone.results.Estimate` per parameter, the likelihood, the search."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rczone.estimation.methods import method_of
from rczone.estimation.optimize import StartOutcome
from rczone.estimation.posterior import POSTERIOR_ISSUES
from rczone.estimation.search import SearchSummary
from rczone.results import Estimate, Result, json_number

if TYPE_CHECKING:
    from rczone.estimation.posterior import Posterior

#: Codes of :attr:`FitResult.issues`: what makes a result untrustworthy (CLI exit code 3).
ISSUES = {
    "at_bound": "an estimate is at a bound of its search box",
    "std_error": "a standard error could not be computed",
    "hessian": "the Hessian is not positive definite (the parameters are not identifiable)",
    "not_converged": "the search has not settled on one optimum",
    "starts_disagree": "starts that reach the same cost disagree on an estimate",
    **POSTERIOR_ISSUES,
}


@dataclass(frozen=True, eq=False, repr=False)
class FitResult(Result):
    """What a fit found; never a modified network.

    Attributes
    ----------
    parameters : dict of str to Estimate
        One record per free parameter, in order: value, standard error, bounds, construction
        value, at-bound flag, unit (:class:`~rczone.results.Estimate`).
    correlation : ndarray, shape (d, d)
        Correlation of the estimates (in eta); NaN where unavailable.
    objective_value : float
        The minimized objective at the estimate; what it means depends on the method
        (:attr:`objective`: K^2 s of squared output error for ``"ls"``, ``-log L`` for ``"ml"``,
        ``-log posterior`` of the tempered likelihood for ``"map"``).
    method : str
        The estimation method (a key of :data:`rczone.estimation.methods.REGISTRY`).
    engine : str
        The engine that computed the objective (:mod:`rczone.estimation.engines`).
    optimizer : str
        The local method.
    hold : str
        Inter-sample behaviour of the inputs.
    converged : bool
        Whether the winning start converged.
    n_evals : int
        Cost evaluations over all starts (Hessian excluded).
    starts : tuple of StartOutcome
        Every start's outcome.
    best_start : int
        Index of the winning start.
    rmse_K : float
        RMSE of the fit, K: open-loop for ``"ls"``, one-step-ahead for ``"ml"``/``"map"``.
    rmse_kind : str
        ``"open-loop"`` or ``"one-step"``.
    llf : float
        Log-likelihood at the estimate (untempered, without the prior for ``"map"``); NaN for a
        method without a noise model (``"ls"``).
    nobs : int
        Measured output samples (missing ones not counted).
    fixed : dict of str to float
        Values of the non-free parameters used.
    flags : tuple of str
        Human-readable warnings (at bound, not converged, Hessian not positive definite, starts
        that disagree, missing standard errors): each makes the result untrustworthy.
    search : SearchSummary, optional
        How the optimum was found: distinct optima, how many starts reached each, the spread.
    notes : tuple of str
        Findings that do not make the result untrustworthy (a noise level at its floor).
    issues : tuple of str
        Codes of the flags (keys of :data:`ISSUES`); empty when the result can be trusted.
    posterior : Posterior, optional
        A sampling method's draws and diagnostics (:mod:`rczone.estimation.posterior`); the
        estimates are then posterior means and the standard errors posterior standard
        deviations, and :meth:`conf_int` gives equal-tailed credible intervals.
    options : dict
        The method's own options the fit ran with (:attr:`rczone.estimation.methods.Method.options`).
    """

    parameters: Mapping[str, Estimate]
    correlation: np.ndarray
    objective_value: float
    method: str
    engine: str
    optimizer: str
    hold: str
    converged: bool
    n_evals: int
    starts: tuple[StartOutcome, ...]
    best_start: int
    rmse_K: float
    rmse_kind: str
    llf: float = math.nan
    nobs: int = 0
    fixed: Mapping[str, float] = field(default_factory=dict)
    flags: tuple[str, ...] = ()
    search: SearchSummary | None = None
    notes: tuple[str, ...] = ()
    issues: tuple[str, ...] = ()
    posterior: Posterior | None = None
    options: Mapping[str, Any] = field(default_factory=dict)

    @property
    def names(self) -> tuple[str, ...]:
        """Free parameters, in order."""
        return tuple(self.parameters)

    @property
    def estimates(self) -> dict[str, float]:
        """Estimated values by name, SI units."""
        return {n: e.value for n, e in self.parameters.items()}

    @property
    def std_errors(self) -> dict[str, float]:
        """Standard errors by name, SI units (NaN where unavailable)."""
        return {n: e.std_error for n, e in self.parameters.items()}

    @property
    def objective(self) -> str:
        """What :attr:`objective_value` means, with its unit."""
        return method_of(self.method).objective

    @property
    def n_params(self) -> int:
        """Estimated parameters (noise levels and initial states included)."""
        return len(self.parameters)

    @property
    def aic(self) -> float:
        """Akaike's information criterion, ``2 k - 2 llf`` (NaN without a likelihood)."""
        return 2.0 * self.n_params - 2.0 * self.llf

    @property
    def bic(self) -> float:
        """Schwarz's Bayesian information criterion, ``k log(nobs) - 2 llf`` (NaN without a likelihood)."""
        return self.n_params * math.log(max(self.nobs, 1)) - 2.0 * self.llf

    @property
    def trustworthy(self) -> bool:
        """No flag: estimates inside their bounds, standard errors, a settled search."""
        return not self.issues

    def conf_int(self, alpha: float = 0.05):
        """Wald intervals of level ``1 - alpha`` (see :meth:`rczone.results.Estimate.interval`).

        Parameters
        ----------
        alpha : float
            One minus the coverage.

        Returns
        -------
        DataFrame
            Columns ``lower`` and ``upper`` (SI units), one row per free parameter.
        """
        import pandas as pd

        rows = self._intervals(alpha)
        return pd.DataFrame.from_dict(rows, orient="index", columns=["lower", "upper"]).rename_axis(
            "parameter"
        )

    def _intervals(self, alpha: float) -> dict[str, tuple[float, float]]:
        """Wald intervals, or the posterior's credible intervals for a sampled fit."""
        if self.posterior is None:
            return {n: e.interval(alpha) for n, e in self.parameters.items()}
        q = self.posterior.interval(1.0 - alpha)
        return {n: (float(q[i, 0]), float(q[i, 1])) for i, n in enumerate(self.names)}

    def to_frame(self):
        """One row per free parameter: estimate, standard error, 95 % interval, unit, bounds, construction."""
        import pandas as pd

        rows = []
        intervals = self._intervals(0.05)
        for n, e in self.parameters.items():
            lo, hi = intervals[n]
            rows.append(
                {
                    "parameter": n,
                    "estimate": e.value,
                    "std_error": e.std_error,
                    "ci_lower": lo,
                    "ci_upper": hi,
                    "unit": e.unit,
                    "lower": e.lower,
                    "upper": e.upper,
                    "construction": e.construction,
                    "ratio_to_construction": e.ratio_to_construction,
                    "at_bound": e.at_bound,
                }
            )
        return pd.DataFrame(rows).set_index("parameter")

    def ratio_to_construction(self, name: str) -> float:
        """``estimate / construction`` of a free parameter (NaN without a construction value)."""
        return self.parameters[name].ratio_to_construction

    def starts_table(self) -> list[dict[str, Any]]:
        """One row per start: start and end values, objective, convergence, evaluations."""
        rows = []
        for k, s in enumerate(self.starts):
            row: dict[str, Any] = {"start_index": k, "winner": k == self.best_start}
            row.update({f"start_{n}": float(v) for n, v in zip(self.names, s.start)})
            row.update({f"end_{n}": float(v) for n, v in zip(self.names, s.end)})
            row.update(
                objective_value=json_number(s.cost),
                converged=s.converged,
                n_evals=s.n_evals,
                message=s.message,
            )
            rows.append(row)
        return rows

    def _repr_line(self) -> str:
        verdict = "trustworthy" if self.trustworthy else "flagged"
        return f"{self.method.upper()} fit of {self.n_params} parameters, {verdict}"

    def summary_lines(self) -> list:
        """The parameter table and the search line."""
        from rczone.results.fit_text import parameter_table, search_line

        return [parameter_table(self, f"{self.method.upper()} fit"), search_line(self)]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (NaN becomes ``None``); a sampled fit's ``interval_95`` is the credible interval."""
        intervals = self._intervals(0.05)
        return {
            "parameters": {
                n: {**e.to_dict(), "interval_95": [json_number(v) for v in intervals[n]]}
                for n, e in self.parameters.items()
            },
            "correlation": {
                a: {b: json_number(self.correlation[i, j]) for j, b in enumerate(self.names)}
                for i, a in enumerate(self.names)
            },
            "objective_value": json_number(self.objective_value),
            "objective": self.objective,
            "llf": json_number(self.llf),
            "aic": json_number(self.aic),
            "bic": json_number(self.bic),
            "nobs": self.nobs,
            "method": self.method,
            **({"method_options": dict(self.options)} if self.options else {}),
            "engine": self.engine,
            "optimizer": self.optimizer,
            "hold": self.hold,
            "converged": self.converged,
            "n_evals": self.n_evals,
            "n_starts": len(self.starts),
            "best_start": self.best_start,
            "rmse_K": json_number(self.rmse_K),
            "rmse_kind": self.rmse_kind,
            "fixed": {k: json_number(v) for k, v in self.fixed.items()},
            "flags": list(self.flags),
            "issues": list(self.issues),
            "trustworthy": self.trustworthy,
            "notes": list(self.notes),
            "search": self.search.to_dict(self.names) if self.search is not None else None,
            "starts": self.starts_table(),
            "posterior": self.posterior.to_dict() if self.posterior is not None else None,
        }
