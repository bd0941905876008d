"""Issue 24's figures: rczone against the practical limit on the 2-state peer task, as ratios.

The *limit* is what a specialist would write for this one problem and nothing else: the
2-state wall/room model of ``problems.peer_network`` (pySIP's ``TwTi_RoRi``) with FOH inputs
and regular sampling, discretized once per evaluation in closed form (the symmetric
eigen-decomposition of a 2x2 matrix; [1]_), a Kalman filter unrolled for two states and one
output, and the simulation unrolled the same way, all compiled with numba; the fits are
``scipy.optimize.minimize(method="L-BFGS-B")`` with its default forward-difference gradient
(as pySIP's users run it) and ``scipy.optimize.least_squares`` on the hand-tuned residual,
from the same start and in the same box as rczone's fit. Nothing of rczone is used by the
limit: its likelihood is checked against rczone's ``Objective`` in this run (column "agree").

Every figure is measured in this process, interleaved with the limit (medians of several
rounds), so the ratios hold on a loaded machine even when the absolute times do not. Usage::

    python bench/limit.py                       # every figure; entries "limit_*" of bench/results.json
    python bench/limit.py --out /tmp/x.json     # elsewhere
    python bench/limit.py --skip-slow           # without the four-zone joint fit (seconds)

References
----------
.. [1] C. Moler, C. Van Loan, "Nineteen dubious ways to compute the exponential of a matrix,
   twenty-five years later", SIAM Review 45 (2003) 3-49 (method 14: eigenvectors).
.. [2] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23 (1978) 395-404 (the process-noise integral, here by eigenvectors).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402
from scipy.optimize import least_squares, minimize  # noqa: E402

import problems  # noqa: E402
from rczone.files.atomic import write_json_atomic  # noqa: E402

HERE = Path(__file__).resolve().parent
LOG_2PI = math.log(2.0 * math.pi)
#: The peer task's free sets: process noise on the measured state (7, the CLI's default noise) and on both (8).
FREE_7 = ["Ro", "Ri", "Cw", "Ci", "x0_Tw", "sigma_w_Ti", "sigma_v"]
FREE_8 = problems.PEER_FREE
FREE_LS = ["Ro", "Ri", "Cw", "Ci", "x0_Tw"]
SIGMA_X0 = 0.1
#: Issue 24's targets (ratio to the limit, or seconds for the four-zone fit).
TARGETS = {
    "limit_fit_ml_7": 1.0,
    "limit_fit_ml_8": 1.0,
    "limit_fit_ls": 2.0,
    "limit_value_and_gradient": 3.0,
    "limit_simulate": 5.0,
    "limit_ml_cost": 1.5,
    "limit_fit_4zone_s": 4.0,
}


# ----------------------------------------------------------------------------- the hand-tuned limit


@njit(cache=True)
def peer_matrices(Ro, Ri, Cw, Ci, dt, qw, qi):
    """FOH ``Phi, G0, G1`` (inputs To, Qh) and ``Qd`` of the peer model over ``dt``, by eigenvectors.

    In the coordinates ``s = sqrt(C) x`` the system matrix is symmetric, ``S = U diag(l) U'``;
    every integral of the exponential is then diagonal [1]_ [2]_.
    """
    a00 = -(1.0 / Ro + 1.0 / Ri) / Cw
    a11 = -1.0 / (Ri * Ci)
    s01 = 1.0 / (Ri * math.sqrt(Cw * Ci))  # symmetric off-diagonal of sqrt(C) A sqrt(C)^-1
    half = 0.5 * (a00 - a11)
    root = math.sqrt(half * half + s01 * s01)
    mean = 0.5 * (a00 + a11)
    l0, l1 = mean + root, mean - root
    # eigenvector of l0: (s01, l0 - a00) normalized
    v0, v1 = s01, l0 - a00
    nv = math.sqrt(v0 * v0 + v1 * v1)
    c, s = v0 / nv, v1 / nv
    U = np.array([[c, -s], [s, c]])
    lam = np.array([l0, l1])
    e = np.exp(lam * dt)
    f1 = np.expm1(lam * dt) / lam  # int_0^dt e^{l t} dt
    f2 = (e - 1.0 - lam * dt) / (lam * lam * dt)  # (1/dt) int_0^dt e^{l (dt - s)} s ds
    sq = np.array([math.sqrt(Cw), math.sqrt(Ci)])
    Phi = np.zeros((2, 2))
    H1 = np.zeros((2, 2))
    H2 = np.zeros((2, 2))
    for i in range(2):
        for j in range(2):
            a = b = g = 0.0
            for k in range(2):
                w = U[i, k] * U[j, k]
                a += w * e[k]
                b += w * f1[k]
                g += w * f2[k]
            Phi[i, j] = a * sq[j] / sq[i]
            H1[i, j] = b * sq[j] / sq[i]
            H2[i, j] = g * sq[j] / sq[i]
    # B = [[1/(Ro Cw), 0], [0, 1/Ci]]
    G = np.empty((2, 2))
    G1 = np.empty((2, 2))
    for i in range(2):
        G[i, 0] = H1[i, 0] / (Ro * Cw)
        G[i, 1] = H1[i, 1] / Ci
        G1[i, 0] = H2[i, 0] / (Ro * Cw)
        G1[i, 1] = H2[i, 1] / Ci
    G0 = G - G1
    # Qd = sqrt(C)^-1 U [(U' Qs U)_kl (e^{(lk+ll) dt} - 1) / (lk + ll)] U' sqrt(C)^-1, Qs = sqrt(C) Qc sqrt(C)
    Qs = np.array([[qw * Cw, 0.0], [0.0, qi * Ci]])
    W = U.T @ Qs @ U
    for k in range(2):
        for m in range(2):
            W[k, m] *= np.expm1((lam[k] + lam[m]) * dt) / (lam[k] + lam[m])
    Qsd = U @ W @ U.T
    Qd = np.empty((2, 2))
    for i in range(2):
        for j in range(2):
            Qd[i, j] = Qsd[i, j] / (sq[i] * sq[j])
    return Phi, G0, G1, Qd


@njit(cache=True)
def peer_nll(p, y, u, dt):
    """``-log L`` of the peer model; ``p = (Ro, Ri, Cw, Ci, x0_Tw, x0_Ti, sigma_w_Tw, sigma_w_Ti, sigma_v, sigma_x0)``."""
    Phi, G0, G1, Qd = peer_matrices(p[0], p[1], p[2], p[3], dt, p[6] * p[6], p[7] * p[7])
    x0, x1 = p[4], p[5]
    p00, p01, p11 = p[9] * p[9], 0.0, p[9] * p[9]
    r = p[8] * p[8]
    nll = 0.0
    n = y.shape[0]
    for k in range(n):
        yk = y[k]
        if yk == yk:
            s = p11 + r
            e = yk - x1
            k0 = p01 / s
            k1 = p11 / s
            x0 += k0 * e
            x1 += k1 * e
            p00 -= k0 * p01
            p01 -= k0 * p11
            p11 -= k1 * p11
            nll += 0.5 * (LOG_2PI + math.log(s) + e * e / s)
        if k == n - 1:
            break
        u0, u1, w0, w1 = u[k, 0], u[k, 1], u[k + 1, 0], u[k + 1, 1]
        n0 = Phi[0, 0] * x0 + Phi[0, 1] * x1 + G0[0, 0] * u0 + G0[0, 1] * u1 + G1[0, 0] * w0 + G1[0, 1] * w1
        n1 = Phi[1, 0] * x0 + Phi[1, 1] * x1 + G0[1, 0] * u0 + G0[1, 1] * u1 + G1[1, 0] * w0 + G1[1, 1] * w1
        x0, x1 = n0, n1
        a0 = Phi[0, 0] * p00 + Phi[0, 1] * p01
        a1 = Phi[0, 0] * p01 + Phi[0, 1] * p11
        b0 = Phi[1, 0] * p00 + Phi[1, 1] * p01
        b1 = Phi[1, 0] * p01 + Phi[1, 1] * p11
        p00 = Qd[0, 0] + a0 * Phi[0, 0] + a1 * Phi[0, 1]
        p01 = Qd[0, 1] + a0 * Phi[1, 0] + a1 * Phi[1, 1]
        p11 = Qd[1, 1] + b0 * Phi[1, 0] + b1 * Phi[1, 1]
    return nll


@njit(cache=True)
def peer_simulate(p, u, dt, out):
    """Room temperature of the peer model into ``out``; ``p = (Ro, Ri, Cw, Ci, x0_Tw, x0_Ti)``."""
    Phi, G0, G1, _ = peer_matrices(p[0], p[1], p[2], p[3], dt, 0.0, 0.0)
    x0, x1 = p[4], p[5]
    n = u.shape[0]
    out[0] = x1
    for k in range(n - 1):
        u0, u1, w0, w1 = u[k, 0], u[k, 1], u[k + 1, 0], u[k + 1, 1]
        n0 = Phi[0, 0] * x0 + Phi[0, 1] * x1 + G0[0, 0] * u0 + G0[0, 1] * u1 + G1[0, 0] * w0 + G1[0, 1] * w1
        n1 = Phi[1, 0] * x0 + Phi[1, 1] * x1 + G0[1, 0] * u0 + G0[1, 1] * u1 + G1[1, 0] * w0 + G1[1, 1] * w1
        x0, x1 = n0, n1
        out[k + 1] = x1
    return out


class Limit:
    """The hand-tuned fits of the peer task: parameter vectors in log space (``x0_Tw`` as it is)."""

    def __init__(self, data, fixed: dict[str, float]) -> None:
        self.y = np.ascontiguousarray(data.y[:, 0])
        self.u = np.ascontiguousarray(data.u)
        self.dt = float(data.t[1] - data.t[0])
        self.fixed = fixed
        self.buf = np.empty(self.y.size)

    def params(self, names: list[str], x: np.ndarray) -> np.ndarray:
        v = dict(self.fixed)
        v.update({n: (xi if n == "x0_Tw" else math.exp(xi)) for n, xi in zip(names, x)})
        keys = ("Ro", "Ri", "Cw", "Ci", "x0_Tw", "x0_Ti", "sigma_w_Tw", "sigma_w_Ti", "sigma_v")
        return np.array([v[k] for k in keys] + [SIGMA_X0])

    def nll(self, names: list[str], x: np.ndarray) -> float:
        return float(peer_nll(self.params(names, x), self.y, self.u, self.dt))

    def residual(self, names: list[str], x: np.ndarray) -> np.ndarray:
        yh = peer_simulate(self.params(names, x)[:6], self.u, self.dt, self.buf)
        return (self.y - yh) * math.sqrt(self.dt)

    def fit_ml(self, names, x_start, bounds) -> tuple[float, int]:
        res = minimize(lambda x: self.nll(names, x), x_start, method="L-BFGS-B", bounds=bounds)
        return float(res.fun), int(res.nfev)

    def fit_ls(self, names, x_start, bounds) -> tuple[float, int]:
        lo, hi = np.array(bounds).T
        res = least_squares(lambda x: self.residual(names, x), x_start, bounds=(lo, hi))
        return float(res.cost), int(res.nfev)  # cost = 0.5 sum r^2


# ----------------------------------------------------------------------------- measuring


#: The clock of :func:`timed`: wall time (``time.perf_counter``), or with ``--cpu`` this process's CPU
#: time (``time.process_time``), which other jobs on a shared machine take less away from.
CLOCK = {"clock": time.perf_counter}


def timed(f: Callable[[], object], repeats: int) -> float:
    """Median time of ``repeats`` calls (after one warm-up call), by :data:`CLOCK`."""
    clock = CLOCK["clock"]
    f()
    times = []
    for _ in range(repeats):
        t0 = clock()
        f()
        times.append(clock() - t0)
    return float(np.median(times))


def interleaved(ours: Callable[[], object], limit: Callable[[], object], rounds: int, repeats: int) -> tuple:
    """Median times of ``ours`` and ``limit``, measured alternately over ``rounds`` rounds."""
    a, b = [], []
    for _ in range(rounds):
        a.append(timed(ours, repeats))
        b.append(timed(limit, repeats))
    return float(np.median(a)), float(np.median(b))


def x_of(names: list[str], values: dict[str, float]) -> np.ndarray:
    return np.array([values[n] if n == "x0_Tw" else math.log(values[n]) for n in names])


def peer_setup():
    net, data = problems.peer_network(), problems.peer_data()
    truth = {**problems.PEER_TRUTH, **problems.PEER_NOISE, "x0_Tw": 26.6}
    start = {k: (v + 1.0 if k == "x0_Tw" else 2.0 * v) for k, v in truth.items()} | {"sigma_w_Ti": 1e-4}
    return net, data, truth, start


def figures(rounds: int, skip_slow: bool) -> dict[str, dict]:
    from rczone.estimation import Objective, fit, make_spec
    from rczone.estimation.costs import ml_cost
    from rczone.simulation import simulate

    net, data, truth, start = peer_setup()
    fixed_sx = {"sigma_x0_Tw": SIGMA_X0, "sigma_x0_Ti": SIGMA_X0}
    y0 = float(data.y[0, 0])
    limit = Limit(data, {**truth, "x0_Ti": y0, **fixed_sx})
    out: dict[str, dict] = {}

    def row(name: str, ours: float, lim: float, what: str, **extra) -> None:
        ratio = ours / lim
        target = TARGETS.get(name)
        out[name] = {
            "rczone_s": ours,
            "limit_s": lim,
            "ratio": ratio,
            "target_ratio": target,
            "description": what,
            "clock": "cpu" if CLOCK["clock"] is time.process_time else "wall",
            **extra,
        }
        met = (
            "" if target is None else ("  met" if ratio <= target else "  NOT met") + f" (target {target:g}x)"
        )
        print(f"{name:28s} {fmt(ours):>10s} {fmt(lim):>10s} {ratio:8.2f}x{met}")
        sys.stdout.flush()

    # one likelihood: the Objective (8 free) and ml_cost against the hand-tuned filter
    spec8 = make_spec(net, FREE_8, start={n: truth[n] for n in FREE_8 if truth[n] > 0}, fixed=fixed_sx)
    theta8 = np.array([truth[n] if truth[n] > 0 else 1e-6 for n in FREE_8])
    obj8 = Objective(net, data, spec8, "ml", "foh")
    eta8 = spec8.to_eta(theta8)
    vals8 = {**fixed_sx, **dict(zip(FREE_8, theta8))}
    x8 = x_of(FREE_8, vals8)
    agree = abs(obj8(eta8) / limit.nll(FREE_8, x8) - 1)
    t_obj, t_lim = interleaved(lambda: obj8(eta8), lambda: limit.nll(FREE_8, x8), rounds, 200)
    row(
        "limit_objective",
        t_obj,
        t_lim,
        "one -log L: Objective (8 free) / hand-tuned filter",
        agreement_rel=agree,
    )
    t_cost, t_obj2 = interleaved(lambda: ml_cost(net, vals8, data, "foh"), lambda: obj8(eta8), rounds, 50)
    row("limit_ml_cost", t_cost, t_obj2, "ml_cost (the public function) / Objective, same values")
    t_vg, t_v = interleaved(lambda: obj8.value_and_gradient(eta8), lambda: obj8(eta8), rounds, 50)
    row("limit_value_and_gradient", t_vg, t_v, "Objective.value_and_gradient / Objective (8 free)")
    ss = net.state_space(problems.PEER_TRUTH)
    x0 = np.array([truth["x0_Tw"], y0])
    p_sim = np.array([*(truth[k] for k in ("Ro", "Ri", "Cw", "Ci")), *x0])
    buf = np.empty(data.n_samples)
    t_sim, t_hs = interleaved(
        lambda: simulate(ss, data.t, data.u, x0=x0, hold="foh"),
        lambda: peer_simulate(p_sim, limit.u, limit.dt, buf),
        rounds,
        50,
    )
    row("limit_simulate", t_sim, t_hs, "simulate (public, from a state space) / hand-tuned simulation")

    # the fits: rczone's default (global) search against ONE hand-tuned L-BFGS-B from the same start, same box
    for name, free in (("limit_fit_ml_7", FREE_7), ("limit_fit_ml_8", FREE_8)):
        fixed = {**fixed_sx, **({"sigma_w_Tw": 0.0} if "sigma_w_Tw" not in free else {})}
        st = {n: start[n] for n in free}

        def ours(free=free, fixed=fixed, st=st):
            return fit(net, data, free, method="ml", start=st, fixed=fixed, hold="foh", uncertainty=False)

        res = ours()
        lim_names = free
        bounds = [
            (e.lower, e.upper) if n == "x0_Tw" else (math.log(e.lower), math.log(e.upper))
            for n, e in ((n, res.parameters[n]) for n in lim_names)
        ]
        lim_fixed = Limit(data, {**truth, "x0_Ti": y0, **fixed})
        xs = x_of(lim_names, st)
        lim_cost, lim_evals = lim_fixed.fit_ml(lim_names, xs, bounds)
        t_fit, t_lfit = interleaved(
            ours,
            lambda n=lim_names, xs=xs, b=bounds, lf=lim_fixed: lf.fit_ml(n, xs, b),
            rounds,
            1,
        )
        row(
            name,
            t_fit,
            t_lfit,
            f"default ML fit ({len(free)} free, global search) / one L-BFGS-B fit of the hand-tuned -log L (forward"
            " differences) from the same start in the same box",
            rczone_evals=res.n_evals,
            limit_evals=lim_evals,
            rczone_cost=res.objective_value,
            limit_cost=lim_cost,
        )
    # least squares: rczone's default LS fit against scipy least_squares on the hand-tuned residual
    st = {n: start[n] for n in FREE_LS}

    def ours_ls():
        return fit(net, data, FREE_LS, method="ls", start=st, hold="foh", uncertainty=False)

    res = ours_ls()
    bounds = [
        (e.lower, e.upper) if n == "x0_Tw" else (math.log(e.lower), math.log(e.upper))
        for n, e in ((n, res.parameters[n]) for n in FREE_LS)
    ]
    xs = x_of(FREE_LS, st)
    lim_cost, lim_evals = limit.fit_ls(FREE_LS, xs, bounds)
    t_fit, t_lfit = interleaved(ours_ls, lambda: limit.fit_ls(FREE_LS, xs, bounds), rounds, 1)
    row(
        "limit_fit_ls",
        t_fit,
        t_lfit,
        "default LS fit (5 free, global search) / scipy least_squares on the hand-tuned residual (same start, box)",
        rczone_evals=res.n_evals,
        limit_evals=lim_evals,
        rczone_cost=res.objective_value,
        limit_cost=2.0 * lim_cost,
    )
    if not skip_slow:
        net4, data4 = problems.four_zones(), problems.four_zone_data()
        truth4 = {**problems.FOUR_ZONE_TRUTH, **problems.FOUR_ZONE_NOISE}
        fixed4 = {k: v for k, v in problems.FOUR_ZONE_NOISE.items() if k not in problems.FOUR_ZONE_FREE}
        rng = np.random.default_rng(20260512)
        start4 = {n: truth4[n] * float(np.exp(rng.uniform(-0.5, 0.5))) for n in problems.FOUR_ZONE_FREE}
        t0 = time.perf_counter()
        res4 = fit(
            net4, data4, problems.FOUR_ZONE_FREE, method="ml", start=start4, fixed=fixed4, uncertainty=False
        )
        t4 = time.perf_counter() - t0
        out["limit_fit_4zone_s"] = {
            "rczone_s": t4,
            "target_s": TARGETS["limit_fit_4zone_s"],
            "rczone_evals": res4.n_evals,
            "rczone_cost": res4.objective_value,
            "description": "joint ML fit of four coupled zones (22 free), default global search, seconds (one run)",
        }
        met = "met" if t4 <= TARGETS["limit_fit_4zone_s"] else "NOT met"
        print(f"{'limit_fit_4zone_s':28s} {fmt(t4):>10s} {'':>10s} {'':>9s} {met} (target 4 s)")
        # after the fit (whose one run includes loading the kernels): what one of its evaluations costs
        spec4 = make_spec(net4, problems.FOUR_ZONE_FREE, start=start4, fixed=fixed4)
        obj4 = Objective(net4, data4, spec4, "ml")
        eta4 = spec4.to_eta(spec4.start)
        t_grad, t_val = interleaved(lambda: obj4.value_and_gradient(eta4), lambda: obj4(eta4), rounds, 20)
        t_fwd = timed(lambda: obj4.theta_value_and_gradient(spec4.start), 5)
        row(
            "limit_4zone_value_and_gradient",
            t_grad,
            t_val,
            "four zones (22 free): value + exact gradient (reverse pass) / one value, both rczone's Objective;"
            " forward_sensitivities_s = the forward-sensitivity pass (the Fisher curvature's)",
            forward_sensitivities_s=t_fwd,
        )
    return out


def fmt(s: float) -> str:
    for unit, f in (("s", 1.0), ("ms", 1e3), ("us", 1e6)):
        if s * f >= 1.0:
            return f"{s * f:.3g} {unit}"
    return f"{s * 1e9:.3g} ns"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE / "results.json")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (medians)")
    ap.add_argument("--skip-slow", action="store_true", help="skip the four-zone joint fit")
    ap.add_argument(
        "--cpu",
        action="store_true",
        help="time by this process's CPU time instead of wall time (a shared machine)",
    )
    args = ap.parse_args(argv)
    if args.cpu:
        CLOCK["clock"] = time.process_time
    print(
        f"issue 24 figures on {os.cpu_count()} core(s), load {os.getloadavg()[0]:.2f}; ratio = rczone / limit"
        f" ({'CPU' if args.cpu else 'wall'} time)"
    )
    print(f"{'figure':28s} {'rczone':>10s} {'limit':>10s} {'ratio':>9s}")
    got = figures(args.rounds, args.skip_slow)
    try:
        import json

        previous = json.loads(args.out.read_text())
    except (OSError, ValueError):
        previous = {}
    write_json_atomic(args.out, {**previous, **got})
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
