"""The frozen result of a fit and its JSON-ready form."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rczone.estimation.optimize import StartOutcome
from rczone.estimation.search import SearchSummary

#: Codes of :attr:`FitResult.issues`: what makes a result untrustworthy (CLI exit code 3).
ISSUES = {
    "at_bound": "an estimate is at a bound of its search box",
    "std_error": "a standard error could not be computed",
    "hessian": "the Hessian is not positive definite (the parameters are not identifiable)",
    "not_converged": "the search has not settled on one optimum",
    "starts_disagree": "starts that reach the same cost disagree on an estimate",
}


def _num(v: float) -> float | None:
    """JSON has no NaN: missing numbers become ``None``."""
    v = float(v)
    return v if math.isfinite(v) else None


@dataclass(frozen=True, eq=False)
class FitResult:
    """What a fit found; never a modified network.

    Attributes
    ----------
    names : tuple of str
        Free parameters, in order.
    estimates : dict of str to float
        Estimated values (SI units).
    std_errors : dict of str to float
        Standard errors (delta method); NaN where unavailable.
    correlation : ndarray, shape (d, d)
        Correlation of the estimates (in eta); NaN where unavailable.
    cost : float
        Cost at the estimate (K^2 s for ``"ls"``, ``-log L`` for ``"ml"``, ``-log posterior`` for ``"map"``).
    method, optimizer, hold : str
    converged : bool
        Whether the winning start converged.
    n_evals : int
        Cost evaluations over all starts (Hessian excluded).
    starts : tuple of StartOutcome
        Every start's outcome.
    best_start : int
        Index of the winning start.
    lower, upper, construction : dict of str to float
        Bounds and construction values (NaN: none declared).
    at_bound : dict of str to bool
        Estimates within a small distance (0.1 % of the log-width) of a bound.
    rmse_K : float
        RMSE of the fit, K: open-loop for ``"ls"``, one-step-ahead for ``"ml"``/``"map"``.
    rmse_kind : str
        ``"open-loop"`` or ``"one-step"``.
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
    units : dict of str to str
        SI unit of each free parameter.
    """

    names: tuple[str, ...]
    estimates: Mapping[str, float]
    std_errors: Mapping[str, float]
    correlation: np.ndarray
    cost: float
    method: str
    optimizer: str
    hold: str
    converged: bool
    n_evals: int
    starts: tuple[StartOutcome, ...]
    best_start: int
    lower: Mapping[str, float]
    upper: Mapping[str, float]
    construction: Mapping[str, float]
    at_bound: Mapping[str, bool]
    rmse_K: float
    rmse_kind: str
    fixed: Mapping[str, float] = field(default_factory=dict)
    flags: tuple[str, ...] = ()
    search: SearchSummary | None = None
    notes: tuple[str, ...] = ()
    issues: tuple[str, ...] = ()
    units: Mapping[str, str] = field(default_factory=dict)

    @property
    def trustworthy(self) -> bool:
        """No flag: estimates inside their bounds, standard errors, a settled search."""
        return not self.issues

    def to_frame(self):
        """One row per free parameter: estimate, standard error, unit, bounds, construction, at bound."""
        import pandas as pd

        rows = [
            {
                "parameter": n,
                "estimate": self.estimates[n],
                "std_error": self.std_errors[n],
                "unit": self.units.get(n, ""),
                "lower": self.lower[n],
                "upper": self.upper[n],
                "construction": self.construction[n],
                "ratio_to_construction": self.ratio_to_construction(n),
                "at_bound": self.at_bound[n],
            }
            for n in self.names
        ]
        return pd.DataFrame(rows).set_index("parameter")

    def ratio_to_construction(self, name: str) -> float:
        """``estimate / construction`` (NaN without a construction value)."""
        c = self.construction[name]
        return self.estimates[name] / c if math.isfinite(c) and c != 0 else math.nan

    def starts_table(self) -> list[dict[str, Any]]:
        """One row per start: start and end values, cost, convergence, evaluations."""
        rows = []
        for k, s in enumerate(self.starts):
            row: dict[str, Any] = {"start_index": k, "winner": k == self.best_start}
            row.update({f"start_{n}": float(v) for n, v in zip(self.names, s.start)})
            row.update({f"end_{n}": float(v) for n, v in zip(self.names, s.end)})
            row.update(cost=_num(s.cost), converged=s.converged, n_evals=s.n_evals, message=s.message)
            rows.append(row)
        return rows

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (NaN becomes ``None``)."""
        params = {
            n: {
                "estimate": _num(self.estimates[n]),
                "std_error": _num(self.std_errors[n]),
                "construction": _num(self.construction[n]),
                "lower": _num(self.lower[n]),
                "upper": _num(self.upper[n]),
                "ratio_to_construction": _num(self.ratio_to_construction(n)),
                "at_bound": bool(self.at_bound[n]),
                "unit": self.units.get(n, ""),
            }
            for n in self.names
        }
        return {
            "parameters": params,
            "correlation": {
                a: {b: _num(self.correlation[i, j]) for j, b in enumerate(self.names)}
                for i, a in enumerate(self.names)
            },
            "cost": _num(self.cost),
            "method": self.method,
            "optimizer": self.optimizer,
            "hold": self.hold,
            "converged": self.converged,
            "n_evals": self.n_evals,
            "n_starts": len(self.starts),
            "best_start": self.best_start,
            "rmse_K": _num(self.rmse_K),
            "rmse_kind": self.rmse_kind,
            "fixed": {k: _num(v) for k, v in self.fixed.items()},
            "flags": list(self.flags),
            "issues": list(self.issues),
            "trustworthy": self.trustworthy,
            "notes": list(self.notes),
            "search": self.search.to_dict(self.names) if self.search is not None else None,
            "starts": self.starts_table(),
        }
