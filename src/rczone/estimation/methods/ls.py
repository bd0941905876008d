"""Output-error least squares (Lin et al. 2012, eq. 8): the trapezoid squared error of the simulated output.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012.
"""

from __future__ import annotations

import numpy as np

from rczone.estimation.methods.base import FitProblem, Method, NoOptions


def run(problem: FitProblem, options: NoOptions, rng: np.random.Generator):
    """Minimize the squared output error over the problem's free parameters (global search)."""
    from rczone.estimation.minimize import minimize_fit

    return minimize_fit(problem, problem.objective(), rng)


METHOD = Method(
    name="ls",
    title="output-error least squares",
    kernel="ls",
    stochastic=False,
    objective="squared output error, K^2 s",
    rmse_kind="open-loop",
    abs_tol=0.0,
    rel_tol=1e-5,
    run=run,
)
