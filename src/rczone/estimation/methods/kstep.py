"""The k-step prediction-error method (``--method kstep --option horizons=1,12,72``).

MPC-relevant identification (Shook, Mohtadi & Shah 1991; Gopaluni, Patwardhan & Shah 2003): the
free parameters minimize the k-step prediction errors of the Kalman predictor over a set of
horizons (:mod:`rczone.estimation.kstep`), starting from the maximum-likelihood fit of the same
problem (its global search), with the noise levels then scaled for the band and sandwich standard
errors (:mod:`rczone.estimation.kstep_fit`).

References
----------
.. [1] M. S. Shook, C. Mohtadi, S. L. Shah, "Identification for long-range predictive control",
   IEE Proceedings D 138 (1991) 75-84.
.. [2] R. B. Gopaluni, R. S. Patwardhan, S. L. Shah, "The nature of data pre-filters in MPC
   relevant identification - open- and closed-loop issues", Automatica 39 (2003) 1617-1626.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.methods.base import FitProblem, Method, MethodOptions, NoOptions


@dataclass(frozen=True, kw_only=True)
class KStepOptions(MethodOptions):
    """Options of the k-step method.

    Attributes
    ----------
    horizons : tuple of int
        Steps ahead whose prediction errors the criterion sums.
    """

    horizons: tuple[int, ...] = (1, 12, 72)

    def __post_init__(self) -> None:
        from rczone.estimation.kstep import check_horizons

        if not isinstance(self.horizons, (tuple, list)) or any(isinstance(h, bool) for h in self.horizons):
            raise ParameterError(
                f"option horizons must be positive step counts (e.g. 1,12,72), got {self.horizons!r}"
            )
        object.__setattr__(self, "horizons", check_horizons(self.horizons))


def run(problem: FitProblem, options: KStepOptions, rng: np.random.Generator):
    """The likelihood fit of the problem, then the k-step criterion from its estimate."""
    from rczone.estimation.kstep_fit import fit_kstep
    from rczone.estimation.methods.registry import method_of
    from rczone.estimation.minimize import point_result

    ml = method_of("ml").run(dataclasses.replace(problem, method="ml"), NoOptions(), rng)
    res = fit_kstep(
        problem.network,
        problem.data,
        horizons=options.horizons,
        ml=ml,
        hold=problem.hold,
        max_evals=problem.max_evals or 200,
        progress=problem.progress,
    )
    theta = np.array([res.values[n] for n in problem.spec.names])
    out = point_result(
        problem,
        theta,
        cost=res.objective,
        n_evals=ml.n_evals + res.n_evals,
        converged=res.converged and ml.converged,
        optimizer="L-BFGS-B on the k-step criterion from the ML fit",
    )
    parameters = {n: e._replace(std_error=res.std_error.get(n, math.nan)) for n, e in out.parameters.items()}
    notes = (
        *out.notes,
        *res.notes,
        f"k-step criterion {res.objective:.5g} K^2 at horizons {', '.join(map(str, res.horizons))} steps"
        f" ({res.objective_ml:.5g} at the ML estimate); noise levels x {res.noise_scale:.3g} for the band;"
        " standard errors by the sandwich",
    )
    return dataclasses.replace(out, parameters=parameters, notes=notes)


METHOD = Method(
    name="kstep",
    title="k-step prediction error of the Kalman predictor (MPC-relevant)",
    kernel="ml",
    stochastic=True,
    objective="k-step prediction error, K^2",
    rmse_kind="one-step",
    abs_tol=1e-6,
    rel_tol=1e-6,
    options=KStepOptions,
    run=run,
)
