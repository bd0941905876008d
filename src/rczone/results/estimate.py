"""One record per estimated parameter: value, standard error, interval, bounds, construction value, unit.

It replaces parallel name-keyed dicts (one of values, one of standard errors, one of bounds, ...)
that had to be kept in step by hand; lmfit's ``Parameter`` (value, stderr, min, max) and
statsmodels' ``params``/``bse``/``conf_int()`` are the models.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from scipy.special import ndtri  # the normal quantile; scipy.stats takes 1 s to import

from rczone.results.protocol import json_number


class Estimate(NamedTuple):
    """An estimated parameter.

    Attributes
    ----------
    name : str
        Parameter name.
    value : float
        Estimate, SI units.
    std_error : float
        Standard error (delta method from the Hessian), SI units; NaN where unavailable.
    lower, upper : float
        Bounds of the search box, SI units.
    construction : float
        Construction (declared) value, SI units; NaN where none is declared.
    at_bound : bool
        Within 0.1 % of the log-width of a bound of the search box.
    unit : str
        SI unit of ``value``.
    kind : str
        ``"resistance"``, ``"capacitance"``, ``"noise"``, ``"state"``, ``"gain"`` or ``"other"``.
    log_scale : bool
        Whether the search ran on ``log(value)``; the interval is then formed there (and is
        positive and asymmetric).
    """

    name: str
    value: float
    std_error: float
    lower: float
    upper: float
    construction: float
    at_bound: bool
    unit: str = ""
    kind: str = "other"
    log_scale: bool = False

    @property
    def bound_side(self) -> str | None:
        """``"lower"`` or ``"upper"``: the bound an estimate :attr:`at_bound` sits at; None otherwise.

        The nearer bound on the optimizer's scale (log for a log-scale parameter).
        """
        if not self.at_bound:
            return None
        if self.log_scale and self.lower > 0:
            mid = math.sqrt(self.lower * self.upper)
        else:
            mid = 0.5 * (self.lower + self.upper)
        return "upper" if self.value > mid else "lower"

    def interval(self, alpha: float = 0.05) -> tuple[float, float]:
        """Wald interval of level ``1 - alpha`` (NaN without a standard error).

        Formed on the optimizer's scale: ``exp(log v -+ z se / v)`` for a parameter searched in
        log space (the delta method gives ``se(log v) = se / v``), ``v -+ z se`` otherwise, with
        ``z`` the ``1 - alpha / 2`` normal quantile (Pawitan, *In All Likelihood*, 2001, sec. 2.9
        and 4.7).

        Parameters
        ----------
        alpha : float
            One minus the coverage, in (0, 1).

        Returns
        -------
        (float, float)
            Lower and upper end, SI units.
        """
        if not 0 < alpha < 1:
            raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
        z = float(ndtri(1 - alpha / 2))
        v, se = self.value, self.std_error
        if not (math.isfinite(se) and math.isfinite(v)):
            return math.nan, math.nan
        if self.log_scale and v > 0:
            spread = z * se / v  # a standard error far above the value: the upper end is unbounded
            return v * math.exp(-min(spread, 745.0)), (v * math.exp(spread) if spread < 709.0 else math.inf)
        return v - z * se, v + z * se

    @property
    def ratio_to_construction(self) -> float:
        """``value / construction`` (NaN without a construction value)."""
        c = self.construction
        return self.value / c if math.isfinite(c) and c != 0 else math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields (NaN becomes ``None``), with the 95 % interval."""
        lo, hi = self.interval()
        return {
            "estimate": json_number(self.value),
            "std_error": json_number(self.std_error),
            "interval_95": [json_number(lo), json_number(hi)],
            "construction": json_number(self.construction),
            "lower": json_number(self.lower),
            "upper": json_number(self.upper),
            "ratio_to_construction": json_number(self.ratio_to_construction),
            "at_bound": bool(self.at_bound),
            "unit": self.unit,
        }
