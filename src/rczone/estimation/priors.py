"""The prior of an estimation problem's free parameters, on the scale the estimator works on.

A posterior density is not invariant under a change of variable, so this module states the scale:
every term is ``-log p_eta(eta)``, the negative log density of the *optimizer* variable ``eta``
(:class:`~rczone.estimation.parameters.ParameterSpec`: ``eta = log theta`` for resistances,
capacitances and noise levels, ``eta = theta`` otherwise), up to a constant. A declared prior on
the physical value ``theta`` (:mod:`rczone.network.prior`) is carried to ``eta`` with the Jacobian
``|d theta / d eta| = theta`` of the log transform (Gelman et al. 2013, sec. 2.8):

=============  ==============================  ===============================================
declared       ``-log p_eta`` (log parameter)  ``-log p_eta`` (``eta = theta``)
=============  ==============================  ===============================================
``lognormal``  ``z^2 / 2``, ``z = (log theta - log median) / sigma`` (only on R and C)
``normal``     ``((theta - mean)/sigma)^2 / 2 - log theta``  ``((theta - mean)/sigma)^2 / 2``
``uniform``    ``-log theta`` inside, ``inf`` outside        ``0`` inside, ``inf`` outside
=============  ==============================  ===============================================

A parameter without a declared prior takes the estimator's default (:data:`DEFAULTS`):

* ``"construction"`` (the MAP fit): a log-normal around the construction value with spread
  ``prior_spread`` for every resistance and capacitance that has one (Kristensen, Madsen &
  Jørgensen 2004, sec. 2.2), flat in ``eta`` otherwise;
* ``"flat"`` (posterior sampling): flat in ``eta`` within the parameter's bounds, i.e. log-uniform
  (scale-invariant) for a resistance or a capacitance and uniform otherwise; the bounds make it
  proper. A noise level (a standard deviation) is uniform on its own scale instead: its
  likelihood does not vanish as it goes to zero (process noise explains what it leaves), so a
  log-uniform prior would put the posterior's mass on that plateau down to the lower bound
  (Gelman 2006 recommends the uniform on the standard deviation).

References
----------
Gelman, A., Carlin, J. B., Stern, H. S., Dunson, D. B., Vehtari, A. & Rubin, D. B. (2013).
*Bayesian Data Analysis*, 3rd ed. CRC Press.
Gelman, A. (2006). Prior distributions for variance parameters in hierarchical models. *Bayesian
Analysis* 1(3), 515-534.
Kristensen, N. R., Madsen, H. & Jørgensen, S. B. (2004). Parameter estimation in stochastic grey-box
models. *Automatica* 40(2), 225-237.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError
from rczone.estimation.parameters import ParameterSpec
from rczone.kernels.arrays import Penalty
from rczone.kernels.problem import LOGNORMAL, NORMAL, UNIFORM, prior_terms
from rczone.network.prior import Prior

#: How a free parameter without a declared prior is treated (see the module notes).
DEFAULTS = ("construction", "flat")


@dataclass(frozen=True, eq=False)
class LogPrior:
    """``-log p_eta`` of the free parameters of one problem, as a function of their physical values.

    Build it with :func:`log_prior`.

    Attributes
    ----------
    spec : ParameterSpec
        The free parameters, their transforms and construction values.
    priors : tuple of (Prior or None)
        The prior of each free parameter in the order of ``spec.names`` (on the physical value);
        None for flat in ``eta``.
    declared : tuple of str
        The free parameters whose prior the network declares.
    """

    spec: ParameterSpec
    priors: tuple[Prior | None, ...]
    declared: tuple[str, ...]

    def terms(self, theta: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """The negative log prior at ``theta``, its gradient and a positive curvature, in theta.

        Parameters
        ----------
        theta : ndarray, shape (d,)
            Physical values in the order of ``spec.names``.

        Returns
        -------
        value : float
            ``sum -log p_eta`` up to a constant; ``inf`` outside a uniform prior's support.
        grad : ndarray, shape (d,)
            Its gradient with respect to ``theta``.
        curv : ndarray, shape (d,)
            The prior's Fisher information in ``theta`` (what optimizers scale with).
        """
        theta = np.ascontiguousarray(theta, dtype=np.float64)
        grad, curv = np.zeros(theta.size), np.zeros(theta.size)
        total = prior_terms(theta, self.packed(), grad, curv)
        if not math.isfinite(total):
            return math.inf, np.zeros(theta.size), np.zeros(theta.size)
        return float(total), grad, curv

    def packed(self, likelihood_weight: float = 1.0) -> Penalty:
        """The priors as the arrays the compiled costs evaluate (:func:`rczone.kernels.problem.prior_terms`).

        Parameters
        ----------
        likelihood_weight : float
            The MAP cost's weight of the likelihood, carried along.

        Returns
        -------
        rczone.kernels.arrays.Penalty
        """
        rows = [
            (i, p, bool(lg)) for i, (p, lg) in enumerate(zip(self.priors, self.spec.log)) if p is not None
        ]
        family = {"lognormal": LOGNORMAL, "normal": NORMAL, "uniform": UNIFORM}
        a = [
            p.median if p.dist == "lognormal" else p.mean if p.dist == "normal" else p.lower
            for _, p, _ in rows
        ]
        b = [p.sigma if p.dist in ("lognormal", "normal") else p.upper for _, p, _ in rows]
        return Penalty(
            np.array([i for i, _, _ in rows], dtype=np.int64),
            np.array([family[p.dist] for _, p, _ in rows], dtype=np.int64),
            np.array(a, dtype=np.float64),
            np.array(b, dtype=np.float64),
            np.array([lg for _, _, lg in rows], dtype=np.bool_),
            float(likelihood_weight),
        )

    def to_dict(self) -> dict[str, object]:
        """The prior of each free parameter (``None``: flat in ``eta``), SI units."""
        return {n: (p.to_dict() if p is not None else None) for n, p in zip(self.spec.names, self.priors)}


def log_prior(
    spec: ParameterSpec,
    declared: Mapping[str, Prior],
    *,
    default: str = "construction",
    spread: float = math.log(2.0),
) -> LogPrior:
    """The prior of the free parameters of ``spec``: the declared ones, the default for the rest.

    Parameters
    ----------
    spec : ParameterSpec
        The free parameters.
    declared : mapping of str to Prior
        Declared priors by parameter name (:attr:`rczone.network.RCNetwork.priors`); those of
        parameters that are not free are ignored (a fixed parameter has no prior to apply).
    default : {"construction", "flat"}
        What an undeclared parameter gets (see the module notes).
    spread : float
        ``"construction"`` only: the log-normal's sigma (log units).

    Returns
    -------
    LogPrior

    Raises
    ------
    ParameterError
        For an unknown ``default`` or a non-positive ``spread``.
    """
    if default not in DEFAULTS:
        raise ParameterError(f"default prior must be one of {', '.join(DEFAULTS)}, got {default!r}")
    if not spread > 0:
        raise ParameterError(f"prior spread must be > 0, got {spread!r}")
    priors: list[Prior | None] = []
    for name, kind, c, lo, hi in zip(spec.names, spec.kinds, spec.construction, spec.lower, spec.upper):
        if name in declared:
            priors.append(declared[name])
        elif default == "construction" and kind in ("resistance", "capacitance") and math.isfinite(c):
            priors.append(Prior("lognormal", median=float(c), sigma=float(spread)))
        elif default == "flat" and kind == "noise":
            priors.append(Prior("uniform", lower=float(lo), upper=float(hi)))
        else:
            priors.append(None)
    return LogPrior(spec, tuple(priors), tuple(n for n in spec.names if n in declared))
