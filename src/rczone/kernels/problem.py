"""Compiled cost and gradient of a packed estimation problem: from parameter values to ``J`` in one call.

For a network in conductance form (every node capacitive, numeric ``cp``)
whose resistances, capacities, noise levels and initial states are each a constant or
proportional to one free parameter, and whose heat-input gains are affine in them (the packing is
:func:`rczone.estimation.compiled.compiled_problem`), :func:`evaluate`

* maps ``theta`` to the element values (``k * theta[i]`` or a constant) and assembles
  ``A = -diag(1/c) L' diag(1/R) L``, ``B = diag(1/c) (P' diag(1/R) E + Gb)``,
  ``N = diag(1/c) Nf``, ``M = diag(1/c) Mf`` (:attr:`rczone.network.RCNetwork.conductance_form`),
  with heat-input gains affine in ``theta``, ``Gb = Gb0 + sum_t k_t theta[idx_t] e_i e_j'`` (a
  circuit's shares and its last share ``1 - s_1 - ...``; :class:`rczone.kernels.arrays.Slots`),
  and, for the gradient, their exact derivatives (``dA/dR_k = diag(1/c) L_k' L_k / R_k^2``;
  a capacity scales its row; a gain term adds ``k_t / c_i`` to ``dB[i, j]``);
* starts the measured states at their first measurement and the others at the steady state
  given them (as :func:`rczone.estimation.costs.auto_initial_state`), unless ``x0`` values
  are given, and differentiates that too;
* discretizes each distinct interval (:mod:`rczone.kernels.discretize`) and runs the filter
  (:func:`rczone.kernels.kalman.kalman_filter`) with forward sensitivities; for values only,
  the fused 2-state kernel (:func:`rczone.kernels.rc2.nll_rc2`) where it applies, and the
  filter in modal coordinates (``basis`` of :func:`rczone.kernels.kalman.kalman_filter`) for
  three or more states whose intervals rarely change (:func:`rczone.kernels.kalman.modal_pays`);
* returns ``J_LS`` (trapezoid rule on the open-loop errors, K^2 s), ``J_ML`` (``-log L``) or
  ``J_MAP`` (tempered likelihood plus log-normal prior) and its gradient in ``theta``.

Each path is a compiled entry point of its own, chosen in Python: :func:`value_fused` (values,
fused 2-state kernel), :func:`value_general` (values, modal or general filter) and
:func:`value_and_gradient` (filter with sensitivities); :func:`value_kernel` names the value
kernel of a problem. numba links every callee into each function it compiles and optimizes the
whole, so one function holding all paths cost every command the compile time of all of them.

The problem is a :class:`rczone.kernels.arrays.Problem` of contiguous float64 / int64 / bool
arrays: the kind (LS, ML or MAP), the conductance form, the data with its distinct intervals, the
slots of every element, noise level and initial state, the direct search's box, the MAP prior, the
settings, and a scratch buffer for the fused open-loop errors.

A slot ``(idx, k)`` has the value ``k * theta[idx]``, or ``k`` when ``idx < 0``.

References
----------
.. [1] J. R. R. A. Martins, P. Sturdza, J. J. Alonso, "The complex-step derivative
   approximation", ACM Trans. Math. Software 29(3), 2003 (used by the tests of the gradient).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba._dispatcher import compute_fingerprint

from rczone.kernels.arrays import (
    Assembled,
    AssembledDerivatives,
    ConductanceArrays,
    Discretization,
    ElementValues,
    FilterOptions,
    FilterStart,
    Observation,
    Series,
    Slots,
    Start,
)
from rczone.kernels.discretize import modal_matrices, rc_interval_derivatives, rc_interval_matrices
from rczone.kernels.expm import lu_factor, lu_solve
from rczone.kernels.kalman import kalman_filter, modal_pays, no_sensitivities, outputs
from rczone.kernels.rc2 import nll_rc2

#: Problem kinds.
LS, ML, MAP = 0, 1, 2

#: Prior families of a packed :class:`rczone.kernels.arrays.Penalty`.
LOGNORMAL, NORMAL, UNIFORM = 0, 1, 2

_LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True, error_model="numpy")
def _slot(theta: np.ndarray, idx: int, k: float) -> float:
    return k * theta[idx] if idx >= 0 else k


@njit(cache=True, error_model="numpy")
def theta_of_z(z: np.ndarray, lo: np.ndarray, hi: np.ndarray, logp: np.ndarray) -> np.ndarray:
    """Physical values from direct-search variables (bounds enforced by the transform)."""
    theta = np.empty(z.shape[0])
    for i in range(z.shape[0]):
        eta = lo[i] + (hi[i] - lo[i]) * (0.5 * (1.0 + math.tanh(0.5 * z[i])))
        theta[i] = math.exp(eta) if logp[i] else eta
    return theta


@njit(cache=True, error_model="numpy")
def conductances(
    L: np.ndarray, P: np.ndarray, E: np.ndarray, Gb0: np.ndarray, res: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The conductance matrices of an RC network: ``G = L' diag(1/R) L``, ``Gb = P' diag(1/R) E + Gb0``.

    The one assembly of the network's energy balance ``c dT/dt = -G T + Gb u`` (nodal analysis [1]_):
    :func:`assemble` scales it to ``A, B`` for the compiled costs, and
    :meth:`rczone.network.RCNetwork.state_space` eliminates massless nodes from it first. Real or
    complex ``res`` (complex-step derivatives); the result has its type.

    Parameters
    ----------
    L : ndarray, shape (nr, nn)
        Incidence of the resistors on the nodes (+1, -1; one +1 for a resistor to a boundary).
    P : ndarray, shape (nr, nn)
        The node end of each resistor to a boundary.
    E : ndarray, shape (nr, p)
        The boundary input at the other end.
    Gb0 : ndarray, shape (nn, p)
        Heat-input gains given as numbers (W per unit input).
    res : ndarray, shape (nr,)
        Resistances, K/W.

    Returns
    -------
    G : ndarray, shape (nn, nn)
        W/K.
    Gb : ndarray, shape (nn, p)

    References
    ----------
    .. [1] F. Doerfler, F. Bullo, "Kron reduction of graphs with applications to electrical
       networks", IEEE Trans. Circuits Syst. I, 60(1), 2013, section II (the loopy Laplacian).
    """
    nr, n = L.shape
    p = E.shape[1]
    G = np.zeros((n, n), dtype=res.dtype)
    Gb = np.zeros((n, p), dtype=res.dtype)
    for k in range(nr):
        g = 1.0 / res[k]
        for i in range(n):
            if L[k, i] != 0.0:
                for j in range(n):
                    G[i, j] += L[k, i] * g * L[k, j]
            if P[k, i] != 0.0:
                for j in range(p):
                    Gb[i, j] += P[k, i] * g * E[k, j]
    for i in range(n):
        for j in range(p):
            Gb[i, j] += Gb0[i, j]
    return G, Gb


