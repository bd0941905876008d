"""Initial states consistent with a measured output.

A simulation against measurements should start where the measurement starts. The walls'
temperatures are not measured; :func:`output_consistent_state` puts every unmeasured state
in equilibrium with the first inputs while the measured state is held at its measured
value, which is what a building that has been under steady control before the data start
looks like.
"""

from __future__ import annotations

import numpy as np

from rczone.errors import InputShapeError
from rczone.network.statespace import BilinearStateSpace


def output_consistent_state(
    ss: BilinearStateSpace, u0: np.ndarray, m0: np.ndarray | float, y0: float, output: int = 0
) -> np.ndarray:
    """State with the measured node at ``y0`` and the others in equilibrium.

    Parameters
    ----------
    ss : BilinearStateSpace
        Its output ``output`` must be a state (a row of ``C`` with a single 1 and ``D`` = 0).
    u0 : ndarray, shape (p,)
        Inputs at the first sample.
    m0 : float or ndarray, shape (n_flows,)
        Flows at the first sample.
    y0 : float
        Measured output at the first sample.

    Returns
    -------
    ndarray, shape (n,)
    """
    row = ss.C[output]
    j = int(np.argmax(np.abs(row)))
    if not (np.isclose(row[j], 1.0) and np.count_nonzero(row) == 1 and not np.any(ss.D[output])):
        raise InputShapeError("output_consistent_state needs an output that is a state of the model")
    A, B = ss.matrices(m0)
    rest = [i for i in range(ss.n_states) if i != j]
    x = np.empty(ss.n_states)
    x[j] = y0
    if rest:
        rhs = -(A[np.ix_(rest, [j])][:, 0] * y0 + B[rest] @ np.asarray(u0, dtype=float))
        x[rest] = np.linalg.solve(A[np.ix_(rest, rest)], rhs)
    return x
