"""Identification of R, C and noise parameters from data (Lin et al. 2012 [1]_, section IV).

``fit(network, data, free=[...], method="ls"|"ml"|"map"|"mcmc")`` is the entry point; the
modules hold the pieces: :mod:`parameters` (free set, bounds, theta/eta), :mod:`kalman`
(filter likelihood), :mod:`costs`, :mod:`priors`, :mod:`optimize`, :mod:`uncertainty`,
:mod:`sampling` and :mod:`posterior` (posterior draws), :mod:`result`, :mod:`validation` and a
minimal :mod:`data` set.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from rczone.estimation.costs import Objective, ls_cost, ml_cost
from rczone.estimation.data import Dataset
from rczone.estimation.fit import fit
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.parameters import ParameterSpec, make_spec, noise_parameter_names
from rczone.estimation.posterior import Posterior
from rczone.estimation.result import FitResult

__all__ = [
    "Dataset",
    "FitResult",
    "McmcOptions",
    "Objective",
    "ParameterSpec",
    "Posterior",
    "fit",
    "ls_cost",
    "make_spec",
    "ml_cost",
    "noise_parameter_names",
]
