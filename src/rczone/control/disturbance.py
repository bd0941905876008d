"""An unmeasured disturbance appended to the state for offset-free estimation and control.

A fitted model never matches the building exactly: occupants, solar gains and a wrong
resistance all look to a controller like an unknown, slowly varying heat input or an offset of
the measured temperature. Appending such a disturbance ``d`` to the state and estimating it
with the Kalman filter gives offset-free tracking (Pannocchia and Rawlings [1]_; Maeder,
Borrelli and Morari [2]_): the controller predicts with the estimated ``d`` held (integrating,
a random walk) or decaying (first order, time constant ``tau``).

* ``kind="heat"``: ``d`` (W) enters the heat balance of one capacitive node (default the node of
  the first output) as ``d / C_node``;
* ``kind="offset"``: ``d`` (K) adds to one output (default the first).

The disturbance is driven by white noise of intensity ``sigma`` (W/sqrt(s) or K/sqrt(s)); its
ratio to the measurement noise sets how fast the estimate follows a change.

References
----------
.. [1] G. Pannocchia, J. B. Rawlings, "Disturbance models for offset-free model-predictive
   control", AIChE Journal 49(2) (2003) 426-437.
.. [2] U. Maeder, F. Borrelli, M. Morari, "Linear offset-free model predictive control",
   Automatica 45(10) (2009) 2214-2222.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rczone.errors import ParameterError, did_you_mean

KINDS = ("heat", "offset")
#: Default intensity of the disturbance's driving noise: W/sqrt(s) for heat (a change of about
#: 120 W per hour is believed at once), K/sqrt(s) for an offset (about 0.1 K per hour).
DEFAULT_SIGMA = {"heat": 2.0, "offset": 1.5e-3}
UNITS = {"heat": "W", "offset": "K"}


@dataclass(frozen=True)
class Disturbance:
    """Declaration of the disturbance state (see the module notes).

    Parameters
    ----------
    kind : {"heat", "offset"}
    node : str, optional
        The state node that receives the heat, or the output that gets the offset.
    tau : float, optional
        Correlation time, s (first order); ``None`` integrates (random walk).
    sigma : float, optional
        Intensity of the driving noise; default :data:`DEFAULT_SIGMA`.
    """

    kind: str = "heat"
    node: str | None = None
    tau: float | None = None
    sigma: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ParameterError(f"disturbance kind {self.kind!r}: " + did_you_mean(self.kind, KINDS))
        if self.tau is not None and not (math.isfinite(self.tau) and self.tau > 0):
            raise ParameterError(f"disturbance tau must be finite and > 0 s (or None), got {self.tau!r}")
        if self.sigma is not None and not (math.isfinite(self.sigma) and self.sigma > 0):
            raise ParameterError(f"disturbance sigma must be finite and > 0, got {self.sigma!r}")

    @property
    def intensity(self) -> float:
        """The driving noise's intensity (given or default)."""
        return DEFAULT_SIGMA[self.kind] if self.sigma is None else float(self.sigma)

    @property
    def state_name(self) -> str:
        """Name of the appended state: ``d_heat`` or ``d_offset``."""
        return f"d_{self.kind}"

    @property
    def unit(self) -> str:
        return UNITS[self.kind]

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "node": self.node,
            "tau_s": self.tau,
            "sigma": self.intensity,
            "unit": self.unit,
        }
