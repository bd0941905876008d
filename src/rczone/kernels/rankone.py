"""Compiled exact simulation of an RC model whose flow term is a rank-one update.

With one supply-air flow entering one capacitive node, the symmetrized state matrix is
``S(m) = S0 + m sigma w w'`` (``S = diag(s) A diag(s)^{-1}``, ``s = sqrt(capacities)``). In the
eigenbasis ``Q`` of ``S0`` (computed once), ``Q' S(m) Q = D + rho z z'`` with ``rho = m sigma``
and ``z = Q' w`` fixed: the classical rank-one-modified symmetric eigenproblem. Its
eigenvalues are the roots of the secular equation ``1 + rho sum_j z_j^2 / (d_j - lam) = 0``,
one in each interval between consecutive ``d_j`` (plus one beyond the end), and its
eigenvectors are ``(D - lam I)^{-1} z`` normalized. Each root is found to full accuracy by a
safeguarded Newton iteration in coordinates shifted to the nearer pole (so ``d_j - lam`` is
computed without cancellation), and the eigenvectors use the Gu-Eisenstat recomputed ``z``,
which keeps them orthogonal to working precision. The state is carried in the fixed
coordinates ``xi = Q' diag(s) x``, so a step costs ``O(n^2)`` instead of the ``O(n^3)`` of
forming ``Phi``:

``xi+ = U (e^{lam dt} * (U' xi) + phi1(lam) * (U' b0))`` (ZOH; FOH adds ``phi2`` terms),

with ``U`` the eigenvectors of ``D + rho z z'`` and ``b0 = Q' diag(s) B(m) u``. Components with
``z_j = 0`` (after the once-per-model deflation done by
:func:`rczone.simulation.discretize.rank_one_form`) keep eigenvalue ``d_j``.

References
----------
.. [1] J. R. Bunch, C. P. Nielsen, D. C. Sorensen, "Rank-one modification of the symmetric
   eigenproblem", Numerische Mathematik 31 (1978) 31-48.
.. [2] M. Gu, S. C. Eisenstat, "A stable and efficient algorithm for the rank-one
   modification of the symmetric eigenproblem", SIAM J. Matrix Anal. Appl. 15 (1994) 1266-1276.
.. [3] R.-C. Li, "Solving secular equations stably and efficiently", LAPACK Working Note 89, 1993.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from rczone.kernels.arrays import writable
from rczone.kernels.discretize import phi1, phi2

_EPS = float(np.finfo(float).eps)


class Secular(NamedTuple):
    """A rank-one-modified eigenproblem ``diag(d) + rho z z'`` (``rho > 0``, ``d`` ascending and distinct)."""

    d: np.ndarray  #: (r,)
    z: np.ndarray  #: (r,)
    z2: np.ndarray  #: (r,) ``z * z``
    inv_dd: np.ndarray  #: (r, r) ``1 / (d_i - d_j)`` off the diagonal


class SecularRoots(NamedTuple):
    """The roots of the previous calls, from which the next call of :func:`_eigen` starts."""

    org: np.ndarray  #: (r,) int64, the nearer pole of each root (-1: no previous call)
    tau: np.ndarray  #: (r,) each root's offset from its pole
    track: np.ndarray  #: (3, r) ``d lam / d rho`` of the last call, and the roots of the last two
    rho_prev: np.ndarray  #: (3,) ``(rho_1, rho_2, calls)``


class Eigen(NamedTuple):
    """What :func:`_eigen` writes: eigenvalues, eigenvectors, and its workspace."""

    lam: np.ndarray  #: (n,) eigenvalues (the first r written)
    U: np.ndarray  #: (r, r) eigenvectors, in columns
    zh: np.ndarray  #: (r,) workspace: the Gu-Eisenstat ``z``
    Qinv: np.ndarray  #: (r, r) workspace: ``1 / (d_j - lam_i)``


