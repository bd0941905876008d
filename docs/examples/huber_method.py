"""A Huber-loss output-error estimator for rczone, as a plug-in: one file, one registry line.

Robust least squares down-weights the few samples a sensor glitch or a door left open spoils
(Huber 1964): squared error below ``scale_K``, linear above it. Install it as a package whose
``pyproject.toml`` declares::

    [project.entry-points."rczone.methods"]
    huber = "huber_method:METHOD"

or register it in Python with ``rczone.register_method(METHOD)``. Then ``rczone fit DATA --method
huber --option scale_K=0.2`` and ``rczone.fit(model, data, method="huber", options={"scale_K":
0.2})`` run it.

References
----------
.. [1] P. J. Huber, "Robust estimation of a location parameter", Annals of Mathematical
   Statistics 35(1), 1964, 73-101.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from rczone.errors import ParameterError
from rczone.estimation.methods import FitProblem, Method, MethodOptions
from rczone.estimation.minimize import point_result


@dataclass(frozen=True, kw_only=True)
class HuberOptions(MethodOptions):
    """Options of the Huber method.

    Attributes
    ----------
    scale_K : float
        Errors below this size count squared, larger ones linearly, K.
    """

    scale_K: float = 0.1

    def __post_init__(self) -> None:
        if not (isinstance(self.scale_K, (int, float)) and math.isfinite(self.scale_K) and self.scale_K > 0):
            raise ParameterError(f"option scale_K must be a finite number > 0, got {self.scale_K!r}")


def run(problem: FitProblem, options: HuberOptions, rng: np.random.Generator):
    """Minimize the Huber loss of the open-loop output error from the model's values."""
    spec = problem.spec

    def residuals(eta: np.ndarray) -> np.ndarray:
        e = problem.output_error(spec.to_theta(eta))
        return np.nan_to_num(e[np.isfinite(e)])

    sol = least_squares(
        residuals,
        spec.to_eta(spec.start),
        bounds=(spec.eta_lower, spec.eta_upper),
        loss="huber",
        f_scale=options.scale_K,
    )
    return point_result(
        problem,
        spec.to_theta(sol.x),
        cost=float(sol.cost),
        n_evals=int(sol.nfev),
        converged=bool(sol.success),
        optimizer="scipy least_squares (huber)",
        message=str(sol.message),
    )


METHOD = Method(
    name="huber",
    title="output-error least squares with a Huber loss",
    kernel="ls",
    stochastic=False,
    objective="Huber loss of the output error, K^2",
    rmse_kind="open-loop",
    options=HuberOptions,
    run=run,
)
