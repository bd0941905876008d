"""The accessors a statsmodels user reaches for, on rczone's fit and prediction results.

statsmodels' ``MLEResults`` puts the estimates and their uncertainty at the top of the result:
``params`` and ``bse`` as Series labelled by parameter, ``cov_params()`` as a labelled DataFrame,
``conf_int(alpha)``, ``tvalues``, ``pvalues``, ``llf``, ``aic``, ``bic``, ``nobs``, and for a
prediction ``summary_frame(alpha)`` with the columns ``mean``, ``mean_se``, ``mean_ci_lower`` and
``mean_ci_upper``. These mixins give rczone's results the same names, computed from what the
result already holds (its :class:`~rczone.estimation.result.FitResult`, its standard deviations),
so a user's habits carry over; docs/python.md sets the calls side by side.

One difference is deliberate: rczone searches R and C on a log scale, so its ``conf_int`` is the
Wald interval on that scale (``exp(log v -+ z se / v)``, Pawitan 2001, sec. 4.7), which never
reaches zero; the other parameters' intervals are statsmodels' ``v -+ z se``.

References
----------
Seabold, S. & Perktold, J. (2010). statsmodels: Econometric and statistical modeling with Python.
*Proc. 9th Python in Science Conference*, 92-96.
Pawitan, Y. (2001). *In All Likelihood*. Oxford University Press, sec. 2.9 and 4.7.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from rczone.errors import ParameterError

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd


def normal_quantile(alpha: float) -> float:
    """The ``1 - alpha / 2`` quantile of the standard normal distribution (``alpha`` in (0, 1))."""
    from scipy.special import ndtri

    if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not 0 < alpha < 1:
        raise ParameterError(f"alpha must be a number in (0, 1), got {alpha!r}")
    return float(ndtri(1.0 - alpha / 2.0))


class FitAccessors:
    """statsmodels' names on a fit; the host has ``result`` (a ``FitResult``)."""

    result: Any

    @property
    def params(self) -> pd.Series:
        """The estimates, SI units, labelled by parameter (statsmodels ``params``)."""
        import pandas as pd

        return pd.Series(self.result.estimates, name="params", dtype=float).rename_axis("parameter")

    @property
    def bse(self) -> pd.Series:
        """Standard errors, SI units (statsmodels ``bse``; NaN where unavailable)."""
        import pandas as pd

        return pd.Series(self.result.std_errors, name="bse", dtype=float).rename_axis("parameter")

    @property
    def tvalues(self) -> pd.Series:
        """``params / bse`` (statsmodels ``tvalues``): how many standard errors from zero."""
        return (self.params / self.bse).rename("tvalues")

    @property
    def pvalues(self) -> pd.Series:
        """Two-sided normal p-values of ``tvalues`` (statsmodels ``pvalues`` without ``use_t``)."""
        import pandas as pd
        from scipy.special import ndtr

        t = self.tvalues
        return pd.Series(2.0 * ndtr(-np.abs(t.to_numpy(float))), index=t.index, name="pvalues")

    @property
    def correlation(self) -> pd.DataFrame:
        """The estimates' correlation matrix, rows and columns labelled by parameter."""
        import pandas as pd

        names = list(self.result.names)
        return pd.DataFrame(np.asarray(self.result.correlation, float), index=names, columns=names)

    def cov_params(self) -> pd.DataFrame:
        """Covariance of the estimates, SI units, labelled (statsmodels ``cov_params()``).

        ``cov_ij = corr_ij se_i se_j``, the first-order covariance in physical units of the one
        the optimizer estimated (the correlation is the same on both scales to first order).
        """
        se = self.bse.to_numpy(float)
        return self.correlation * np.outer(se, se)

    def conf_int(self, alpha: float = 0.05) -> pd.DataFrame:
        """Intervals of level ``1 - alpha``: columns ``lower`` and ``upper``, one row per parameter.

        Wald intervals on the scale the parameter was searched on (log for R and C, see the module
        docstring); a fit by sampling gives its equal-tailed credible intervals.
        """
        normal_quantile(alpha)  # the check of alpha, one line
        return self.result.conf_int(alpha)

    @property
    def llf(self) -> float:
        """Log-likelihood at the estimates (NaN for least squares, which has no noise model)."""
        return float(self.result.llf)

    @property
    def aic(self) -> float:
        """Akaike's information criterion, ``2 k - 2 llf``."""
        return float(self.result.aic)

    @property
    def bic(self) -> float:
        """Schwarz's criterion, ``k log(nobs) - 2 llf``."""
        return float(self.result.bic)

    @property
    def nobs(self) -> int:
        """Measured output samples the likelihood sums over."""
        return int(self.result.nobs)

    @property
    def df_model(self) -> int:
        """Estimated parameters (noise levels and initial states included)."""
        return int(self.result.n_params)

    def header_lines(self) -> list[str]:
        """The block above the parameter table, as statsmodels' ``summary()`` opens: one
        ``Name: value`` line each (rich markup; user strings escaped), then an empty line."""
        from rczone.results.fit_text import esc

        rows = self.header_rows()
        wide = max(len(k) for k, _ in rows)
        return [f"{k + ':':<{wide + 1}} {esc(v)}" for k, v in rows] + [""]

    def header_rows(self) -> list[tuple[str, str]]:
        """The block above the parameter table, as statsmodels' ``summary()`` opens."""
        r = self.result
        llf = "n/a (least squares)" if not math.isfinite(r.llf) else f"{r.llf:.6g}"
        ic = lambda v: "n/a" if not math.isfinite(v) else f"{v:.6g}"  # noqa: E731
        return [
            ("Model", str(getattr(self, "model_label", "model"))),
            ("Data", str(getattr(self, "data_label", "data"))),
            ("Method", f"{r.method.upper()} ({r.objective})"),
            ("No. Observations", str(r.nobs)),
            ("Df Model", str(r.n_params)),
            ("Log-Likelihood", llf),
            ("AIC", ic(r.aic)),
            ("BIC", ic(r.bic)),
            ("RMSE (K)", f"{r.rmse_K:.4g} ({r.rmse_kind})"),
        ]


