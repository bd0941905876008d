"""The zone model as an estimator and a controller see it: noise, reheat and disturbance appended.

:class:`ControlModel` wraps a :class:`~rczone.models.zone.ZoneModel` and adds

* the noise model (:class:`~rczone.control.noise.NoiseModel`);
* a heat input at the supply-air node (W), the reheat coil's power: with ``Ts = T_ahu + P/(m
  cp)`` the supply-air term ``m cp (Ts - Ti)`` is ``m cp (T_ahu - Ti) + P``, so a controller
  that sets the flow and the reheat power faces a model that is bilinear in the flow only;
* optionally a disturbance state (:mod:`rczone.control.disturbance`).

For a sample time ``dt`` and a constant flow ``m`` the continuous model is discretized exactly by
the project's one discretization module (:func:`~rczone.simulation.discretize.zoh`,
:func:`~rczone.simulation.discretize.process_noise_covariance`); without the appended parts
the matrices are those of :meth:`ZoneModel.discrete`. Their derivatives with respect to the
flow (:meth:`ControlModel.flow_derivative`, exact, by the Fréchet derivative of the
exponential) linearize the bilinear model for a sequential-linearization MPC.

References
----------
.. [1] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of Dynamic Systems*, 3rd
   ed., 1998, section 6.3 (zero-order hold).
.. [2] N. J. Higham, *Functions of Matrices*, SIAM, 2008, section 10.6 (Fréchet derivative
   of the exponential).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from rczone.control.disturbance import Disturbance
from rczone.control.noise import NoiseModel
from rczone.errors import InputShapeError, ParameterError, did_you_mean
from rczone.models.zone import ZoneModel
from rczone.simulation.discretize import process_noise_covariance, zoh, zoh_derivative


class ContinuousMatrices(NamedTuple):
    """``dx = (A0 + sum m_f N_f) x + (B0 + sum m_f M_f) u + E P + w``, ``y = C x + D u + v``."""

    A0: np.ndarray
    N: np.ndarray
    B0: np.ndarray
    M: np.ndarray
    E: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Qc: np.ndarray


class DiscreteMatrices(NamedTuple):
    """``x[k+1] = Ad x[k] + Bd u[k] + Ed P[k] + w[k]``, ``w ~ N(0, Qd)``; ``y = C x + D u + v``, ``v ~ N(0, R)``."""

    Ad: np.ndarray
    Bd: np.ndarray
    Ed: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Qd: np.ndarray
    R: np.ndarray


class FlowDerivative(NamedTuple):
    """Derivatives of ``Ad``, ``Bd``, ``Ed`` with respect to each flow, shapes (nf, n, ...), per kg/s."""

    dAd: np.ndarray
    dBd: np.ndarray
    dEd: np.ndarray


def _supply_heat_column(model: ZoneModel) -> np.ndarray:
    """Heat input (per W) at the node of the first supply-air element, shape (n,)."""
    net = model.network
    ss = model.state_space()
    if not net.supply_air:
        return np.zeros(ss.n_states)
    s = net.supply_air[0]
    cp = s.cp if isinstance(s.cp, (int, float)) else net.values(model.theta)[s.cp]
    f, ts = net.flow_names.index(s.flow), ss.input_names.index(s.temperature)
    # M_f[:, Ts] is cp/C at the node (spread over the states if the node is massless)
    return ss.M[f][:, ts] / float(cp)


class ControlModel:
    """A zone model with its noise, the supply-node heat input and an optional disturbance state.

    Parameters
    ----------
    model : ZoneModel
    disturbance : Disturbance, optional
    noise : NoiseModel, optional
        Default :meth:`NoiseModel.from_model`.
    """

    def __init__(
        self, model: ZoneModel, *, disturbance: Disturbance | None = None, noise: NoiseModel | None = None
    ) -> None:
        self.model = model
        self.disturbance = disturbance
        self.noise = noise or NoiseModel.from_model(model)
        ss = model.state_space()
        self.input_names = ss.input_names
        self.flow_names = ss.flow_names
        self.output_names = ss.output_names
        self.state_names = ss.state_names + ((disturbance.state_name,) if disturbance else ())
        self.matrices = self._augment(ss, _supply_heat_column(model), disturbance)
        self._discrete = lru_cache(maxsize=256)(self._discrete_uncached)
        self._derivative = lru_cache(maxsize=256)(self._derivative_uncached)

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    def _augment(self, ss, e: np.ndarray, dist: Disturbance | None) -> ContinuousMatrices:
        n, nf, p, ny = ss.n_states, ss.n_flows, ss.n_inputs, len(ss.output_names)
        if dist is None:
            return ContinuousMatrices(ss.A, ss.N, ss.B, ss.M, e[:, None], ss.C, ss.D, self.noise.Qc)
        na = n + 1
        A0 = np.zeros((na, na))
        A0[:n, :n] = ss.A
        A0[n, n] = -1.0 / dist.tau if dist.tau is not None else 0.0
        N = np.zeros((nf, na, na))
        N[:, :n, :n] = ss.N
        B0 = np.vstack([ss.B, np.zeros((1, p))])
        M = np.concatenate([ss.M, np.zeros((nf, 1, p))], axis=1)
        C = np.hstack([ss.C, np.zeros((ny, 1))])
        Qc = np.zeros((na, na))
        Qc[:n, :n] = self.noise.Qc
        Qc[n, n] = dist.intensity**2
        if dist.kind == "heat":
            node = dist.node or ss.output_names[0]
            if node not in ss.state_names:
                raise ParameterError(
                    f"disturbance node {node!r}: heat enters a capacitive node; "
                    + did_you_mean(node, ss.state_names)
                )
            i = ss.state_names.index(node)
            A0[i, n] = 1.0 / float(self.model.state_space().capacities[i])
        else:
            out = dist.node or ss.output_names[0]
            if out not in ss.output_names:
                raise ParameterError(f"disturbance output {out!r}: " + did_you_mean(out, ss.output_names))
            C[ss.output_names.index(out), n] = 1.0
        return ContinuousMatrices(A0, N, B0, M, np.append(e, 0.0)[:, None], C, ss.D, Qc)

    def _flows(self, m: float | np.ndarray) -> tuple[float, ...]:
        arr = np.atleast_1d(np.asarray(m, dtype=float))
        nf = len(self.flow_names)
        if arr.shape != (nf,) and not (nf == 0 and arr.shape == (1,) and arr[0] == 0.0):
            raise InputShapeError(
                f"flow m must have {nf} value(s) for {list(self.flow_names)}, got {arr.tolist()}"
            )
        if not np.all(np.isfinite(arr)) or np.any(arr < 0):
            raise InputShapeError(f"flow m must be finite and >= 0 kg/s, got {arr.tolist()}")
        return tuple(float(v) for v in arr[:nf])

    def _key(self, dt: float, m: float | np.ndarray) -> tuple[float, tuple[float, ...]]:
        """The validated cache key ``(dt, flows)``."""
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise InputShapeError(f"sample time dt must be finite and > 0 s, got {dt!r}")
        return float(dt), self._flows(m)

    def continuous(self, m: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(A(m), [B(m) | E])`` of the continuous model at flow ``m``."""
        mk = np.array(self._flows(m))
        c = self.matrices
        A = c.A0 + np.tensordot(mk, c.N, axes=1) if mk.size else c.A0
        B = c.B0 + np.tensordot(mk, c.M, axes=1) if mk.size else c.B0
        return A, np.hstack([B, c.E])

    def discrete(self, dt: float, m: float | np.ndarray) -> DiscreteMatrices:
        """Exact ZOH matrices and noise covariances for ``dt`` s at constant flow ``m`` (cached)."""
        return self._discrete(*self._key(dt, m))

    def _discrete_uncached(self, dt: float, m: tuple[float, ...]) -> DiscreteMatrices:
        A, BE = self.continuous(np.array(m))
        Ad, Gd = zoh(A, BE, dt)
        Qd = process_noise_covariance(A, self.matrices.Qc, dt) if np.any(self.matrices.Qc) else 0 * A
        p = self.matrices.B0.shape[1]
        return DiscreteMatrices(Ad, Gd[:, :p], Gd[:, p:], self.matrices.C, self.matrices.D, Qd, self.noise.R)

    def flow_derivative(self, dt: float, m: float | np.ndarray) -> FlowDerivative:
        """Exact derivatives of ``Ad``, ``Bd``, ``Ed`` with respect to each flow at ``(dt, m)``."""
        return self._derivative(*self._key(dt, m))

    def _derivative_uncached(self, dt: float, m: tuple[float, ...]) -> FlowDerivative:
        A, BE = self.continuous(np.array(m))
        c = self.matrices
        p = c.B0.shape[1]
        outs = [zoh_derivative(A, BE, c.N[f], np.hstack([c.M[f], 0 * c.E]), dt) for f in range(len(m))]
        dAd = np.array([o[0] for o in outs]).reshape(len(m), *A.shape)
        dG = np.array([o[1] for o in outs]).reshape(len(m), *BE.shape)
        return FlowDerivative(dAd, dG[:, :, :p], dG[:, :, p:])
