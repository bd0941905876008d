"""Fisher information of RC parameters from output sensitivities, with nuisances marginalized.

Shared by :func:`rczone.diagnostics.diagnose` (what a data set can identify) and
:func:`rczone.diagnostics.design.design_test` (a test that identifies more). A fit must also absorb
directions it does not care about: the unknown initial state of every node, and an unknown constant
offset of every heat input that is only guessed (held at a constant). Their output responses are
linear in the nuisance values, so they are marginalized exactly by the Schur complement of their
block of the Fisher matrix [1]_.

Every output of a model counts: the sensitivities of all outputs are stacked, each output's missing
samples skipped. Output errors of a building model are correlated over tens of minutes, so a sample
carries the weight ``min(1, dt / correlation_time) / sigma^2`` (one independent sample per
correlation time).

References
----------
.. [1] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (Fisher information, nuisance parameters, experiment design).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rczone.errors import ParameterError, did_you_mean
from rczone.network import BilinearStateSpace, RCNetwork
from rczone.simulation import simulate


def check_free(network: RCNetwork, free: Sequence[str], values: Mapping[str, float] | None = None) -> None:
    """The parameters of an analysis in ``log(theta)``: known, base (not tied), and > 0 at ``values``."""
    for n in free:
        if n not in network.parameters:
            raise ParameterError(f"unknown free parameter {n!r}; " + did_you_mean(n, network.parameters))
        if network.parameters[n].is_tied:
            raise ParameterError(
                f"parameter {n!r} is tied ({n} = {network.parameters[n].expr}); name its base parameters"
            )
        if values is not None and not values[n] > 0:
            raise ParameterError(
                f"parameter {n!r} is {values[n]:g}; the analysis is in log({n}), so leave it out of free"
            )


def sample_weight(dt: float, sigma_K: float, correlation_time_s: float) -> float:
    """Fisher weight of one sample: ``min(1, dt / correlation_time_s) / sigma_K**2`` (1/K^2)."""
    return min(1.0, dt / correlation_time_s) / sigma_K**2


def nuisance_responses(
    ss: BilinearStateSpace,
    t: np.ndarray,
    u: np.ndarray,
    m: np.ndarray | None,
    offsets: Sequence[str] = (),
    initial_state: bool = True,
    hold: str = "zoh",
) -> tuple[np.ndarray, list[str]]:
    """Output responses to each unit initial state (zero inputs) and to a unit constant of each offset input.

    Parameters
    ----------
    ss : BilinearStateSpace
    t : ndarray, shape (N,)
    u : ndarray, shape (N, p)
    m : ndarray, shape (N, n_flows), or None
    offsets : sequence of str
        Inputs whose unknown constant offset is a nuisance.
    initial_state : bool
        Include the initial state of every node.
    hold : {"zoh", "foh"}
        Inputs between samples (:func:`rczone.simulation.simulate`).

    Returns
    -------
    responses : ndarray, shape (N, ny, k)
    names : list of str
        ``x0[<state>]`` and ``offset[<input>]``, the order of the last axis.
    """
    zero = np.zeros_like(u)
    mm = m if m is not None and m.shape[1] else None
    n = ss.n_states
    cols, names = [], []
    for i, s in enumerate(ss.state_names if initial_state else ()):
        cols.append(simulate(ss, t, zero, mm, x0=np.eye(n)[i], hold=hold).y)
        names.append(f"x0[{s}]")
    for h in offsets:
        uq = zero.copy()
        uq[:, ss.input_names.index(h)] = 1.0
        cols.append(simulate(ss, t, uq, mm, x0=np.zeros(n), hold=hold).y)
        names.append(f"offset[{h}]")
    if not cols:
        return np.zeros((t.size, ss.C.shape[0], 0)), names
    return np.stack(cols, axis=-1), names


def marginal_fisher(S: np.ndarray, nuisance: np.ndarray, weight: float) -> np.ndarray:
    """Fisher information of the parameters with the nuisance directions marginalized.

    Parameters
    ----------
    S : ndarray, shape (n, P)
        Stacked output sensitivities of the parameters.
    nuisance : ndarray, shape (n, k)
        Stacked output responses of the nuisances (``k`` may be 0).
    weight : float
        Weight of one sample (:func:`sample_weight`).

    Returns
    -------
    ndarray, shape (P, P)
        ``w (S'S - S'V (V'V)^+ V'S)``, the Schur complement of the nuisance block, computed as
        ``w (PS)'(PS)`` with ``PS`` the part of ``S`` the nuisances cannot absorb
        (:func:`project_out`, an orthogonal projection by least squares): the same matrix, positive
        semidefinite by construction, without the cancellation of the difference when a parameter's
        sensitivity lies almost in the nuisances' span (there the difference kept rounding errors
        larger than the result, and a verdict could flip with the last digits of the inputs).
    """
    R = project_out(S, nuisance)
    return weight * (R.T @ R)


def project_out(delta: np.ndarray, nuisance: np.ndarray) -> np.ndarray:
    """``delta`` minus its least-squares projection on the nuisance columns (what a fit cannot absorb)."""
    if nuisance.shape[1] == 0:
        return delta
    coef, *_ = np.linalg.lstsq(nuisance, delta, rcond=None)
    return delta - nuisance @ coef


def rms(x: np.ndarray) -> float:
    """Root mean square (0 for an empty array)."""
    return float(np.sqrt(np.mean(x**2))) if x.size else 0.0