@njit(cache=True, error_model="numpy")
def assemble(form: ConductanceArrays, res, cap) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A0, N, B0, M)`` of the conductance form for resistor values ``res`` and capacities ``cap``.

    ``A0 = -G / c``, ``B0 = Gb / c`` (rows divided by the capacities) of :func:`conductances`,
    ``N = Nf / c``, ``M = Mf / c``.

    Parameters
    ----------
    form : ConductanceArrays
        The network in conductance form.
    res : ndarray, shape (nr,)
        Resistances, K/W.
    cap : ndarray, shape (n,)
        Capacities, J/K.

    Returns
    -------
    A0, N, B0, M : ndarray, shapes (n, n), (nf, n, n), (n, p), (nf, n, p)
    """
    Nf, Mf = form.Nf, form.Mf
    n = form.L.shape[1]
    p = form.E.shape[1]
    nf = Nf.shape[0]
    A0, B0 = conductances(form.L, form.P, form.E, form.Gb0, res)  # scaled in place below
    N = np.empty((nf, n, n))
    M = np.empty((nf, n, p))
    for i in range(n):
        for j in range(n):
            A0[i, j] = -A0[i, j] / cap[i]
        for j in range(p):
            B0[i, j] = B0[i, j] / cap[i]
        for f in range(nf):
            for j in range(n):
                N[f, i, j] = Nf[f, i, j] / cap[i]
            for j in range(p):
                M[f, i, j] = Mf[f, i, j] / cap[i]
    return A0, N, B0, M


@njit(cache=True, error_model="numpy")
def assemble_derivatives(
    form: ConductanceArrays, slots: Slots, res: np.ndarray, mod: Assembled, q: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Derivatives of ``(A0, N, B0, M)`` with respect to ``theta[0..q-1]`` through the element slots.

    Parameters
    ----------
    form : ConductanceArrays
        The network in conductance form.
    slots : Slots
        The resistances', capacities' and heat-input gains' slots are read.
    res : ndarray, shape (nr,)
        Resistances, K/W.
    mod : Assembled
        ``A0, N, B0, M`` and the capacities ``cap`` of :func:`assemble` are read.
    q : int
        Number of directions.

    Returns
    -------
    dA0, dN, dB0, dM : ndarray, shapes (q, n, n), (q, nf, n, n), (q, n, p), (q, nf, n, p)
    """
    L, P, E = form.L, form.P, form.E
    A0, N, B0, M, cap = mod.A0, mod.N, mod.B0, mod.M, mod.cap
    res_idx, res_k, cap_idx, cap_k = slots.res_idx, slots.res_k, slots.cap_idx, slots.cap_k
    nr, n = L.shape
    p = E.shape[1]
    nf = N.shape[0]
    dA0 = np.zeros((q, n, n))
    dN = np.zeros((q, nf, n, n))
    dB0 = np.zeros((q, n, p))
    dM = np.zeros((q, nf, n, p))
    if q == 0:
        return dA0, dN, dB0, dM
    for k in range(nr):
        d = res_idx[k]
        if d < 0:
            continue
        w = res_k[k] / (res[k] * res[k])  # d(1/R)/dtheta = -k / R^2
        for i in range(n):
            if L[k, i] != 0.0:
                for j in range(n):
                    dA0[d, i, j] += L[k, i] * w * L[k, j] / cap[i]
            if P[k, i] != 0.0:
                for j in range(p):
                    dB0[d, i, j] -= P[k, i] * w * E[k, j] / cap[i]
    for t in range(slots.gain_state.shape[0]):
        d = slots.gain_idx[t]
        if d >= 0:  # B0 = Gb / c: dB0/dtheta = k / c in the gain's place
            i = slots.gain_state[t]
            dB0[d, i, slots.gain_input[t]] += slots.gain_k[t] / cap[i]
    for i in range(n):
        d = cap_idx[i]
        if d < 0:
            continue
        w = -cap_k[i] / cap[i]  # a row divided by c: d/dtheta = -(k / c) * row
        for j in range(n):
            dA0[d, i, j] += w * A0[i, j]
        for j in range(p):
            dB0[d, i, j] += w * B0[i, j]
        for f in range(nf):
            for j in range(n):
                dN[d, f, i, j] += w * N[f, i, j]
            for j in range(p):
                dM[d, f, i, j] += w * M[f, i, j]
    return dA0, dN, dB0, dM


