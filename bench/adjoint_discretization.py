"""What the floor fit's gradient would cost with the adjoint carried through the discretization (a prototype).

Usage::

    python bench/adjoint_discretization.py            # the small office's floor, as bench/energyplus.py fits it
    python bench/adjoint_discretization.py --fit      # and one fit with the prototype's gradient

rczone's gradient of a packed likelihood (:func:`rczone.kernels.adjoint.gradient_general`) runs the
filter's reverse pass, which gives the matrix adjoints ``Phi_bar``, ``G0_bar``, ``Qd_bar`` of each
distinct interval, and contracts them with the **forward** derivatives of those matrices along every
parameter (:func:`rczone.kernels.discretize.rc_interval_derivatives`): ``q`` directions per interval.
Here the adjoints are carried back through the same spectral formulas instead, once per interval
whatever ``q``: with ``S = T^-1 A T`` diagonal (``T = D^-1 V`` of the symmetrized eigen-decomposition),
the Daleckii-Krein derivative ``dPhi = T (F o T^-1 dA T) T^-1`` has the adjoint
``A_bar = T^-T (F o T' Phi_bar T^-T) T'`` (Higham, *Functions of Matrices*, SIAM 2008, Theorem 3.11);
the hold matrix adds ``Fg o T' G0_bar (T^-1 B)'`` inside and ``B_bar = T^-T diag(wg) T' G0_bar``; the
noise integral ``Qd = T (W o Om) T'`` adds ``2 sum_m S_im Y_ijm`` with ``S = T' Qd_bar T`` and gives
``qc_bar = diag(T^-T (S o Om) T^-1)``. The sums of ``A_bar`` and ``B_bar`` over the intervals (weighted by
each flow for its ``N_f``, ``M_f``) meet each parameter's ``dA0``, ``dN``, ``dB0``, ``dM``, ``dqc`` once.
Zero-order hold and maximum likelihood only (a prototype, not rczone's code).

Prints the largest relative difference from rczone's gradient at a few points (the oracle) and the
CPU time of both (``time.process_time``, after compilation); with ``--fit``, one ML fit
(``n_starts=1``) with this gradient in place of rczone's, CPU per part.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from energyplus import floor_problem, make_trend  # noqa: E402
from rczone.kernels.adjoint import gradient_general, zero_adjoints  # noqa: E402
from rczone.kernels.arrays import Discretization, FilterOptions, FilterStart, Observation, Series  # noqa: E402
from rczone.kernels.discretize import (  # noqa: E402
    SERIES_LIMIT,
    _dd2,
    _dd3_sorted,
    _key_matrices,
    phi1,
    rc_interval_matrices,
    symmetric_eigen,
)
from rczone.kernels.problem import assembled, theta_of_z, value_general  # noqa: E402
from rczone.kernels.reverse import nll_reverse  # noqa: E402

_LOG_2PI = math.log(2.0 * math.pi)


@njit(error_model="numpy")
def _kernels(lam: np.ndarray, h: float):
    """``x = lam h``, ``e^x``, the ZOH weights ``h phi1(x)`` and the divided differences of ``Phi`` and ``G0``."""
    n = lam.shape[0]
    x = lam * h
    e = np.exp(x)
    wg = np.empty(n)
    F0 = np.empty((n, n))
    Fg = np.empty((n, n))
    for i in range(n):
        wg[i] = phi1(x[i], math.expm1(x[i])) * h
        for j in range(i, n):
            F0[i, j] = F0[j, i] = h * _dd2(x[i], x[j], e[i], e[j])
            Fg[i, j] = Fg[j, i] = h * h * _dd3_sorted(0.0, x[i], x[j], 1.0, e[i], e[j])
    return x, e, wg, F0, Fg


@njit(error_model="numpy")
def _noise_bar(Ti, qc, x, e, F0, h, S, Eb) -> np.ndarray:
    """Add the noise integral's share to ``Eb`` (the adjoint of ``T^-1 dA T``); the diagonal of ``S o Om`` mapped back."""
    n = x.shape[0]
    W = np.empty((n, n))
    Om = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += Ti[i, k] * qc[k] * Ti[j, k]
            W[i, j] = W[j, i] = acc
            xs = x[i] + x[j]
            Om[i, j] = Om[j, i] = phi1(xs, math.expm1(xs)) * h
    for m in range(n):
        for i in range(n):
            for j in range(i, n):
                lo = min(x[i], x[j]) + x[m]
                hi = max(x[i], x[j]) + x[m]
                if hi <= 0.0 and lo <= -SERIES_LIMIT:  # as rczone's forward formula
                    v = h * (Om[i if x[i] >= x[j] else j, m] - e[m] * F0[i, j]) / (-lo)
                else:
                    v = h * h * _dd3_sorted(0.0, x[i] + x[m], x[j] + x[m], 1.0, e[i] * e[m], e[j] * e[m])
                Eb[i, j] += 2.0 * S[i, m] * v * W[j, m]
                if j != i:
                    Eb[j, i] += 2.0 * S[j, m] * v * W[i, m]
    return S * Om


