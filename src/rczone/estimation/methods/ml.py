"""Kalman-filter maximum likelihood (Lin et al. 2012, eq. 9): measurement and process noise estimated.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012.
.. [2] N. R. Kristensen, H. Madsen, S. B. Jørgensen, "Parameter estimation in stochastic grey-box
   models", Automatica 40(2), 2004, 225-237.
"""

from __future__ import annotations

import numpy as np

from rczone.estimation.methods.base import FitProblem, Method, NoOptions


def run(problem: FitProblem, options: NoOptions, rng: np.random.Generator):
    """Minimize the negative log-likelihood of the Kalman filter's innovations (global search)."""
    from rczone.estimation.minimize import minimize_fit

    return minimize_fit(problem, problem.objective(), rng)


METHOD = Method(
    name="ml",
    title="Kalman-filter maximum likelihood",
    kernel="ml",
    stochastic=True,
    objective="negative log-likelihood",
    rmse_kind="one-step",
    abs_tol=0.01,
    rel_tol=1e-9,
    run=run,
)
