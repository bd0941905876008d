"""Estimation methods as plug-ins: each one module with its own options and ``run``.

======================  =================================================================
module                  method
======================  =================================================================
:mod:`.ls`              ``ls``: output-error least squares
:mod:`.ml`              ``ml``: Kalman-filter maximum likelihood (the default)
:mod:`.map`             ``map``: ML with a prior, the likelihood tempered
:mod:`.mcmc`            ``mcmc``: posterior sampling (NUTS)
======================  =================================================================

:mod:`.base` says what a method is (:class:`Method`, :class:`MethodOptions`,
:class:`FitProblem`), :mod:`.registry` holds them by name and reads plug-ins from the
entry-point group ``rczone.methods``. docs/extending.md shows a complete small method.
"""

from rczone.estimation.methods.base import FitProblem, Method, MethodOptions, NoOptions
from rczone.estimation.methods.registry import (
    DEFAULT_METHOD,
    ENTRY_POINT_GROUP,
    REGISTRY,
    method_names,
    method_of,
    register_method,
    unregister_method,
)

__all__ = [
    "DEFAULT_METHOD",
    "ENTRY_POINT_GROUP",
    "REGISTRY",
    "FitProblem",
    "Method",
    "MethodOptions",
    "NoOptions",
    "method_names",
    "method_of",
    "register_method",
    "unregister_method",
]