class RankOneModel(NamedTuple):
    """A model with a rank-one flow term in the coordinates ``xi = Q' diag(s) x`` of :func:`simulate_rank_one_kernel`."""

    d: np.ndarray  #: (n,) eigenvalues of ``S0``: the r active ones ascending first, then the deflated ones
    z: np.ndarray  #: (r,) active components of ``Q' w`` (all non-zero)
    sigma: float  #: ``S(m) = S0 + m sigma w w'``
    Bq: np.ndarray  #: (n, p) ``Q' diag(s) B``
    Mq: np.ndarray  #: (n, p) ``Q' diag(s) M`` (``B(m) = B + m M``)


@njit(cache=True, error_model="numpy")
def _newton_root(
    d: np.ndarray, z2: np.ndarray, rho: float, o: int, x: float, lo: float, hi: float, q: np.ndarray
) -> tuple[float, float]:
    """Root (relative to pole ``d[o]``) of the secular function in ``(lo, hi)``.

    Newton's method on ``h(x) = (d_o - lam) f(lam)``, which removes the nearest pole so
    the iteration converges quadratically from either side; a step leaving the bracket is
    replaced by bisection. Stops when ``|f|`` is below its rounding-error bound [3]_ or when a
    Newton step is below ``1e-9`` relative (the next error is then below rounding).

    Returns ``(x, step)``: the root is ``x + step`` and ``q[j] = 1/((d_j - d_o) - x)`` (``j != o``)
    holds the reciprocals at ``x``, so the caller gets those at the root as
    ``q (1 + q step)`` without new divisions (``|q step| < 1e-9``).
    """
    r = d.shape[0]
    for _ in range(100):
        w = -x
        h = w + rho * z2[o]
        dh = -1.0
        bound = abs(w) + rho * z2[o]
        for j in range(r):
            if j != o:
                dj = d[j] - d[o]
                qj = 1.0 / (dj - x)
                q[j] = qj
                t = rho * z2[j] * qj
                h += t * w
                dh -= t * dj * qj
                bound += abs(t * w)
        if abs(h) <= 8.0 * r * _EPS * bound:
            return x, 0.0
        if (h < 0.0) == (w < 0.0):  # f = h / w > 0: root on the left
            hi = x
        else:
            lo = x
        xn = x - h / dh
        if not (lo < xn < hi):
            xn = 0.5 * (lo + hi)
        elif abs(xn - x) <= 1e-9 * abs(xn):
            # quadratic convergence: the error after this step is ~ step^2 / gap < 1e-18 |x|
            return x, xn - x
        if hi - lo <= 4.0 * _EPS * max(abs(lo), abs(hi)):
            return x, xn - x
        x = xn
    return x, 0.0


