"""The noise model of a fitted zone: continuous intensities and their discrete covariances.

A likelihood fit (``--method ml``) estimates the stochastic model of Madsen and Holst [1]_

.. math::

    dx = (A(m) x + B(m) u)\\,dt + \\sigma_w\\,dW, \\qquad y_k = C x_k + D u_k + v_k,
    \\quad v_k \\sim N(0, R),

with one process-noise intensity ``sigma_w_<state>`` (K/sqrt(s)) per state and one measurement
standard deviation ``sigma_v`` (K) per output, stored in :attr:`ZoneModel.noise`. Over a sample
time ``dt`` at a constant flow ``m`` the process noise integrates to the discrete covariance
``Qd = int_0^dt e^{A(m)s} Qc e^{A(m)'s} ds`` (Van Loan [2]_), computed by the project's one
discretization module (:func:`rczone.simulation.discretize.process_noise_covariance`, called
by :class:`rczone.control.model.ControlModel`).

A model without fitted noise (a least-squares fit, construction values) gets the documented
defaults of :data:`rczone.network.stochastic.KINDS`, and :attr:`NoiseModel.source`
says so.

References
----------
.. [1] H. Madsen, J. Holst, "Estimation of continuous-time models for the heat dynamics of a
   building", Energy and Buildings 22 (1995) 67-79.
.. [2] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23(3), 1978.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel
from rczone.network.stochastic import (
    KINDS,
    MEASUREMENT_NOISE,
    PROCESS_NOISE,
    measurement_noise_names,
    process_noise_name,
    process_noise_names,
)


@dataclass(frozen=True, eq=False)
class NoiseModel:
    """Continuous process-noise intensity and measurement-noise covariance of a model.

    Attributes
    ----------
    Qc : ndarray, shape (n, n), K^2/s
        Diagonal, ``sigma_w_<state>**2``.
    R : ndarray, shape (ny, ny), K^2
        Diagonal, ``sigma_v**2`` per output.
    state_names, output_names : tuple of str
    source : str
        ``"fitted"`` when every value came from the model, ``"default"`` or ``"partly default"``.
    """

    Qc: np.ndarray
    R: np.ndarray
    state_names: tuple[str, ...]
    output_names: tuple[str, ...]
    source: str

    @classmethod
    def from_model(cls, model: ZoneModel, *, overrides: Mapping[str, float] | None = None) -> NoiseModel:
        """The noise of ``model`` (its ``sigma_w_*``, ``sigma_v*``), defaults where it has none.

        Parameters
        ----------
        model : ZoneModel
        overrides : mapping, optional
            ``sigma_w_<state>`` / ``sigma_v`` values that replace the model's.
        """
        net = model.network
        values = {**dict(model.noise), **dict(overrides or {})}
        w_names = list(process_noise_names(net.state_names))
        v_names = list(measurement_noise_names(net.outputs))
        unknown = [k for k in dict(overrides or {}) if k not in (*w_names, *v_names)]
        if unknown:
            raise ParameterError(
                f"noise override {unknown[0]!r}: model {net.name!r} has the noise values "
                f"{', '.join((*w_names, *v_names))}"
            )
        sw = [values.get(k, KINDS[PROCESS_NOISE].default) for k in w_names]
        sv = [values.get(k, KINDS[MEASUREMENT_NOISE].default) for k in v_names]
        for k, v in zip((*w_names, *v_names), (*sw, *sv)):
            if not (math.isfinite(v) and v >= 0):
                raise ParameterError(f"noise value {k} = {v!r}: must be finite and >= 0")
        if any(v <= 0 for v in sv):
            raise ParameterError(
                "a measurement-noise standard deviation is 0: a state estimator needs sigma_v > 0 "
                "(override it, e.g. with the sensor's resolution)"
            )
        given = sum(k in values for k in (*w_names, *v_names))
        source = (
            "fitted" if given == len(w_names) + len(v_names) else "default" if not given else "partly default"
        )
        return cls(np.diag(np.square(sw)), np.diag(np.square(sv)), net.state_names, net.outputs, source)

    def to_dict(self) -> dict[str, Any]:
        """Named standard deviations (what ``--json`` writes)."""
        return {
            "sigma_w_K_per_sqrt_s": dict(zip(self.state_names, np.sqrt(np.diag(self.Qc)).tolist())),
            "sigma_v_K": dict(zip(self.output_names, np.sqrt(np.diag(self.R)).tolist())),
            "source": self.source,
        }

    def summary(self) -> str:
        """One line per noise value."""
        d = self.to_dict()
        lines = [f"noise model ({d['source']})"]
        lines += [
            f"  {process_noise_name(k):<18s} {v:.3g} K/sqrt(s)" for k, v in d["sigma_w_K_per_sqrt_s"].items()
        ]
        lines += [f"  sigma_v {k:<10s} {v:.3g} K" for k, v in d["sigma_v_K"].items()]
        return "\n".join(lines)
