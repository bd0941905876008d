"""Exact simulation of bilinear RC models on sampled inputs.

The flows ``m`` are held constant over each sample interval (a VAV damper command);
the other inputs are held constant (``hold="zoh"``) or vary linearly (``hold="foh"``).
Within each interval the model is then LTI and is stepped exactly by the matrix
exponential. Discretizations are computed once per distinct ``(dt, m)`` pair, which
makes typical building data (m constant for long stretches, regular sampling) cheap.

For RC networks (``diag(c) (A + m N)`` symmetric, checked at run time) the distinct
discretizations are computed by the exact spectral formulas
(:func:`rczone.simulation.discretize.interval_discretization`: closed form for ``n <= 2``, a
symmetric eigen-decomposition otherwise) instead of one matrix exponential each; any other
state space uses the matrix exponential. The sample loop runs compiled
(:mod:`rczone.kernels.propagate`); its plain twin is in the tests (``tests/oracles.py``).

A symmetric 2-state model runs one compiled loop (:func:`rczone.kernels.rc2.simulate_rc2`:
the closed-form discretization at each interval that differs from the previous one, and the
steps), with no batching and no Python between the checks and the result.

When the flow changes at nearly every sample (more than :data:`FEW_KEYS` distinct
``(dt, m)``) and the model has one supply-air flow and three or more states,
:func:`simulate` instead steps the exact rank-one-update eigen-decomposition of
:mod:`rczone.kernels.rankone`, which costs ``O(n^2)`` per sample. Every path is exact to
rounding; they differ only in the last few bits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rczone.errors import InputShapeError
from rczone.kernels.arrays import writable
from rczone.network.statespace import BilinearStateSpace
from rczone.simulation.discretize import (
    SYMMETRY_RTOL,
    RankOneForm,
    interval_discretization,
    rank_one_form,
    symmetrizing_scale,
)
from rczone.simulation.intervals import interval_keys, unique_rows

HOLDS = ("zoh", "foh")
#: Up to this many distinct ``(dt, m)`` the batched per-key discretization beats per-sample updates.
FEW_KEYS = 32
#: Rank-one forms kept per state space (one per flow range simulated).
_FORMS_KEPT = 8


def check_time(t: np.ndarray) -> np.ndarray:
    """Validate a time vector (s): 1-D, finite, strictly increasing."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise InputShapeError(f"time must be a 1-D array of at least 2 samples, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InputShapeError(
            f"time has non-finite values at index {int(np.flatnonzero(~np.isfinite(t))[0])}"
        )
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

    def to_frame(self):
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
    uniq, _, which = unique_rows(interval_keys(t, m))
    Phi, G0, G1, _ = interval_discretization(ss.A, ss.N, ss.B, ss.M, ss.capacities, uniq, hold)
    return Phi, G0, G1, which


def propagate(
    Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray, which: np.ndarray, u: np.ndarray, x0: np.ndarray
) -> np.ndarray:
    """Step ``x[k+1] = Phi[w] x[k] + G0[w] u[k] + G1[w] u[k+1]`` with ``w = which[k]``.

    Pure array kernel, compiled (:func:`rczone.kernels.propagate.propagate_kernel`);
    returns states of shape ``(N, n)``.
    """
    # imported here: loading numba costs ~0.3 s, which commands that never simulate should not pay
    from rczone.kernels.propagate import propagate as propagate_compiled

    return propagate_compiled(Phi, G0, G1, which, u, x0)


def _rank_one_form_of(ss: BilinearStateSpace, m_max: float) -> RankOneForm | None:
    """:func:`rank_one_form` of ``ss`` for flows up to ``m_max``, kept on the (immutable) state space.

    The eigen-decomposition and deflation are a property of the model, not of the data: a
    model simulated again (MPC predictions, comparisons) reuses them. Up to
    :data:`_FORMS_KEPT` flow ranges are kept per state space.
    """
    kept = ss.__dict__.setdefault("_rank_one_forms", {})
    if m_max not in kept:
        scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
        if len(kept) >= _FORMS_KEPT:
            kept.pop(next(iter(kept)))
        kept[m_max] = None if scale is None else rank_one_form(ss.A, ss.N, scale, m_max)
    return kept[m_max]


