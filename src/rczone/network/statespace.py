"""Named continuous-time state spaces: the bilinear model and its LTI slices.

.. math::

    \\dot x = (A + \\textstyle\\sum_k m_k N_k)\\,x + (B + \\textstyle\\sum_k m_k M_k)\\,u,
    \\qquad y = C x + D u

For a constant flow vector ``m`` the model is LTI (Lin et al. 2012, eq. (5)), see
:meth:`BilinearStateSpace.lti`.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rczone.errors import InputShapeError


class StateSpaceDerivative(NamedTuple):
    """Derivatives of the bilinear state-space matrices with respect to one parameter."""

    dA: np.ndarray
    dN: np.ndarray
    dB: np.ndarray
    dM: np.ndarray
    dC: np.ndarray
    dD: np.ndarray
    dQ: np.ndarray | None = None
    """Derivative of :attr:`BilinearStateSpace.diffusion` (None: zero)."""


def _flows(m: float | Sequence[float] | np.ndarray, nf: int) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(m, dtype=float))
    if arr.shape != (nf,):
        raise InputShapeError(f"flow must have {nf} value(s) (one per flow input), got shape {arr.shape}")
    return arr


@dataclass(frozen=True, eq=False)
class LinearStateSpace:
    """An LTI state space ``dx/dt = A x + B u, y = C x + D u`` with named signals.

    Attributes
    ----------
    A : ndarray, shape (n, n), 1/s
    B : ndarray, shape (n, p)
    C : ndarray, shape (ny, n)
    D : ndarray, shape (ny, p)
    state_names, input_names, output_names : tuple of str
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def dc_gain(self) -> np.ndarray:
        """Steady-state gain ``D - C A^{-1} B``, shape (ny, p)."""
        return self.D - self.C @ np.linalg.solve(self.A, self.B)

    def input_index(self, name: str) -> int:
        """Column of input ``name``."""
        from rczone.errors import InputShapeError, did_you_mean

        try:
            return self.input_names.index(name)
        except ValueError:
            raise InputShapeError(
                f"unknown input {name!r}; " + did_you_mean(name, self.input_names)
            ) from None


@dataclass(frozen=True, eq=False)
class BilinearStateSpace:
    """The bilinear state space of an RC network with supply-air flows.

    Attributes
    ----------
    A : ndarray, shape (n, n)
        State matrix at zero flow, 1/s.
    N : ndarray, shape (n_flows, n, n)
        State-matrix change per unit flow, 1/(kg).
    B : ndarray, shape (n, p)
        Input matrix at zero flow.
    M : ndarray, shape (n_flows, n, p)
        Input-matrix change per unit flow.
    C, D : ndarray
        Output matrices (``D`` is non-zero when an output is a massless node).
    capacities : ndarray, shape (n,)
        Heat capacity of each state node, J/K (for energy balances); NaN for the latent states of
        a disturbance (:mod:`rczone.network.disturbance`).
    diffusion : ndarray, shape (n,), optional
        Diffusion intensity each state has by declaration (variance per second): the latent
        states' Gaussian-process SDEs; zero for the nodes. Added to the estimation's process noise
        ``sigma_w_<state>**2``. Default: zeros.
    """

    A: np.ndarray
    N: np.ndarray
    B: np.ndarray
    M: np.ndarray
    C: np.ndarray
    D: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    flow_names: tuple[str, ...]
    output_names: tuple[str, ...]
    capacities: np.ndarray
    diffusion: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.diffusion is None:
            object.__setattr__(self, "diffusion", np.zeros(self.A.shape[0]))

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.B.shape[1]

    @property
    def n_flows(self) -> int:
        return self.N.shape[0]

    def matrices(self, m: float | Sequence[float] | np.ndarray = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """``(A + sum m_k N_k, B + sum m_k M_k)`` for a constant flow vector ``m``."""
        if self.n_flows == 0:
            return self.A, self.B
        mk = _flows(m, self.n_flows)
        if mk.shape[0] == 1:  # one flow (the usual zone): no tensordot overhead
            return self.A + mk[0] * self.N[0], self.B + mk[0] * self.M[0]
        return (
            self.A + np.tensordot(mk, self.N, axes=1),
            self.B + np.tensordot(mk, self.M, axes=1),
        )

    def lti(self, m: float | Sequence[float] | np.ndarray = 0.0) -> LinearStateSpace:
        """The LTI model at constant flow ``m`` (kg/s), Lin et al. 2012, eq. (5)."""
        A, B = self.matrices(m)
        return LinearStateSpace(A, B, self.C, self.D, self.state_names, self.input_names, self.output_names)
