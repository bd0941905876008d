"""The MPC's quadratic program in condensed form: the decisions only, the states eliminated.

A linear time-varying prediction over ``H`` steps,

.. math::

    x_{k+1} = A_k x_k + \\sum_j b_{j,k} d_{j,k} + c_k, \\qquad y_{k} = C x_k + (\\text{known}),

gives every output as an affine function of the decisions, ``y_{k+1} = f_k + Y_k z`` (the
prediction matrices of Maciejowski [1]_, section 3.1, here time-varying). With the states
eliminated the QP has ``(r + 1) H`` variables (``r`` decisions and one comfort slack per step)
instead of ``(n + r + 1) H``, and no equality constraints: for the 13-state zone model the
operator-splitting solver needs tens of iterations instead of thousands, since the dynamics'
equality rows with their widely spread time constants are what slow it down. Jerez, Kerrigan
and Constantinides [2]_ compare the two forms: the condensed one is the smaller for long state
vectors and short horizons, the case of a zone model and a 6-h horizon.

The constraint matrix has one sparsity pattern for every step (a decision at step ``j``
reaches the outputs from ``j + 1`` on: lower-triangular blocks, explicit zeros kept), so the
solver is set up once and later steps only update its vectors and matrix values
(:class:`CondensedSolver`; OSQP's ``update``, Stellato et al. [3]_, section 5.3), warm-started
from the last solution.

References
----------
.. [1] J. M. Maciejowski, *Predictive Control with Constraints*, Prentice Hall, 2002.
.. [2] J. L. Jerez, E. C. Kerrigan, G. A. Constantinides, "A condensed and sparse QP formulation
   for predictive control", 50th IEEE Conference on Decision and Control (2011) 5217-5222.
.. [3] B. Stellato, G. Banjac, P. Goulart, A. Bemporad, S. Boyd, "OSQP: an operator splitting
   solver for quadratic programs", Mathematical Programming Computation 12 (2020) 637-672.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp


class QPMatrices(NamedTuple):
    """The sparse QP ``min 1/2 z'Pz + q'z, lower <= Az <= upper`` as OSQP takes it."""

    P: sp.csc_matrix  #: upper triangle of the quadratic term
    q: np.ndarray  #: linear term
    A: sp.csc_matrix  #: constraint matrix
    lower: np.ndarray
    upper: np.ndarray


class Decision(NamedTuple):
    """One decision over the horizon, in the units the QP sees (e.g. kg/s, kW).

    ``effect[k]`` (n,) is the change of ``x_{k+1}`` per unit of the decision at step ``k``;
    ``cost`` (H,) its linear cost; ``lower``, ``upper`` (H,) its bounds; ``previous`` the value
    applied last (the first move's reference).
    """

    effect: np.ndarray
    cost: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    previous: float


class Prediction(NamedTuple):
    """``x_{k+1} = Ad[k] x_k + c[k] + decisions`` from ``x0``; the output row ``C`` (n,)."""

    Ad: np.ndarray
    c: np.ndarray
    x0: np.ndarray
    C: np.ndarray


class Band(NamedTuple):
    """The soft output band at steps 1..H and the output's linear cost there, (H,) each.

    ``lower``, ``upper`` are for ``C x_k`` (the known part of the output already subtracted);
    ``output_cost`` is a linear cost on ``C x_k`` (e.g. the cooling load's tangent).
    """

    lower: np.ndarray
    upper: np.ndarray
    output_cost: np.ndarray


class Weights(NamedTuple):
    """Slack cost per K and per K^2, and the move penalty per unit^2 of every decision."""

    slack: float
    slack_quadratic: float
    move: float


class Coupling(NamedTuple):
    """``z_a[k] - coef[k] z_b[k] <= 0`` at every step, ``a``, ``b`` decision indices (a reheat limit)."""

    a: int
    b: int
    coef: np.ndarray


class Response(NamedTuple):
    """Outputs at steps 1..H: ``free`` (H,) with every decision at zero, ``Y`` (H, r H) per decision."""

    free: np.ndarray
    Y: np.ndarray


def response(pred: Prediction, decisions: Sequence[Decision]) -> Response:
    """The outputs' affine dependence on the decisions ``z = [d_1 (H), ..., d_r (H)]``."""
    H, n = pred.c.shape
    r = len(decisions)
    f = np.asarray(pred.x0, float)
    X = np.zeros((n, r * H))
    free, Y = np.empty(H), np.empty((H, r * H))
    for k in range(H):
        f = pred.Ad[k] @ f + pred.c[k]
        X = pred.Ad[k] @ X
        for j, d in enumerate(decisions):
            X[:, j * H + k] += d.effect[k]
        free[k] = pred.C @ f
        Y[k] = pred.C @ X
    return Response(free, Y)


def _pattern(H: int, r: int, couplings: Sequence[Coupling]) -> np.ndarray:
    """The structural non-zeros of the constraint matrix (the same at every step)."""
    tri = np.tril(np.ones((H, H), bool))
    eye = np.eye(H, dtype=bool)
    band = np.hstack([np.hstack([tri] * r), eye])
    rows = [band, band, np.eye(r * H, (r + 1) * H, dtype=bool)]
    for cp in couplings:
        rows.append(
            np.eye(H, (r + 1) * H, cp.a * H, dtype=bool) | np.eye(H, (r + 1) * H, cp.b * H, dtype=bool)
        )
    rows.append(np.eye(H, (r + 1) * H, r * H, dtype=bool))
    return np.vstack(rows)


def _csc(dense: np.ndarray, mask: np.ndarray) -> sp.csc_matrix:
    """``dense`` restricted to ``mask``, explicit zeros kept (so that the pattern never changes)."""
    cols, rows = np.nonzero(mask.T)  # column-major: the CSC order
    indptr = np.r_[0, np.cumsum(np.bincount(cols, minlength=mask.shape[1]))]
    return sp.csc_matrix((dense[rows, cols], rows, indptr), shape=mask.shape)


def condensed_qp(
    pred: Prediction,
    decisions: Sequence[Decision],
    band: Band,
    weights: Weights,
    couplings: Sequence[Coupling] = (),
) -> QPMatrices:
    """The condensed QP in ``z = [d_1 (H), ..., d_r (H), s (H)]`` (see the module notes)."""
    H = len(band.lower)
    r = len(decisions)
    nz = (r + 1) * H
    resp = response(pred, decisions)
    eye = np.eye(H)
    A = [np.hstack([resp.Y, eye]), np.hstack([resp.Y, -eye]), np.eye(r * H, nz)]
    for cp in couplings:
        row = np.zeros((H, nz))
        row[:, cp.a * H : (cp.a + 1) * H] = eye
        row[:, cp.b * H : (cp.b + 1) * H] = -np.diag(cp.coef)
        A.append(row)
    A.append(np.eye(H, nz, r * H))
    inf, zero = np.full(H, np.inf), np.zeros(H)
    nc = len(couplings)
    lo = [band.lower - resp.free, -inf, *(d.lower for d in decisions), *[-inf] * nc, zero]
    hi = [inf, band.upper - resp.free, *(d.upper for d in decisions), *[zero] * nc, inf]
    q = np.concatenate([d.cost for d in decisions] + [np.full(H, weights.slack)])
    q[: r * H] += band.output_cost @ resp.Y
    for j, d in enumerate(decisions):
        q[j * H] -= 2 * weights.move * d.previous
    D = sp.diags([np.ones(H), -np.ones(H - 1)], [0, -1], shape=(H, H))
    M2 = 2 * weights.move * (D.T @ D)
    P = sp.block_diag([M2] * r + [2 * weights.slack_quadratic * sp.eye(H)], format="csc")
    mask = _pattern(H, r, couplings)
    return QPMatrices(
        sp.triu(P, format="csc"), q, _csc(np.vstack(A), mask), np.concatenate(lo), np.concatenate(hi)
    )


#: OSQP's settings for the MPC's QPs (both forms).
OSQP_SETTINGS = {
    "verbose": False,
    "eps_abs": 1e-5,
    "eps_rel": 1e-5,
    "max_iter": 20000,
    "polishing": True,
}


class CondensedSolver:
    """One OSQP problem set up once; later QPs of the same pattern only update it (module notes)."""

    def __init__(self, osqp: Any) -> None:
        self._osqp = osqp
        self._solver: Any = None
        self._shape: tuple[int, int] | None = None

    def solve(self, qp: QPMatrices, warm: np.ndarray | None = None) -> Any:
        """OSQP's result for ``qp``, started from ``warm`` (or from the last solution)."""
        shape = (qp.A.shape, qp.A.nnz, qp.P.nnz)
        if self._solver is None or shape != self._shape:
            self._solver = self._osqp.OSQP()
            self._solver.setup(qp.P, qp.q, qp.A, qp.lower, qp.upper, **OSQP_SETTINGS)
            self._shape = shape
        else:
            self._solver.update(q=qp.q, l=qp.lower, u=qp.upper, Px=qp.P.data, Ax=qp.A.data)
        if warm is not None:
            self._solver.warm_start(x=warm)
        return self._solver.solve(raise_error=False)