@njit(error_model="numpy")
def interval_adjoint(A, B, qc, h, scale, Phib, G0b, Qdb, Abar, Bbar, qcbar) -> None:
    """Add to ``Abar``, ``Bbar``, ``qcbar`` the adjoints of one ZOH interval's ``Phi``, ``G0``, ``Qd`` (module notes)."""
    n = A.shape[0]
    lam, V = symmetric_eigen(A, scale)
    T = np.empty((n, n))
    Ti = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            T[i, j] = V[i, j] / scale[i]
            Ti[j, i] = V[i, j] * scale[i]
    x, e, wg, F0, Fg = _kernels(lam, h)
    Tt = np.ascontiguousarray(T.T)
    Tit = np.ascontiguousarray(Ti.T)
    TiB = Ti @ B
    Eb = F0 * (Tt @ Phib @ Tit) + Fg * (Tt @ G0b @ np.ascontiguousarray(TiB.T))
    TG = Tt @ G0b
    for i in range(n):
        TG[i] *= wg[i]
    Bbar += Tit @ TG
    S = Tt @ Qdb @ T
    SOm = _noise_bar(Ti, qc, x, e, F0, h, S, Eb)
    Abar += Tit @ Eb @ Tt
    back = Tit @ SOm @ Ti
    for k in range(n):
        qcbar[k] += back[k, k]