@njit(cache=True, error_model="numpy")
def _secular_roots(
    d: np.ndarray, z2: np.ndarray, rho: float, org: np.ndarray, tau: np.ndarray, Qinv: np.ndarray
) -> None:
    """Roots of ``1 + rho sum_j z2_j/(d_j - lam)`` for ``rho > 0``, ``d`` ascending and distinct.

    Root ``i`` (in ``(d_i, d_{i+1})``, the last in ``(d_{r-1}, d_{r-1} + rho |z|^2]``) is returned
    as ``lam_i = d[org[i]] + tau[i]`` with ``org[i]`` the nearer pole, so that every
    ``d_j - lam_i = (d_j - d[org[i]]) - tau[i]`` is accurate to rounding, and
    ``Qinv[i, j] = 1/(d_j - lam_i)``. On entry ``org``/``tau`` may hold a starting guess
    (``org[i] < 0``: none), e.g. the previous sample's roots.
    """
    r = d.shape[0]
    for i in range(r):
        q = Qinv[i]
        if i == r - 1:
            znorm2 = 0.0
            for j in range(r):
                znorm2 += z2[j]
            o = i
            lo, hi = 0.0, rho * znorm2
            x = tau[i] if org[i] == i and lo < tau[i] < hi else 0.5 * hi
            x, step = _newton_root(d, z2, rho, o, x, lo, hi, q)
        else:
            gap = d[i + 1] - d[i]
            o = org[i]
            if o == i and 0.0 < tau[i] < gap:
                x = tau[i]
            elif o == i + 1 and -gap < tau[i] < 0.0:
                x = tau[i]
            else:
                mid = 0.5 * gap
                f = 1.0
                for j in range(r):
                    f += rho * z2[j] / ((d[j] - d[i]) - mid)
                o = i if f >= 0.0 else i + 1
                x = 0.25 * gap if o == i else -0.25 * gap
            if o == i:
                x, step = _newton_root(d, z2, rho, o, x, 0.0, gap, q)
                if x + step > 0.5 * gap:  # nearer the right pole: refine relative to it
                    o = i + 1
                    x, step = _newton_root(d, z2, rho, o, x + step - gap, -gap, 0.0, q)
            else:
                x, step = _newton_root(d, z2, rho, o, x, -gap, 0.0, q)
                if x + step < -0.5 * gap:
                    o = i
                    x, step = _newton_root(d, z2, rho, o, x + step + gap, 0.0, gap, q)
        for j in range(r):
            if j != o:
                q[j] *= 1.0 + q[j] * step
        org[i] = o
        tau[i] = x + step
        q[o] = -1.0 / tau[i]


@njit(cache=True, error_model="numpy", inline="always")
def _eigen(problem: Secular, rho: float, roots: SecularRoots, out: Eigen) -> None:
    """Eigenvalues ``lam`` and orthonormal eigenvectors (columns of ``U``) of ``diag(d) + rho z z'``.

    ``rho > 0``. ``roots`` carries the previous calls' roots: ``track[0]`` their derivatives
    ``d lam_i / d rho = (u_i' z)^2``, ``track[1]`` and ``track[2]`` the roots of the last two
    calls, ``rho_prev = (rho_1, rho_2, calls)``. The next call starts from the first-order
    prediction plus the curvature fitted to the older root (a quadratic through both, with the
    last slope), so Newton needs about two iterations per root (2.5 with the first-order
    prediction alone).
    """
    d, z, z2, inv_dd = problem
    org, tau, track, rho_prev = roots
    lam, U, zh, Qinv = out
    r = d.shape[0]
    if org[0] >= 0:
        step = rho - rho_prev[0]
        back = rho_prev[1] - rho_prev[0]
        quad = rho_prev[2] > 1.0 and back != 0.0
        w = step * step / (back * back) if quad else 0.0
        for i in range(r):
            # first order, plus the curvature from the root two calls back when there is one:
            # lam(rho) ~ lam1 + s1 d + c d^2 with c fitted to lam2 at rho2
            tau[i] += step * track[0, i] + w * (track[2, i] - track[1, i] - track[0, i] * back)
    _secular_roots(d, z2, rho, org, tau, Qinv)
    for i in range(r):
        lam[i] = d[org[i]] + tau[i]
        track[2, i] = track[1, i]
        track[1, i] = lam[i]
    # Gu-Eisenstat: the z for which the computed roots are exact eigenvalues
    for j in range(r):
        prod = -((d[j] - d[org[j]]) - tau[j]) / rho
        for i in range(r):
            if i != j:
                prod *= -((d[j] - d[org[i]]) - tau[i]) * inv_dd[i, j]
        v = math.sqrt(max(prod, 0.0))
        zh[j] = v if z[j] >= 0.0 else -v
    for i in range(r):
        nrm = 0.0
        for j in range(r):
            v = zh[j] * Qinv[i, j]
            U[j, i] = v
            nrm += v * v
        nrm = 1.0 / math.sqrt(nrm)
        uz = 0.0
        for j in range(r):
            U[j, i] *= nrm
            uz += U[j, i] * z[j]
        track[0, i] = uz * uz
    rho_prev[1] = rho_prev[0]
    rho_prev[0] = rho
    rho_prev[2] += 1.0


