"""Maximum a posteriori: a tempered Kalman likelihood plus a prior on the free R and C.

The prior is the one declared in the model file, else log-normal around the construction value
with spread :attr:`MapOptions.prior_spread` (a factor of 2 by default; Kristensen, Madsen &
Jørgensen 2004 use such priors for grey-box models). The likelihood is counted once per
:attr:`MapOptions.correlation_time_s` of correlated output error, a tempered (power) likelihood
(Bissiri, Holmes & Walker 2016), so that a night of closed-loop data cannot overrule the
construction values with thousands of samples that carry the information of a few dozen.

References
----------
.. [1] N. R. Kristensen, H. Madsen, S. B. Jørgensen, "Parameter estimation in stochastic grey-box
   models", Automatica 40(2), 2004, 225-237.
.. [2] P. G. Bissiri, C. C. Holmes, S. G. Walker, "A general framework for updating belief
   distributions", J. R. Stat. Soc. B 78(5), 2016.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rczone.estimation.methods.base import FitProblem, Method, MethodOptions, positive_float

#: Default spread of the log-normal prior, log units (a factor of 2).
PRIOR_SPREAD = math.log(2.0)
#: Default correlation time of the output error, s.
CORRELATION_TIME_S = 1800.0


@dataclass(frozen=True, kw_only=True)
class MapOptions(MethodOptions):
    """Options of the MAP method.

    Attributes
    ----------
    prior_spread : float
        Spread (log units) of the default log-normal prior around the construction value.
    correlation_time_s : float
        Correlation time of the output error, s; the likelihood is weighted by
        ``min(1, dt / correlation_time_s)``.
    """

    prior_spread: float = PRIOR_SPREAD
    correlation_time_s: float = CORRELATION_TIME_S

    def __post_init__(self) -> None:
        positive_float(self, "prior_spread")
        positive_float(self, "correlation_time_s")


def run(problem: FitProblem, options: MapOptions, rng: np.random.Generator):
    """Minimize the negative log-posterior of the tempered likelihood (global search)."""
    from rczone.estimation.minimize import minimize_fit

    weight = min(1.0, problem.sample_time_s / options.correlation_time_s)
    objective = problem.objective(prior_spread=options.prior_spread, likelihood_weight=weight)
    return minimize_fit(problem, objective, rng)


METHOD = Method(
    name="map",
    title="maximum a posteriori (ML with a log-normal prior)",
    kernel="ml",
    stochastic=True,
    prior=True,
    objective="negative log-posterior (tempered likelihood)",
    rmse_kind="one-step",
    abs_tol=0.01,
    rel_tol=1e-9,
    options=MapOptions,
    run=run,
)