@njit(error_model="numpy")
def gradient_adjoint(theta: np.ndarray, prob) -> tuple[float, np.ndarray]:
    """``J_ML`` of a packed ZOH problem and its gradient in ``theta`` (module notes); ``(inf, zeros)`` if invalid."""
    q = theta.shape[0]
    grad = np.zeros(q)
    mod, der, ok = assembled(theta, prob, q)
    if not ok:
        return math.inf, grad
    n, p, ny, nf = mod.A0.shape[0], mod.B0.shape[1], mod.C.shape[0], mod.N.shape[0]
    keys = prob.data.keys
    scale = np.sqrt(mod.cap)
    mats = rc_interval_matrices(mod, Discretization(keys, scale, False, True))
    bars = zero_adjoints(keys.shape[0], n, p, ny)
    obs = Observation(
        mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, 0, n)), np.zeros((ny, 0, p)), np.zeros((ny, 0))
    )
    start = FilterStart(mod.x0, mod.P0, np.zeros((0, n)), np.zeros((0, n, n)))
    series = Series(prob.data.u, prob.data.y, prob.data.which)
    nll, n_obs, _ = nll_reverse(mats, obs, start, series, FilterOptions(False, False, prob.consts[2]), bars)
    if n_obs < 0:
        return math.inf, grad
    Asum = np.zeros((1 + nf, n, n))
    Bsum = np.zeros((1 + nf, n, p))
    qcbar = np.zeros(n)
    for w in range(keys.shape[0]):
        A, B = _key_matrices(mod, keys[w])
        Ab = np.zeros((n, n))
        Bb = np.zeros((n, p))
        interval_adjoint(A, B, mod.qc, keys[w, 0], scale, bars.Phi[w], bars.G0[w], bars.Qd[w], Ab, Bb, qcbar)
        Asum[0] += Ab
        Bsum[0] += Bb
        for f in range(nf):
            if keys[w, 1 + f] != 0.0:
                Asum[1 + f] += keys[w, 1 + f] * Ab
                Bsum[1 + f] += keys[w, 1 + f] * Bb
    for d in range(q):
        acc = np.sum(bars.r * der.dr[:, d]) + np.sum(bars.x0 * der.dx0[d]) + np.sum(qcbar * der.dqc[d])
        acc += np.sum(bars.P0 * der.dP0[d]) + np.sum(Asum[0] * der.dA0[d]) + np.sum(Bsum[0] * der.dB0[d])
        for f in range(nf):
            acc += np.sum(Asum[1 + f] * der.dN[d, f]) + np.sum(Bsum[1 + f] * der.dM[d, f])
        grad[d] = acc
    return nll + 0.5 * n_obs * _LOG_2PI, grad


def cpu_per_call(f, *args, budget: float = 3.0) -> float:
    f(*args)
    c0, n = time.process_time(), 0
    while time.process_time() - c0 < budget:
        f(*args)
        n += 1
    return (time.process_time() - c0) / n


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", action="store_true", help="also one fit with the prototype's gradient")
    args = ap.parse_args(argv)
    from rczone.estimation import costs, fit
    from rczone.estimation.fit import default_free
    from rczone.estimation.parameters import make_spec

    with tempfile.TemporaryDirectory() as tmp:
        make_trend(Path(tmp))
        net, data = floor_problem(Path(tmp))
    spec = make_spec(net, list(default_free(net, "ml")))
    prob = costs.Objective(net, data, spec, "ml")._packed
    lo, hi, logp = prob.box
    rng = np.random.default_rng(0)
    print(
        f"load {os.getloadavg()[0]:.2f}; {len(net.state_names)} states, {spec.n_free} free, {data.intervals[0].shape[0]} intervals"
    )
    for k in range(3):
        eta = spec.to_eta(spec.start) + (0.0 if k == 0 else 0.3 * rng.standard_normal(spec.n_free))
        f = np.clip((eta - lo) / (hi - lo), 1e-6, 1 - 1e-6)
        theta = theta_of_z(np.log(f) - np.log1p(-f), lo, hi, logp)
        (j0, g0), (j1, g1) = gradient_general(theta, prob), gradient_adjoint(theta, prob)
        print(
            f"point {k}: -log L {j0:.10g} vs {j1:.10g}; gradient max rel. difference {np.max(np.abs(g1 - g0)) / np.max(np.abs(g0)):.1e}"
        )
    for name, fn in (
        ("rczone gradient", gradient_general),
        ("prototype gradient", gradient_adjoint),
        ("likelihood alone", value_general),
    ):
        print(f"{name:20s} {1e3 * cpu_per_call(fn, theta, prob):7.2f} ms CPU")
    if args.fit:
        costs.gradient_kernel = lambda prob, fused: gradient_adjoint  # the prototype in place of rczone's
        fit(net, data, method="ml", n_starts=1, max_evals=5, uncertainty=False)  # compiles
        c0 = time.process_time()
        res = fit(net, data, method="ml", n_starts=1)
        print(
            f"fit with the prototype: {time.process_time() - c0:.1f} s CPU, {res.n_evals} evaluations,"
            f" {len(res.starts)} local searches, -log L {-res.llf:.4f}, converged {res.converged}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