@njit(cache=True, error_model="numpy")
def initial_state(mod: Assembled, der: AssembledDerivatives, start: Start) -> bool:
    """Derive the initial state ``mod.x0`` and its derivatives ``der.dx0`` (q, n) in place; False when singular.

    The given states (``start.given``) keep the values and derivatives the caller put there; the
    others are derived from the data when needed: the measured ones (first measurement finite) at
    ``y0``, the rest at the steady state given them, ``A_ff x_f = -(B_f u0 + A_fm x_m)`` at the
    first flows (every state that is not measured counts as free there, given or not).

    Parameters
    ----------
    mod : Assembled
        ``A0, N, B0, M`` are read; ``x0`` receives the derived states.
    der : AssembledDerivatives
        ``dA0, dN, dB0, dM`` are read; ``dx0`` receives the derived states' derivatives.
    start : Start
        The first sample, which state each output measures, and which states are given.

    Returns
    -------
    bool
        False when the steady state of the unmeasured states is singular (``x0`` then partial).
    """
    A0, N, B0, M = mod.A0, mod.N, mod.B0, mod.M
    dA0, dN, dB0, dM = der.dA0, der.dN, der.dB0, der.dM
    m0, u0, y0, out_state, given = start.m0, start.u0, start.y0, start.out_state, start.given
    n = A0.shape[0]
    p = B0.shape[1]
    q = dA0.shape[0]
    auto = False
    for i in range(n):
        auto = auto or not given[i]
    if not auto:
        return True
    x = np.zeros(n)
    dx = np.zeros((q, n))
    A = A0.copy()
    B = B0.copy()
    dA = dA0.copy()
    dB = dB0.copy()
    for f in range(N.shape[0]):
        mf = m0[f]
        for i in range(n):
            for j in range(n):
                A[i, j] += mf * N[f, i, j]
            for j in range(p):
                B[i, j] += mf * M[f, i, j]
            for d in range(q):
                for j in range(n):
                    dA[d, i, j] += mf * dN[d, f, i, j]
                for j in range(p):
                    dB[d, i, j] += mf * dM[d, f, i, j]
    measured = np.zeros(n, dtype=np.bool_)
    for j in range(out_state.shape[0]):
        s = out_state[j]
        if y0[j] == y0[j] and not measured[s]:
            measured[s] = True
            x[s] = y0[j]
    free = np.empty(n, dtype=np.int64)
    nfree = 0
    for i in range(n):
        if not measured[i]:
            free[nfree] = i
            nfree += 1
    if nfree:
        Aff = np.empty((nfree, nfree))
        rhs = np.zeros((nfree, 1))
        for a in range(nfree):
            i = free[a]
            for b in range(nfree):
                Aff[a, b] = A[i, free[b]]
            acc = 0.0
            for j in range(p):
                acc -= B[i, j] * u0[j]
            for j in range(n):
                if measured[j]:
                    acc -= A[i, j] * x[j]
            rhs[a, 0] = acc
        piv = np.empty(nfree, dtype=np.int64)
        lu_factor(Aff, piv)
        for a in range(nfree):
            if not (Aff[a, a] != 0.0 and abs(Aff[a, a]) < math.inf):
                return False
        lu_solve(Aff, piv, rhs)
        for a in range(nfree):
            x[free[a]] = rhs[a, 0]
        if q:
            # A_ff dx_f = -(dA_f. x + dB_f u0)
            sub = np.empty((nfree, q))
            for a in range(nfree):
                i = free[a]
                for d in range(q):
                    acc = 0.0
                    for j in range(n):
                        acc -= dA[d, i, j] * x[j]
                    for j in range(p):
                        acc -= dB[d, i, j] * u0[j]
                    sub[a, d] = acc
            lu_solve(Aff, piv, sub)
            for a in range(nfree):
                for d in range(q):
                    dx[d, free[a]] = sub[a, d]
    for i in range(n):
        if not given[i]:
            mod.x0[i] = x[i]
            for d in range(q):
                der.dx0[d, i] = dx[d, i]
    return True


