"""Exact output sensitivities to parameters (forward sensitivity equations).

For a parameter ``eta_j`` (by default ``log theta_j``) the sensitivity ``s_j = dx/deta_j``
obeys

.. math::

    \\dot s_j = A(m) s_j + A_j'(m) x + B_j'(m) u, \\qquad
    \\partial y / \\partial \\eta_j = C s_j + C_j' x + D_j' u ,

with ``A(m) = A + m N`` and primes the exact matrix derivatives of
:meth:`rczone.network.RCNetwork.state_space_derivatives`. State and sensitivities form one
block-lower-triangular linear system per sample interval that is stepped exactly with the
same discretization as the simulation, so the sensitivities are exact for the sampled model
(no finite differences of simulated outputs).

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., 1999, sec. 10.3.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rczone.errors import InputShapeError
from rczone.network import BilinearStateSpace, RCNetwork
from rczone.simulation.simulate import check_inputs, check_time, propagate, steady_state, transition_matrices


@dataclass(frozen=True, eq=False)
class Sensitivities:
    """Outputs and their sensitivities at the sample times.

    Attributes
    ----------
    y : ndarray, shape (N, ny)
    dy : ndarray, shape (N, ny, P)
        ``dy[k, i, j] = d y_i(t_k) / d eta_j``.
    names : tuple of str
        Parameter names in the order of the last axis of ``dy``.
    log : bool
        True when ``eta = log(theta)``.
    """

    t: np.ndarray
    y: np.ndarray
    dy: np.ndarray
    names: tuple[str, ...]
    log: bool


def output_sensitivities(
    network: RCNetwork,
    theta: Mapping[str, float] | None,
    wrt: Sequence[str],
    t: np.ndarray,
    u: np.ndarray,
    m: np.ndarray | None = None,
    x0: np.ndarray | None = None,
    hold: str = "zoh",
    log: bool = True,
) -> Sensitivities:
    """Simulate ``network`` and return exact output sensitivities to the parameters ``wrt``.

    Parameters
    ----------
    network, theta : the model and its base parameter values.
    wrt : sequence of str
        Base parameters to differentiate with respect to.
    t, u, m, hold : as in :func:`rczone.simulation.simulate`.
    x0 : ndarray, shape (n,), optional
        Fixed initial state (zero sensitivity). Default: the steady state for the first
        inputs, whose sensitivity ``-A^{-1}(A' x0 + B' u0)`` is included.
    log : bool
        Differentiate with respect to ``log(theta_j)`` (default) or ``theta_j``.

    Returns
    -------
    Sensitivities
    """
    ss = network.state_space(theta)
    ders = network.state_space_derivatives(theta, wrt, log=log)
    t = check_time(t)
    u = check_inputs(u, t.size, ss.input_names, "u")
    if ss.n_flows:
        if m is None:
            raise InputShapeError(f"this model has flow input(s) {list(ss.flow_names)}; pass m")
        m = check_inputs(m, t.size, ss.flow_names, "m")
    else:
        m = np.zeros((t.size, 0))
    n, P = ss.n_states, len(ders)
    if x0 is None:
        x0 = steady_state(ss, u[0], m[0])
        A0, _ = ss.matrices(m[0])
        dx0 = [
            -np.linalg.solve(
                A0, (d.dA + np.tensordot(m[0], d.dN, 1)) @ x0 + (d.dB + np.tensordot(m[0], d.dM, 1)) @ u[0]
            )
            for d in ders
        ]
    else:
        x0 = np.asarray(x0, float)
        if x0.shape != (n,):
            raise InputShapeError(f"x0 must have shape ({n},), got {x0.shape}")
        dx0 = [np.zeros(n)] * P
    big = n * (1 + P)
    nf, p = ss.n_flows, ss.n_inputs
    A = np.zeros((big, big))
    N = np.zeros((nf, big, big))
    B = np.zeros((big, p))
    M = np.zeros((nf, big, p))
    A[:n, :n], N[:, :n, :n], B[:n], M[:, :n] = ss.A, ss.N, ss.B, ss.M
    for j, d in enumerate(ders):
        r = slice(n * (j + 1), n * (j + 2))
        A[r, r], N[:, r, r] = ss.A, ss.N
        A[r, :n], N[:, r, :n] = d.dA, d.dN
        B[r], M[:, r] = d.dB, d.dM
    aug = BilinearStateSpace(
        A,
        N,
        B,
        M,
        np.zeros((0, big)),
        np.zeros((0, p)),
        ("",) * big,
        ss.input_names,
        ss.flow_names,
        (),
        np.ones(big),
    )
    Phi, G0, G1, which = transition_matrices(aug, t, m, hold)
    z = propagate(Phi, G0, G1, which, u, np.concatenate([x0, *dx0]))
    x = z[:, :n]
    y = x @ ss.C.T + u @ ss.D.T
    dy = np.empty((t.size, ss.C.shape[0], P))
    for j, d in enumerate(ders):
        s = z[:, n * (j + 1) : n * (j + 2)]
        dy[:, :, j] = s @ ss.C.T + x @ d.dC.T + u @ d.dD.T
    return Sensitivities(t, y, dy, tuple(wrt), log)
