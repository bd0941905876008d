"""The workflows a user runs, shared by the command line and the Python API.

:class:`FitSettings` is the one settings object of a fit; :func:`fit_and_check` fits and makes the
checks after the fit; :mod:`rczone.workflow.api` holds the functions :mod:`rczone` exports.
"""

from rczone.estimation.settings import FitSettings
from rczone.workflow.checks import check_fit, fit_and_check

__all__ = ["FitSettings", "check_fit", "fit_and_check"]