@njit(cache=True, error_model="numpy")
def trapezoid(t: np.ndarray, e: np.ndarray, de: np.ndarray, grad: np.ndarray, curv: np.ndarray) -> float:
    """``int e^2 dt`` (trapezoid rule over intervals with both ends measured) and its gradient.

    ``curv`` receives the diagonal of the Gauss-Newton Hessian ``sum (de_k^2 + de_k+1^2) h``.
    """
    sse = 0.0
    q = de.shape[2]
    for k in range(e.shape[0] - 1):
        h = t[k + 1] - t[k]
        for j in range(e.shape[1]):
            a = e[k, j]
            b = e[k + 1, j]
            if a == a and b == b:
                sse += 0.5 * (a * a + b * b) * h
                for d in range(q):
                    da = de[k, j, d]
                    db = de[k + 1, j, d]
                    grad[d] += (a * da + b * db) * h
                    curv[d] += (da * da + db * db) * h
    return sse


@njit(cache=True, error_model="numpy")
def element_values(theta: np.ndarray, prob) -> tuple[ElementValues, bool]:
    """The element values, noise levels and given initial states at ``theta``; False where invalid.

    Invalid: a resistance or capacity that is not positive and finite, an infinite initial
    state, or (ML, MAP) a negative or infinite noise level.
    """
    L = prob.form.L
    out_state = prob.form.output_state
    sl = prob.slots
    res_idx, res_k, cap_idx, cap_k = sl.res_idx, sl.res_k, sl.cap_idx, sl.cap_k
    sv_idx, sv_k, sw_idx, sw_k = sl.sv_idx, sl.sv_k, sl.sw_idx, sl.sw_k
    sx_idx, sx_k, x0_idx, x0_k = sl.sx_idx, sl.sx_k, sl.x0_idx, sl.x0_k
    nr, n = L.shape
    ny = out_state.shape[0]
    ok = True
    res = np.empty(nr)
    for s in range(nr):
        res[s] = _slot(theta, res_idx[s], res_k[s])
        ok = ok and res[s] > 0.0 and res[s] < math.inf
    cap = np.empty(n)
    for s in range(n):
        cap[s] = _slot(theta, cap_idx[s], cap_k[s])
        ok = ok and cap[s] > 0.0 and cap[s] < math.inf
    sv = np.empty(ny)
    for s in range(ny):
        sv[s] = _slot(theta, sv_idx[s], sv_k[s])
    sw = np.empty(n)
    sx = np.empty(n)
    x0v = np.empty(n)
    for s in range(n):
        sw[s] = _slot(theta, sw_idx[s], sw_k[s])
        sx[s] = _slot(theta, sx_idx[s], sx_k[s])
        x0v[s] = _slot(theta, x0_idx[s], x0_k[s])
        ok = ok and abs(x0v[s]) < math.inf
    if prob.kind != LS:
        for s in range(ny):
            ok = ok and sv[s] >= 0.0 and sv[s] < math.inf
        for s in range(n):
            ok = ok and sw[s] >= 0.0 and sw[s] < math.inf and sx[s] >= 0.0 and sx[s] < math.inf
    return ElementValues(res, cap, sv, sw, sx, x0v), ok


