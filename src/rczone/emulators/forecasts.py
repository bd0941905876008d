"""Weather forecasts with error: BOPTEST's forecast uncertainty scenarios for the outdoor temperature.

BOPTEST [1]_ emulates the error of a dry-bulb temperature forecast issued at time ``k`` for
``tau`` hours ahead by a first-order autoregressive process fitted to forecasts of five cities
by Zheng et al. [2]_:

.. math::

    e_{1|k} = F_0 + K_0\\,\\omega_0, \\qquad
    e_{\\tau+1|k} = F\\,e_{\\tau|k} + \\varepsilon_\\tau, \\quad
    \\varepsilon_\\tau \\sim \\mathcal N(\\mu, K^2),

and the forecast is the true value plus the error, ``To(k + tau) + e_{tau|k}``. Each scenario is
one set of parameters (:data:`SCENARIOS`, the values BOPTEST ships for ``low``, ``medium`` and
``high``; ``none`` is its deterministic forecast). A fresh error path is drawn for every forecast,
from a generator seeded by the test's seed. Here the path is drawn at whole hours ``tau = 1, 2,
...`` after the forecast's first time, the error at that first time is zero (it is measured), and
values in between are interpolated linearly.

References
----------
.. [1] D. Blum et al., "Building optimization testing framework (BOPTEST) for simulation-based
   benchmarking of control strategies in buildings", Journal of Building Performance Simulation
   14(5) (2021) 586-610; its documentation "Weather forecast uncertainty emulator" (forecast
   uncertainty scenarios) and the parameters of ``forecast/forecast_uncertainty_params.json``.
.. [2] W. Zheng, L. Zabala, J. Febres, D. Blum, Z. Wang, "Quantifying and simulating the weather
   forecast uncertainty for advanced building control", Journal of Building Performance
   Simulation (2025) 1-16, doi:10.1080/19401493.2025.2453537.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError, did_you_mean


@dataclass(frozen=True)
class AR1Error:
    """The AR(1) forecast error of one scenario (K; see the module notes)."""

    F0: float
    K0: float
    F: float
    K: float
    mu: float

    def path(self, hours: int, rng: np.random.Generator) -> np.ndarray:
        """Errors ``e_{1|k} .. e_{hours|k}`` (shape (hours,)), K."""
        e = np.empty(hours)
        if hours:
            e[0] = rng.normal(self.F0, self.K0)
        for i in range(1, hours):
            e[i] = rng.normal(self.F * e[i - 1] + self.mu, self.K)
        return e


#: BOPTEST's temperature forecast uncertainty scenarios (``none``: no error).
SCENARIOS: dict[str, AR1Error | None] = {
    "none": None,
    "low": AR1Error(F0=0.0, K0=0.6, F=0.92, K=0.4, mu=0.0),
    "medium": AR1Error(F0=0.15, K0=1.2, F=0.93, K=0.6, mu=0.0),
    "high": AR1Error(F0=-0.58, K0=1.5, F=0.95, K=0.7, mu=-0.015),
}


def scenario(name: str) -> AR1Error | None:
    """The error model of scenario ``name``, or one line naming the scenarios."""
    if name not in SCENARIOS:
        raise ParameterError(f"unknown forecast uncertainty {name!r}; {did_you_mean(name, SCENARIOS)}")
    return SCENARIOS[name]


def forecast_error(model: AR1Error | None, offsets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The error of a forecast at ``offsets`` s after its issue (shape of ``offsets``), K."""
    offsets = np.asarray(offsets, float)
    if model is None or offsets.size == 0:
        return np.zeros_like(offsets)
    hours = int(np.ceil(offsets.max() / 3600.0)) if offsets.max() > 0 else 0
    knots = np.r_[0.0, model.path(hours, rng)]
    return np.interp(offsets / 3600.0, np.arange(hours + 1), knots)