class PredictionFrames:
    """statsmodels' ``summary_frame(alpha)`` on a prediction; the host has ``predicted``, ``sd``,
    ``outputs``, ``t``, ``index``."""

    predicted: np.ndarray
    sd: np.ndarray
    outputs: tuple[str, ...]
    t: np.ndarray
    index: Any

    def summary_frame(self, alpha: float = 0.05, output: str | None = None) -> pd.DataFrame:
        """Mean, its standard deviation and the band of level ``1 - alpha`` of one output.

        The columns are statsmodels' (``mean``, ``mean_se``, ``mean_ci_lower``, ``mean_ci_upper``);
        the band is ``mean -+ z sd`` with ``z`` the normal quantile, at any ``alpha`` (the report's
        band is ``alpha = 0.0455``, two standard deviations).

        Parameters
        ----------
        alpha : float
            One minus the band's probability.
        output : str, optional
            The output (default the first).

        Returns
        -------
        DataFrame
            Indexed by the data's time stamps (or by the time in seconds without clock time).

        Raises
        ------
        DataError
            The prediction has no band (a model without noise levels or standard errors).
        """
        import pandas as pd

        from rczone.errors import DataError

        z = normal_quantile(alpha)
        if not getattr(self, "has_band", True):  # no standard deviation: a band of NaN is no band
            raise DataError(f"the prediction has {getattr(self, 'no_band_note', 'no band')}")
        name = self.outputs[0] if output is None else output
        if name not in self.outputs:
            raise ParameterError(f"output must be one of {', '.join(self.outputs)}, got {output!r}")
        j = self.outputs.index(name)
        mean, sd = self.predicted[:, j], self.sd[:, j]
        index = self.index if self.index is not None else pd.Index(self.t, name="time")
        return pd.DataFrame(
            {"mean": mean, "mean_se": sd, "mean_ci_lower": mean - z * sd, "mean_ci_upper": mean + z * sd},
            index=index,
        )

    @property
    def predicted_mean(self) -> pd.DataFrame:
        """The predictions, one column per output (statsmodels ``predicted_mean``)."""
        import pandas as pd

        index = self.index if self.index is not None else pd.Index(self.t, name="time")
        return pd.DataFrame(self.predicted, index=index, columns=list(self.outputs))