@njit(cache=True, error_model="numpy")
def assembled(theta: np.ndarray, prob, q: int) -> tuple[Assembled, AssembledDerivatives, bool]:
    """The model at physical values ``theta`` and its derivatives in ``theta[0..q-1]``.

    False where the values are invalid (:func:`element_values`; the arrays are then computed
    but meaningless) or the steady state that starts the unmeasured states is singular.
    """
    vals, valid = element_values(theta, prob)
    out_state = prob.form.output_state
    m, u, y = prob.data.m, prob.data.u, prob.data.y
    sl = prob.slots
    sv_idx, sv_k, sw_idx, sw_k = sl.sv_idx, sl.sv_k, sl.sw_idx, sl.sw_k
    sx_idx, sx_k, x0_idx, x0_given = sl.sx_idx, sl.sx_k, sl.x0_idx, sl.x0_given
    sv, sw, sx = vals.sv, vals.sw, vals.sx
    n = prob.form.L.shape[1]
    ny = out_state.shape[0]
    A0, N, B0, M = assemble(prob.form, vals.res, vals.cap)
    # the heat-input gains that are parameters, affine in theta (Slots)
    gain_state, gain_input = sl.gain_state, sl.gain_input
    for t in range(gain_state.shape[0]):
        i = gain_state[t]
        gain = _slot(theta, sl.gain_idx[t], sl.gain_k[t])
        valid = valid and abs(gain) < math.inf
        B0[i, gain_input[t]] += gain / vals.cap[i]
    qc = np.zeros(n)
    P0 = np.zeros((n, n))
    r = np.ones(ny)
    dqc = np.zeros((q, n))
    dP0 = np.zeros((q, n, n))
    dr = np.zeros((ny, q))
    if prob.kind != LS:
        for s in range(n):
            qc[s] = sw[s] * sw[s]
            P0[s, s] = sx[s] * sx[s]
            if q and sw_idx[s] >= 0:
                dqc[sw_idx[s], s] += 2.0 * sw[s] * sw_k[s]
            if q and sx_idx[s] >= 0:
                dP0[sx_idx[s], s, s] += 2.0 * sx[s] * sx_k[s]
        for s in range(ny):
            r[s] = sv[s] * sv[s]
            if q and sv_idx[s] >= 0:
                dr[s, sv_idx[s]] += 2.0 * sv[s] * sv_k[s]
    C = np.zeros((ny, n))  # output j reads state out_state[j]
    for s in range(ny):
        C[s, out_state[s]] = 1.0
    # the given initial states, moving with their own parameter; initial_state derives the others
    x0 = vals.x0.copy()
    dx0 = np.zeros((q, n))
    for s in range(n):
        if x0_given[s] and 0 <= x0_idx[s] < q:
            dx0[x0_idx[s], s] = 1.0
    mod = Assembled(A0, N, B0, M, vals.cap, x0, P0, qc, r, C)
    dA0, dN, dB0, dM = assemble_derivatives(prob.form, sl, vals.res, mod, q)
    der = AssembledDerivatives(dA0, dN, dB0, dM, dx0, dP0, dqc, dr)
    ok = initial_state(mod, der, Start(m[0], u[0], y[0], out_state, x0_given))
    return mod, der, valid and ok