def _simulate_rank_one(
    ss: BilinearStateSpace, t: np.ndarray, u: np.ndarray, m: np.ndarray, x0: np.ndarray, hold: str
) -> np.ndarray | None:
    """States by the compiled rank-one path (one flow, RC structure, n >= 3), or None if it does not apply.

    For two states and less the batched closed form is as fast; so it is when there are few
    distinct ``(dt, m)`` (at most :data:`FEW_KEYS`), each then decomposed once. A state space
    that is not an RC network, or with several flows, takes the general path.
    """
    if ss.n_flows != 1 or ss.n_states < 3 or hold not in HOLDS:
        return None
    if np.unique(m[:-1, 0]).size * np.unique(np.diff(t)).size <= FEW_KEYS:
        return None
    form = _rank_one_form_of(ss, float(np.max(np.abs(m))))
    if form is None:
        return None
    from rczone.kernels.rankone import simulate_rank_one  # numba loads lazily, see propagate

    return simulate_rank_one(form, ss.B, ss.M[0], t, m[:, 0], u, x0, hold)


def _float_array(a: object, shape: tuple[int, ...]) -> np.ndarray | None:
    """``a`` as a C-contiguous float64 array when it already is one of ``shape`` (no conversion), else None."""
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == shape:
        return writable(a)  # read-only data would compile the kernel a second time
    return None


def _simulate_rc2(
    ss: BilinearStateSpace, t: object, u: object, m: object, x0: object, hold: str
) -> SimulationResult | None:
    """The compiled 2-state simulation (:func:`rczone.kernels.rc2.simulate_rc2`), or None where it does not apply.

    It applies to a symmetric 2-state RC model given float64 arrays of the right shapes and
    inputs that the checks of :func:`simulate` accept (the kernel checks them itself and
    declines otherwise, so the general path reports the error). The model's arrays are made
    contiguous once and kept on the (immutable) state space: a model simulated in a loop (an
    MPC, an emulator) pays only the kernel.
    """
    if ss.n_states != 2 or hold not in HOLDS or not isinstance(t, np.ndarray) or t.ndim != 1 or t.size < 2:
        return None
    n = t.size
    ta = _float_array(t, (n,))
    ua = _float_array(u, (n, ss.n_inputs))
    ma = _float_array(m, (n, ss.n_flows)) if ss.n_flows else np.zeros((n, 0))
    xa = np.empty(0) if x0 is None else _float_array(x0, (2,))
    if ta is None or ua is None or ma is None or xa is None:
        return None
    arrays = ss.__dict__.get("_rc2_arrays")
    if arrays is None:
        arrays = ss.__dict__["_rc2_arrays"] = tuple(
            writable(a) for a in (ss.A, ss.N, ss.B, ss.M, ss.capacities, ss.C, ss.D)
        )
    from rczone.kernels.rc2 import simulate_rc2  # numba loads lazily, see propagate

    x = np.empty((n, 2))
    y = np.empty((n, ss.C.shape[0]))
    if simulate_rc2(*arrays, ta, ma, ua, xa, hold == "foh", SYMMETRY_RTOL, x, y) != 0:
        return None
    return SimulationResult(ta, x, y, ss.state_names, ss.output_names)


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

    Examples
    --------
    A room (``C = 1 MJ/K``) cooling through ``R = 0.01 K/W`` to 10 degC outdoors from 20 degC follows
    ``10 + 10 exp(-t / RC)`` exactly at the samples:

    >>> import numpy as np
    >>> from rczone.network import Node, Parameter, RCNetwork, Resistor
    >>> net = RCNetwork(
    ...     "room", nodes=[Node("Ti", "C")], boundaries=["To"], resistors=[Resistor("Ti", "To", "R")],
    ...     parameters=[Parameter("C", "capacitance", 1e6), Parameter("R", "resistance", 0.01)])
    >>> t = np.arange(0.0, 36000.0, 600.0)
    >>> res = simulate(net.state_space(), t, np.full((t.size, 1), 10.0), x0=np.array([20.0]))
    >>> bool(np.allclose(res.y[:, 0], 10 + 10 * np.exp(-t / (1e6 * 0.01))))
    True
    """
    fast = _simulate_rc2(ss, t, u, m, x0, hold)
    if fast is not None:
        return fast
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
            raise InputShapeError(
                f"x0 must have shape ({ss.n_states},) for states {list(ss.state_names)}, got {x0.shape}"
            )
    x = _simulate_rank_one(ss, t, u, m, x0, hold)
    if x is None:
        Phi, G0, G1, which = transition_matrices(ss, t, m, hold)
        x = propagate(Phi, G0, G1, which, u, x0)
    y = x @ ss.C.T + u @ ss.D.T
    return SimulationResult(t, x, y, ss.state_names, ss.output_names)
