"""The estimation methods, registered in one place.

Every module that behaves differently per method asks the :class:`Method` record for the
property it needs (is the objective a likelihood? is there a prior? which kernel cost does it
call?) instead of comparing method strings, as lmfit's ``Minimizer.minimize(method=)`` dispatches
from one table. A new estimator is a module that computes its objective and one line of
:data:`REGISTRY`.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   (eq. 8: output-error least squares; eq. 9: Kalman-filter maximum likelihood).
"""

from __future__ import annotations

from typing import NamedTuple

from rczone.errors import ParameterError, did_you_mean


class Method(NamedTuple):
    """What a fit method is, as the rest of rczone needs to know it.

    Attributes
    ----------
    name : str
        The method's name on the command line and in the API (``--method``, ``method=``).
    title : str
        What it is, in a few words.
    kernel : {"ls", "ml"}
        The kernel cost it evaluates: trapezoid squared output error, or the Kalman filter's
        negative log-likelihood.
    stochastic : bool
        Whether the model has a noise model (measurement and process noise are estimated, the
        objective is a likelihood, the residuals are innovations).
    prior : bool
        Whether the objective is a tempered likelihood plus a prior (MAP: the declared priors, a
        log-normal around the construction value for the other free R and C;
        :mod:`rczone.estimation.priors`).
    objective : str
        What the objective value means, with its unit.
    rmse_kind : str
        ``"open-loop"`` or ``"one-step"``: the error the fit's RMSE is of.
    abs_tol : float
        Objective differences below ``abs_tol + rel_tol |objective|`` are the same optimum.
    rel_tol : float
        See ``abs_tol``.
    search : {"minimize", "sample"}
        How :func:`rczone.estimation.fit.fit` finds the values: the global search for the minimum
        of the objective, or draws from the posterior (:mod:`rczone.estimation.sampling`: the
        likelihood of ``kernel`` plus the declared priors, the ``"flat"`` default of
        :mod:`rczone.estimation.priors` for the other parameters; the estimates are posterior means).
    """

    name: str
    title: str
    kernel: str
    stochastic: bool
    prior: bool
    objective: str
    rmse_kind: str
    abs_tol: float
    rel_tol: float
    search: str = "minimize"


#: The estimation methods by name (the first is listed first in help texts).
REGISTRY: dict[str, Method] = {
    m.name: m
    for m in (
        Method("ls", "output-error least squares", "ls", False, False, "squared output error, K^2 s", "open-loop", 0.0, 1e-5),
        Method("ml", "Kalman-filter maximum likelihood", "ml", True, False, "negative log-likelihood", "one-step", 0.01, 1e-9),
        Method("map", "maximum a posteriori (ML with a log-normal prior)", "ml", True, True, "negative log-posterior (tempered likelihood)", "one-step", 0.01, 1e-9),
        Method("mcmc", "posterior sampling (NUTS) of the Kalman likelihood and the declared priors", "ml", True, False, "negative log-likelihood at the posterior mean", "one-step", 0.01, 1e-9, "sample"),
    )
}  # fmt: skip

#: Method names, in registry order.
METHODS: tuple[str, ...] = tuple(REGISTRY)

#: The default method of the command line, the API and the batch manifest.
DEFAULT_METHOD = "ml"


def method_of(name: str) -> Method:
    """The registered method called ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`REGISTRY`.

    Returns
    -------
    Method

    Raises
    ------
    ParameterError
        For an unknown name, with the closest known one.
    """
    m = REGISTRY.get(name) if isinstance(name, str) else None
    if m is None:
        raise ParameterError(
            f"unknown method {name!r}; {did_you_mean(str(name), METHODS)} (method must be one of"
            f" {', '.join(METHODS)})"
        )
    return m