@njit(cache=True, error_model="numpy")
def prior_terms(theta: np.ndarray, penalty, grad: np.ndarray, curv: np.ndarray) -> float:
    """``-log p_eta`` of the packed priors at ``theta`` (up to a constant), added to ``grad`` and ``curv``.

    The one evaluation of a MAP prior (the compiled costs and :meth:`rczone.estimation.priors.LogPrior.terms`
    call it). A prior on ``theta`` becomes a density on the optimizer's ``eta``: for a parameter
    searched in log space the Jacobian ``|d theta / d eta| = theta`` adds ``-log theta`` [1]_,
    except to a log-normal, which is a normal in ``log theta``. Per prior, with ``x = theta[i]``:

    * log-normal (median ``a``, sigma ``b``): ``0.5 z^2``, ``z = (log x - log a) / b``; gradient
      ``z / (b x)``, curvature ``1 / (b x)^2``;
    * normal (mean ``a``, sigma ``b``): ``0.5 z^2``, ``z = (x - a) / b``; gradient ``z / b``,
      curvature ``1 / b^2``;
    * uniform on ``[a, b]``: ``0``, ``inf`` outside;

    plus the Jacobian term where it applies; ``inf`` for ``x <= 0`` in log space. The curvature
    is the prior's Fisher information (what optimizers scale their variables with).

    Parameters
    ----------
    theta : ndarray, shape (d,)
        Physical values.
    penalty : rczone.kernels.arrays.Penalty
        The packed priors.
    grad, curv : ndarray, shape (d,)
        Receive the gradient and curvature in ``theta`` (added).

    Returns
    -------
    float

    References
    ----------
    .. [1] A. Gelman et al., *Bayesian Data Analysis*, 3rd ed., CRC Press, 2013, section 1.8
       (transformation of variables).
    """
    idx, family, pa, pb, logp = penalty.prior_idx, penalty.family, penalty.a, penalty.b, penalty.log
    total = 0.0
    for k in range(idx.shape[0]):
        i = idx[k]
        x = theta[i]
        f = family[k]
        jac = 0.0
        djac = 0.0
        if logp[k]:
            if not x > 0.0:
                return math.inf
            if f != LOGNORMAL:
                jac = -math.log(x)
                djac = -1.0 / x
        if f == LOGNORMAL:
            z = (math.log(x) - math.log(pa[k])) / pb[k]
            total += 0.5 * z * z
            grad[i] += z / (pb[k] * x)
            curv[i] += 1.0 / (pb[k] * x) ** 2
        elif f == NORMAL:
            z = (x - pa[k]) / pb[k]
            total += 0.5 * z * z + jac
            grad[i] += z / pb[k] + djac
            curv[i] += 1.0 / (pb[k] * pb[k])
        else:
            if not pa[k] <= x <= pb[k]:
                return math.inf
            total += jac
            grad[i] += djac
    return total


@njit(cache=True, error_model="numpy")
def with_prior(
    j: float, theta: np.ndarray, penalty, grad: np.ndarray, curv: np.ndarray, want_grad: bool
) -> float:
    """``J_MAP = w J + prior`` (:func:`prior_terms`) of ``J = -log L``, with ``w`` the likelihood weight.

    ``grad`` and ``curv`` (of ``J``) are scaled by ``w`` in place; the prior's own terms are added
    only ``want_grad``.
    """
    weight = penalty.likelihood_weight
    for i in range(theta.shape[0]):
        grad[i] *= weight
        curv[i] *= weight
    if want_grad:
        return weight * j + prior_terms(theta, penalty, grad, curv)
    return weight * j + prior_terms(theta, penalty, np.zeros(theta.shape[0]), np.zeros(theta.shape[0]))


@njit(cache=True, error_model="numpy", inline="always")
def _no_directions(theta: np.ndarray) -> int:
    # q = 0 as a value, not the constant: a literal 0 would compile assembled() and its callees a
    # second time beside the specialization of value_and_gradient
    return theta.shape[0] * 0


# Three entry points, chosen in Python (value_kernel, and value_and_gradient for gradients): each
# compiles only the filter and discretization it runs. One function holding every path would link,
# optimize and generate the machine code of all of them (about 2.5 MB) into every command and again
# into every compiled caller (the direct search), though a command runs one of them.


