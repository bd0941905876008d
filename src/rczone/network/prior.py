"""A parameter's prior distribution, declared beside it (in a model file: its ``prior`` table).

Three families cover what a building's construction says about a parameter:

=============  =====================  =======================================================
``dist``       keys                   density of the physical value ``x``
=============  =====================  =======================================================
``lognormal``  ``median``, ``sigma``  ``log x ~ N(log median, sigma^2)``; ``x > 0``, so only a
                                      resistance or a capacitance may have it
``normal``     ``mean``, ``sigma``    ``x ~ N(mean, sigma^2)``
``uniform``    ``lower``, ``upper``   constant on ``[lower, upper]``
=============  =====================  =======================================================

``median``, ``mean``, ``lower``, ``upper`` and a normal's ``sigma`` are in the parameter's unit; a
log-normal's ``sigma`` is dimensionless (a factor ``exp(sigma)`` around the median: 0.7 is
"within a factor of two" at one standard deviation). The log-normal is the usual prior of a
positive physical parameter (Gelman et al. 2013, sec. 2.8; Kristensen, Madsen & Jørgensen 2004,
sec. 2.2 use it in the MAP estimation of grey-box models).

Estimators read them through :mod:`rczone.estimation.priors`: the MAP cost adds the declared prior
of every free parameter that has one (and its own log-normal around the construction value for the
other resistances and capacitances), and posterior sampling (``--method mcmc``,
:mod:`rczone.estimation.sampling`) samples the likelihood times the declared priors.

References
----------
Gelman, A., Carlin, J. B., Stern, H. S., Dunson, D. B., Vehtari, A. & Rubin, D. B. (2013).
*Bayesian Data Analysis*, 3rd ed. CRC Press.
Kristensen, N. R., Madsen, H. & Jørgensen, S. B. (2004). Parameter estimation in stochastic grey-box
models. *Automatica* 40(2), 225-237.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from rczone.errors import ParameterError, did_you_mean

#: dist -> the keys that define it, in the order they are written.
DISTRIBUTIONS = {
    "lognormal": ("median", "sigma"),
    "normal": ("mean", "sigma"),
    "uniform": ("lower", "upper"),
}

#: Keys scaled with the parameter's unit (a log-normal's sigma is a ratio, not scaled).
_SCALED = {"lognormal": ("median",), "normal": ("mean", "sigma"), "uniform": ("lower", "upper")}
_ALL_KEYS = ("median", "mean", "sigma", "lower", "upper")


@dataclass(frozen=True)
class Prior:
    """The prior distribution of one parameter (see the module table).

    Give ``dist`` and exactly the two numbers of its family, in SI units:
    ``Prior("lognormal", median=0.01, sigma=0.7)``, ``Prior("normal", mean=20.0, sigma=2.0)``,
    ``Prior("uniform", lower=0.0, upper=50.0)``.

    Parameters
    ----------
    dist : {"lognormal", "normal", "uniform"}
        The family.
    median, mean, sigma, lower, upper : float, optional
        The family's numbers (:data:`DISTRIBUTIONS`); the others stay None.

    Raises
    ------
    ParameterError
        For an unknown family, a number missing, foreign to the family or not finite,
        ``sigma <= 0``, ``median <= 0`` or ``lower >= upper``.
    """

    dist: str
    median: float | None = None
    mean: float | None = None
    sigma: float | None = None
    lower: float | None = None
    upper: float | None = None

    def __post_init__(self) -> None:
        if self.dist not in DISTRIBUTIONS:
            raise ParameterError(
                f"prior dist {self.dist!r} is not one of {', '.join(DISTRIBUTIONS)}; "
                + did_you_mean(str(self.dist), tuple(DISTRIBUTIONS))
            )
        keys = DISTRIBUTIONS[self.dist]
        for key in _ALL_KEYS:
            v = getattr(self, key)
            if key not in keys:
                if v is not None:
                    raise ParameterError(
                        f"{self.dist} prior: {key} belongs to another family; it is defined by {', '.join(keys)}"
                    )
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"{self.dist} prior: {key} must be a finite number, got {v!r}")
            object.__setattr__(self, key, float(v))
        if self.dist == "uniform" and not self.lower < self.upper:
            raise ParameterError(f"uniform prior: lower {self.lower:g} must be < upper {self.upper:g}")
        if self.dist != "uniform" and not self.sigma > 0:
            raise ParameterError(f"{self.dist} prior: sigma must be > 0, got {self.sigma:g}")
        if self.dist == "lognormal" and not self.median > 0:
            raise ParameterError(f"lognormal prior: median must be > 0, got {self.median:g}")

    @classmethod
    def from_dict(cls, d: Mapping[str, object], *, scale: float = 1.0) -> Prior:
        """A prior from ``{"dist": ..., <its keys>}`` (a model file's table, a JSON object).

        Parameters
        ----------
        d : mapping
            ``dist`` and exactly the keys of that family.
        scale : float
            Factor from the table's unit to SI (applied to the keys in the parameter's unit).

        Raises
        ------
        ParameterError
            One line naming the missing, unknown or malformed key, with a hint.
        """
        dist = d.get("dist")
        if dist is None:
            raise ParameterError(f"a prior needs dist = one of {', '.join(DISTRIBUTIONS)}")
        if not isinstance(dist, str) or dist not in DISTRIBUTIONS:
            raise ParameterError(
                f"prior dist {dist!r} is not one of {', '.join(DISTRIBUTIONS)}; "
                + did_you_mean(str(dist), tuple(DISTRIBUTIONS))
            )
        keys = DISTRIBUTIONS[dist]
        allowed = ("dist", *keys)
        for k in d:
            if k not in allowed:
                raise ParameterError(
                    f"{dist} prior: unknown key {k!r}; {did_you_mean(str(k), allowed)}"
                    f" (allowed: {', '.join(allowed)})"
                )
        missing = [k for k in keys if k not in d]
        if missing:
            raise ParameterError(
                f"{dist} prior: needs {' and '.join(missing)} (it is defined by {', '.join(keys)})"
            )
        values = {}
        for k in keys:
            v = d[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ParameterError(f"{dist} prior: {k} must be a number, got {v!r}")
            values[k] = float(v) * scale if k in _SCALED[dist] else float(v)
        return cls(dist, **values)

    def to_dict(self) -> dict[str, object]:
        """``{"dist": ..., <its keys>}`` in SI units, what :meth:`from_dict` reads back."""
        return {"dist": self.dist, **{k: getattr(self, k) for k in DISTRIBUTIONS[self.dist]}}

    @property
    def needs_positive(self) -> bool:
        """True when the distribution lives on ``x > 0`` (a log-normal)."""
        return self.dist == "lognormal"

    def logpdf(self, x: float) -> float:
        """The log density at the physical value ``x`` (``-inf`` outside the support)."""
        if self.dist == "uniform":
            return -math.log(self.upper - self.lower) if self.lower <= x <= self.upper else -math.inf
        if self.dist == "normal":
            z = (x - self.mean) / self.sigma
            return -0.5 * z * z - math.log(self.sigma) - 0.5 * math.log(2.0 * math.pi)
        if not x > 0:
            return -math.inf
        z = (math.log(x) - math.log(self.median)) / self.sigma
        return -0.5 * z * z - math.log(self.sigma * x) - 0.5 * math.log(2.0 * math.pi)