@njit(cache=True, error_model="numpy")
def _weights(x: float, foh: bool) -> tuple[float, float, float]:
    """``(e^x, (e^x - 1)/x, (e^x - 1 - x)/x^2)`` (the last only for FOH, 0 otherwise)."""
    em1 = math.expm1(x)
    # em1 + 1 is exact to eps absolutely, all that Phi = U diag(e) U' (|e| <= 1 for RC) needs
    return em1 + 1.0, phi1(x, em1), phi2(x, em1) if foh else 0.0


@njit(cache=True, error_model="numpy")
def simulate_rank_one_kernel(
    model: RankOneModel, t: np.ndarray, m: np.ndarray, u: np.ndarray, xi0: np.ndarray, foh: bool
) -> np.ndarray:
    """States ``xi = Q' diag(s) x`` at every sample.

    Parameters
    ----------
    model : RankOneModel
        ``S0``'s eigenvalues ``d`` in the ``xi`` order (the ``r = len(z)`` active ones ascending
        first, then the deflated ones), the active components ``z`` of ``Q' w``, ``sigma`` and the
        input matrices ``Bq, Mq`` in these coordinates.
    t : ndarray, shape (N,)
    m : ndarray, shape (N,)
        Flow held from ``t[k]`` to ``t[k+1]``.
    u : ndarray, shape (N, p)
    xi0 : ndarray, shape (n,)
    foh : bool

    Returns
    -------
    xi : ndarray, shape (N, n)
    """
    d, z, sigma, Bq, Mq = model.d, model.z, model.sigma, model.Bq, model.Mq
    r = z.shape[0]
    n = d.shape[0]
    N, p = u.shape
    # explicit loops throughout: array expressions and slice assignment cost seconds of compile time
    xi = np.empty((N, n))
    for i in range(n):
        xi[0, i] = xi0[i]
    da = np.empty(r)
    dr = np.empty(r)  # the rho < 0 problem, negated and reversed to ascending
    za = np.empty(r)
    zr = np.empty(r)
    za2 = np.empty(r)
    zr2 = np.empty(r)
    org_a = np.empty(r, np.int64)
    org_r = np.empty(r, np.int64)
    for i in range(r):
        da[i] = d[i]
        dr[i] = -d[r - 1 - i]
        za[i] = z[i]
        zr[i] = z[r - 1 - i]
        za2[i] = z[i] * z[i]
        zr2[i] = z[r - 1 - i] * z[r - 1 - i]
        org_a[i] = -1
        org_r[i] = -1
    inv_a = np.zeros((r, r))
    inv_r = np.zeros((r, r))
    for i in range(r):
        for j in range(r):
            if i != j:
                inv_a[i, j] = 1.0 / (da[i] - da[j])
                inv_r[i, j] = 1.0 / (dr[i] - dr[j])
    tau_a = np.zeros(r)
    tau_r = np.zeros(r)
    track_a = np.zeros((3, r))
    track_r = np.zeros((3, r))
    rho_a = np.zeros(3)
    rho_r = np.zeros(3)
    lam = np.empty(n)
    U = np.zeros((r, r))
    Ut = np.empty((r, r))
    Qinv = np.empty((r, r))
    zh = np.empty(r)
    e = np.empty(n)
    g0 = np.empty(n)
    g1 = np.empty(n)
    b0 = np.empty(n)
    b1 = np.zeros(n)
    ca = np.empty(r)
    last_h = -1.0
    last_m = math.nan
    for k in range(N - 1):
        h = t[k + 1] - t[k]
        mk = m[k]
        if mk != last_m or h != last_h:
            rho = mk * sigma
            if rho > 0.0 and r > 0:
                _eigen(
                    Secular(da, za, za2, inv_a),
                    rho,
                    SecularRoots(org_a, tau_a, track_a, rho_a),
                    Eigen(lam, U, zh, Qinv),
                )
            elif rho < 0.0 and r > 0:
                _eigen(
                    Secular(dr, zr, zr2, inv_r),
                    -rho,
                    SecularRoots(org_r, tau_r, track_r, rho_r),
                    Eigen(lam, Ut, zh, Qinv),
                )
                for i in range(r):
                    lam[i] = -lam[i]
                    for j in range(r):
                        U[j, i] = Ut[r - 1 - j, i]
            else:
                for i in range(r):
                    lam[i] = da[i]
                    for j in range(r):
                        U[j, i] = 1.0 if i == j else 0.0
            for i in range(r, n):
                lam[i] = d[i]
            for i in range(n):
                ei, w1, w2 = _weights(lam[i] * h, foh)
                e[i] = ei
                if foh:
                    g0[i] = (w1 - w2) * h
                    g1[i] = w2 * h
                else:
                    g0[i] = w1 * h
                    g1[i] = 0.0
            last_h = h
            last_m = mk
        for i in range(n):
            acc0 = 0.0
            acc1 = 0.0
            for j in range(p):
                bij = Bq[i, j] + mk * Mq[i, j]
                acc0 += bij * u[k, j]
                if foh:
                    acc1 += bij * u[k + 1, j]
            b0[i] = acc0
            b1[i] = acc1
        # active block: U (e * U'xi + g0 * U'b0 + g1 * U'b1)
        for i in range(r):
            s_x = 0.0
            s_0 = 0.0
            for j in range(r):
                s_x += U[j, i] * xi[k, j]
                s_0 += U[j, i] * b0[j]
            ca[i] = e[i] * s_x + g0[i] * s_0
            if foh:
                s_1 = 0.0
                for j in range(r):
                    s_1 += U[j, i] * b1[j]
                ca[i] += g1[i] * s_1
        for j in range(r):
            acc = 0.0
            for i in range(r):
                acc += U[j, i] * ca[i]
            xi[k + 1, j] = acc
        for j in range(r, n):
            xi[k + 1, j] = e[j] * xi[k, j] + g0[j] * b0[j] + g1[j] * b1[j]
    return xi


