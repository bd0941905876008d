"""Posterior sampling (NUTS) of the Kalman likelihood and the declared priors.

The estimates are posterior means, the standard errors posterior standard deviations; R-hat, the
effective sample size and divergences decide convergence (:mod:`rczone.estimation.posterior`).
The sampler is nutpie's No-U-Turn sampler (Hoffman & Gelman 2014), run by
:mod:`rczone.estimation.sampling`.

References
----------
.. [1] M. D. Hoffman, A. Gelman, "The No-U-Turn sampler: adaptively setting path lengths in
   Hamiltonian Monte Carlo", J. Machine Learning Research 15, 2014, 1593-1623.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rczone.estimation.methods.base import FitProblem, Method, MethodOptions, positive_int

#: Smallest and largest value of each option (a typo of a few zeros in a manifest should not ask
#: for days of sampling or the memory of a billion draws). NUTS adapts its step size and mass matrix
#: in windows of the warm-up (Hoffman & Gelman 2014, sec. 3.2; nutpie's first window is 30 % of it):
#: without warm-up draws nutpie's adaptation panics, so at least as many as the draws' minimum.
LIMITS = {"draws": (10, 1_000_000), "tune": (10, 1_000_000), "chains": (1, 64)}


@dataclass(frozen=True, kw_only=True)
class McmcOptions(MethodOptions):
    """How long to sample.

    Attributes
    ----------
    draws : int
        Draws kept per chain.
    tune : int
        Warm-up draws per chain (step size and mass matrix adaptation), discarded.
    chains : int
        Independent chains (R-hat needs at least two).
    """

    draws: int = 1000
    tune: int = 1000
    chains: int = 4

    def __post_init__(self) -> None:
        for name, (low, high) in LIMITS.items():
            positive_int(self, name, low, high)


def run(problem: FitProblem, options: McmcOptions, rng: np.random.Generator):
    """Sample the posterior of the ML objective from around one L-BFGS search."""
    from rczone.estimation.sampling import sample_fit

    return sample_fit(problem.objective(), settings=options, rng=rng, progress=problem.progress)


METHOD = Method(
    name="mcmc",
    title="posterior sampling (NUTS) of the Kalman likelihood and the declared priors",
    kernel="ml",
    stochastic=True,
    objective="negative log-likelihood at the posterior mean",
    rmse_kind="one-step",
    abs_tol=0.01,
    rel_tol=1e-9,
    search="sample",
    options=McmcOptions,
    run=run,
)