@njit(cache=True, error_model="numpy")
def value_fused(theta: np.ndarray, prob) -> float:
    """The cost at physical values ``theta`` of a 2-state, 1-output problem (fused kernel); ``inf`` where invalid."""
    mod, _, ok = assembled(theta, prob, _no_directions(theta))
    if not ok:
        return math.inf
    t, m, u, y, groups = prob.data.t, prob.data.m, prob.data.u, prob.data.y, prob.data.groups
    foh, sym_rtol, steady_rtol, _ = prob.consts
    scratch = prob.scratch
    N_t = t.shape[0]
    e = scratch[:0]
    if prob.kind == LS:
        e = scratch
        for k in range(N_t):
            e[k] = math.nan
    nll, n_obs = nll_rc2(
        mod.A0, mod.N, mod.B0, mod.M, mod.cap, t, m, u, y[:, 0], mod.x0, mod.P0, mod.C[0],
        np.zeros(mod.B0.shape[1]), mod.r[0], mod.qc, foh, sym_rtol, steady_rtol, e, groups,
    )  # fmt: skip
    if n_obs < 0:
        return math.inf
    grad = np.zeros(theta.shape[0])
    curv = np.zeros(theta.shape[0])
    if prob.kind == LS:
        return trapezoid(t, e.reshape((N_t, 1)), np.empty((N_t, 1, 0)), grad, curv)
    j = nll + 0.5 * n_obs * _LOG_2PI
    if prob.kind == MAP:
        j = with_prior(j, theta, prob.penalty, grad, curv, False)
    return j


@njit(cache=True, error_model="numpy")
def value_general(theta: np.ndarray, prob) -> float:
    """The cost at physical values ``theta`` by the general filter (modal where it pays); ``inf`` where invalid."""
    mod, _, ok = assembled(theta, prob, _no_directions(theta))
    if not ok:
        return math.inf
    t, u, y, keys, which = prob.data.t, prob.data.u, prob.data.y, prob.data.keys, prob.data.which
    foh, _, steady_rtol, _ = prob.consts
    kind = prob.kind
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    ny = mod.C.shape[0]
    N_t = t.shape[0]
    scale = np.sqrt(mod.cap)
    obs = Observation(
        mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, 0, n)), np.zeros((ny, 0, p)), np.zeros((ny, 0))
    )
    prior = FilterStart(mod.x0, mod.P0, np.zeros((0, n)), np.zeros((0, n, n)))
    opts = FilterOptions(foh, kind == LS, steady_rtol)
    outs = outputs(N_t, n, ny, 0, kind == LS, False)
    dmats = no_sensitivities(keys.shape[0], n, p)
    if kind != LS and modal_pays(which, n):
        # values of larger models with flows constant over stretches: in modal coordinates
        mats, basis = modal_matrices(mod, Discretization(keys, scale, foh, True))
        nll, n_obs, _, _ = kalman_filter(mats, dmats, obs, prior, Series(u, y, which), opts, outs, basis)
    else:
        # a packed problem is an RC network: the spectral route only, not the matrix exponentials'
        mats = rc_interval_matrices(mod, Discretization(keys, scale, foh, kind != LS))
        nll, n_obs, _, _ = kalman_filter(mats, dmats, obs, prior, Series(u, y, which), opts, outs)
        if n_obs >= 0 and kind == LS:
            return trapezoid(t, outs.e, outs.de, np.zeros(theta.shape[0]), np.zeros(theta.shape[0]))
    if n_obs < 0:
        return math.inf
    j = nll + 0.5 * n_obs * _LOG_2PI
    if kind == MAP:
        j = with_prior(j, theta, prob.penalty, np.zeros(theta.shape[0]), np.zeros(theta.shape[0]), False)
    return j


@njit(cache=True, error_model="numpy")
def value_and_gradient(theta: np.ndarray, prob) -> tuple[float, np.ndarray, np.ndarray]:
    """The cost at physical values ``theta`` (one or more), its gradient and a diagonal curvature estimate.

    The curvature is the Fisher information for ``J_ML`` and the Gauss-Newton Hessian for
    ``J_LS``, in ``theta``. ``(inf, zeros, zeros)`` where the model is invalid.
    """
    d = theta.shape[0]
    grad = np.zeros(d)
    curv = np.zeros(d)
    mod, der, ok = assembled(theta, prob, d)
    if not ok:
        return math.inf, grad, curv
    t, u, y, keys, which = prob.data.t, prob.data.u, prob.data.y, prob.data.keys, prob.data.which
    foh, _, steady_rtol, _ = prob.consts
    kind = prob.kind
    n = mod.A0.shape[0]
    p = mod.B0.shape[1]
    ny = mod.C.shape[0]
    # an RC network (every packed problem): no Fréchet derivatives of matrix exponentials to compile
    mats, dmats = rc_interval_derivatives(mod, der, Discretization(keys, np.sqrt(mod.cap), foh, kind != LS))
    obs = Observation(mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, d, n)), np.zeros((ny, d, p)), der.dr)
    outs = outputs(t.shape[0], n, ny, d, kind == LS, False)
    nll, n_obs, g, fim = kalman_filter(
        mats,
        dmats,
        obs,
        FilterStart(mod.x0, mod.P0, der.dx0, der.dP0),
        Series(u, y, which),
        FilterOptions(foh, kind == LS, steady_rtol),
        outs,
    )
    if n_obs < 0:
        return math.inf, grad, curv
    if kind == LS:
        return trapezoid(t, outs.e, outs.de, grad, curv), grad, curv
    j = nll + 0.5 * n_obs * _LOG_2PI
    for i in range(d):
        grad[i] = g[i]
        curv[i] = fim[i]
    if kind == MAP:
        j = with_prior(j, theta, prob.penalty, grad, curv, True)
    return j, grad, curv