def simulate_rank_one(
    form,
    B: np.ndarray,
    M: np.ndarray,
    t: np.ndarray,
    m: np.ndarray,
    u: np.ndarray,
    x0: np.ndarray,
    hold: str = "zoh",
) -> np.ndarray:
    """States ``x`` (N, n) of ``dx/dt = (A + m N) x + (B + m M) u`` via :func:`simulate_rank_one_kernel`.

    Parameters
    ----------
    form : rczone.simulation.discretize.RankOneForm
        From :func:`rczone.simulation.discretize.rank_one_form` for the model's ``A, N``
        (any object with its attributes ``Q, d, z, r, sigma, scale``).
    B, M : ndarray, shapes (n, p), (n, p)
        Input matrix at zero flow and its change per unit flow.
    t : ndarray, shape (N,)
    m : ndarray, shape (N,)
    u : ndarray, shape (N, p)
    x0 : ndarray, shape (n,)
    hold : {"zoh", "foh"}
    """
    sQ = form.Q.T * form.scale[None, :]  # Q' diag(s)
    f = writable  # a data set's read-only arrays would compile a second specialization
    model = RankOneModel(f(form.d), f(form.z), float(form.sigma), f(sQ @ B), f(sQ @ M))
    xi = simulate_rank_one_kernel(
        model, f(t), f(m), f(u), f(sQ @ np.asarray(x0, dtype=np.float64)), hold == "foh"
    )
    x = (xi @ form.Q.T) / form.scale[None, :]
    x[0] = x0  # exactly, rather than through the change of basis
    return x
