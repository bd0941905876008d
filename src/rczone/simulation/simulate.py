"""Exact simulation of bilinear RC models on sampled inputs.

The flows ``m`` are held constant over each sample interval (a VAV damper command);
the other inputs are held constant (``hold="zoh"``) or vary linearly (``hold="foh"``).
Within each interval the model is then LTI and is stepped exactly by the matrix
exponential. Discretizations are computed once per distinct ``(dt, m)`` pair, which
makes typical building data (m constant for long stretches, regular sampling) cheap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rczone.errors import InputShapeError
from rczone.network.statespace import BilinearStateSpace
from rczone.simulation.discretize import foh, zoh

HOLDS = ("zoh", "foh")


def check_time(t: np.ndarray) -> np.ndarray:
    """Validate a time vector (s): 1-D, finite, strictly increasing."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise InputShapeError(f"time must be a 1-D array of at least 2 samples, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InputShapeError(f"time has non-finite values at index {int(np.flatnonzero(~np.isfinite(t))[0])}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0])
        raise InputShapeError(
            f"time must be strictly increasing: t[{k + 1}] = {t[k + 1]:g} s follows t[{k}] = {t[k]:g} s"
        )
    return t


def check_inputs(arr: np.ndarray, n_samples: int, names: tuple[str, ...], what: str) -> np.ndarray:
    """Validate a time-first input array of shape ``(n_samples, len(names))``.

    A 1-D array is accepted when there is exactly one channel.
    """
    arr = np.asarray(arr, dtype=float)
    if arr.ndim == 1 and len(names) == 1:
        arr = arr[:, None]
    if arr.shape != (n_samples, len(names)):
        raise InputShapeError(
            f"{what} must have shape (n_samples, {len(names)}) = ({n_samples}, {len(names)}) for"
            f" columns {list(names)}, got {arr.shape}"
        )
    bad = ~np.isfinite(arr)
    if bad.any():
        k, j = (int(i) for i in np.argwhere(bad)[0])
        raise InputShapeError(f"{what} column {names[j]!r} is not finite at sample {k}")
    return arr


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """States and outputs of a simulation at the sample times.

    Attributes
    ----------
    t : ndarray, shape (N,)
    x : ndarray, shape (N, n)
    y : ndarray, shape (N, ny)
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    state_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def to_frame(self):  # noqa: ANN201 - pandas is imported lazily
        """States and outputs as a :class:`pandas.DataFrame` indexed by time (s)."""
        import pandas as pd

        cols = {n: self.x[:, i] for i, n in enumerate(self.state_names)}
        for i, n in enumerate(self.output_names):
            cols.setdefault(n, self.y[:, i])
        return pd.DataFrame(cols, index=pd.Index(self.t, name="time_s"))


def steady_state(ss: BilinearStateSpace, u: np.ndarray, m: np.ndarray | float = 0.0) -> np.ndarray:
    """State in equilibrium with constant inputs ``u`` (shape (p,)) and flows ``m``."""
    A, B = ss.matrices(m)
    return np.linalg.solve(A, -B @ np.asarray(u, dtype=float))


def transition_matrices(
    ss: BilinearStateSpace, t: np.ndarray, m: np.ndarray, hold: str = "zoh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per-interval discrete matrices, computed once per distinct ``(dt, m)``.

    Returns
    -------
    Phi : ndarray, shape (K, n, n)
    G0, G1 : ndarray, shape (K, n, p)
        Input matrices applied to ``u[k]`` and ``u[k+1]`` (``G1`` is zero for ZOH).
    which : ndarray of int, shape (N-1,)
        Index into the first axis for each interval.
    """
    if hold not in HOLDS:
        raise InputShapeError(f"hold must be one of {HOLDS}, got {hold!r}")
    dt = np.diff(t)
    key = np.column_stack([dt, m[:-1]])
    uniq, which = np.unique(key, axis=0, return_inverse=True)
    n, p = ss.n_states, ss.n_inputs
    K = uniq.shape[0]
    Phi = np.empty((K, n, n))
    G0 = np.empty((K, n, p))
    G1 = np.zeros((K, n, p))
    for k in range(K):
        A, B = ss.matrices(uniq[k, 1:]) if ss.n_flows else (ss.A, ss.B)
        if hold == "zoh":
            Phi[k], G0[k] = zoh(A, B, uniq[k, 0])
        else:
            Phi[k], G0[k], G1[k] = foh(A, B, uniq[k, 0])
    return Phi, G0, G1, which.reshape(-1)


def propagate(
    Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray, x0: np.ndarray
) -> np.ndarray:
    """Step ``x[k+1] = Phi[w] x[k] + G0[w] u[k] + G1[w] u[k+1]`` with ``w = which[k]``.

    Pure array kernel; returns states of shape ``(N, n)``.
    """
    N = u.shape[0]
    x = np.empty((N, x0.shape[0]))
    x[0] = x0
    for k in range(N - 1):
        w = which[k]
        x[k + 1] = Phi[w] @ x[k] + G0[w] @ u[k] + G1[w] @ u[k + 1]
    return x


def simulate(
    ss: BilinearStateSpace,
    t: np.ndarray,
    u: np.ndarray,
    m: np.ndarray | None = None,
    x0: np.ndarray | None = None,
    hold: str = "zoh",
) -> SimulationResult:
    """Simulate a bilinear state space exactly on sampled inputs.

    Parameters
    ----------
    ss : BilinearStateSpace
    t : ndarray, shape (N,)
        Sample times, s, strictly increasing (irregular spacing allowed).
    u : ndarray, shape (N, p)
        Inputs in the order of ``ss.input_names``.
    m : ndarray, shape (N, n_flows), optional
        Mass flows, kg/s, held constant from ``t[k]`` to ``t[k+1]``. Required when the
        model has flows.
    x0 : ndarray, shape (n,), optional
        Initial state; default the steady state for ``u[0]`` and ``m[0]``.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of ``u``.

    Returns
    -------
    SimulationResult
    """
    t = check_time(t)
    u = check_inputs(u, t.size, ss.input_names, "u")
    if ss.n_flows:
        if m is None:
            raise InputShapeError(f"this model has flow input(s) {list(ss.flow_names)}; pass m")
        m = check_inputs(m, t.size, ss.flow_names, "m")
    else:
        m = np.zeros((t.size, 0))
    if x0 is None:
        x0 = steady_state(ss, u[0], m[0])
    else:
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (ss.n_states,):
            raise InputShapeError(f"x0 must have shape ({ss.n_states},) for states {list(ss.state_names)}, got {x0.shape}")
    Phi, G0, G1, which = transition_matrices(ss, t, m, hold)
    x = propagate(Phi, G0, G1, which, u, x0)
    y = x @ ss.C.T + u @ ss.D.T
    return SimulationResult(t, x, y, ss.state_names, ss.output_names)