def value_kernel(prob):
    """The compiled cost of a packed problem's values: :func:`value_fused` or :func:`value_general`.

    Returned as a callable ``(theta, prob)`` bound to this problem's compiled specialization
    (:func:`bound_kernel`).

    Parameters
    ----------
    prob : rczone.kernels.arrays.Problem
        The packed problem.

    Returns
    -------
    callable
        ``value(theta, prob) -> float``, as the kernel.
    """
    return bound_kernel(value_fused if prob.consts.fused else value_general, prob)


def bound_kernel(kernel, prob):
    """``kernel(theta, prob)`` bound to its compiled specialization for this problem.

    A numba dispatcher types a named tuple argument in Python at every call (about 5 us for the
    40 arrays of a :class:`rczone.kernels.arrays.Problem`, a quarter of a 2-state likelihood),
    so the specialization is resolved once (at the first call: a problem whose kernel is never
    called compiles nothing) and called directly for a float64 ``theta`` and this same problem;
    any other argument goes through the dispatcher. Resolving it from the problem's numba type
    costs about 0.3 ms (numba's ``typeof_pyval`` types the 40 arrays in Python), more than a short
    fit saves, so the specialization is kept per kernel and structure (:func:`_specialization`). :func:`value_kernel` binds the value kernels,
    :func:`rczone.kernels.adjoint.gradient_kernel` the gradient kernels.

    Parameters
    ----------
    kernel : numba dispatcher
        A compiled entry point taking ``(theta, prob)``.
    prob : rczone.kernels.arrays.Problem
        The packed problem.

    Returns
    -------
    callable
        ``kernel(theta, prob)``, as the kernel returns it.
    """
    entry = None

    def call(theta: np.ndarray, problem):
        nonlocal entry
        if (
            problem is prob
            and type(theta) is np.ndarray
            and theta.dtype == np.float64
            and theta.ndim == 1
            and theta.flags.c_contiguous
        ):
            if entry is None:
                entry = _specialization(kernel, prob)
            return entry(theta, prob)
        return kernel(theta, problem)

    return call


#: Compiled specializations of :func:`bound_kernel`, by kernel, problem class and numba fingerprint.
_SPECIALIZATIONS: dict = {}


def _specialization(kernel, prob):
    """The compiled ``kernel`` for a float64 ``theta`` and problems typed as ``prob``.

    Problems of one structure (a batch's zones, a search's objectives) have one numba type; numba's
    own fingerprint of an argument (the dtype, dimensions, layout and writability of every array,
    what its dispatcher keys its type cache by; a few microseconds) finds it again without typing
    the problem in Python.
    """
    try:
        key = (kernel, type(prob), compute_fingerprint(prob))
    except (TypeError, ValueError, NotImplementedError):  # not fingerprinted: type it each time
        key = None
    entry = _SPECIALIZATIONS.get(key) if key is not None else None
    if entry is None:
        entry = kernel.compile((types.Array(types.float64, 1, "C"), kernel.typeof_pyval(prob)))
        if key is not None:
            _SPECIALIZATIONS[key] = entry
    return entry


def cost(theta: np.ndarray, prob) -> float:
    """The cost at physical values ``theta`` (from Python); ``inf`` where the model is invalid."""
    return float(value_kernel(prob)(theta, prob))


def cost_and_gradient(theta: np.ndarray, prob) -> tuple[float, np.ndarray, np.ndarray]:
    """:func:`value_and_gradient` from Python, also without free parameters (empty gradient)."""
    if theta.shape[0] == 0:
        return value_general(theta, prob), np.zeros(0), np.zeros(0)
    return value_and_gradient(theta, prob)
