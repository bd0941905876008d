"""Posterior samplers on the 2-state task: draws and effective samples per second, beside the ML fit.

Usage::

    python bench/sampling.py [--draws 1000] [--tune 1000] [--chains 4] [--out FILE]

The task is the 2-state peer model of ``bench/problems.py`` (pySIP's ``TwTi_RoRi``) on 720
half-hourly samples simulated at known values; free: Ro, Ri, Cw, Ci, the wall's process noise and
the measurement noise (6 parameters), the log posterior of :mod:`rczone.estimation.sampling` (the
Kalman likelihood, flat priors on log R and log C, uniform on the noise levels) in the sampler's
unbounded variable. Every sampler starts from the same over-dispersed points around the ML
estimate and is timed warm-up included:

* ``nutpie``: NUTS with nutpie's adaptation, calling back the exact gradient (what rczone uses);
* ``mici``: mici's dynamic multinomial HMC (NUTS-like), step size and diagonal metric adapted, the
  same gradient; skipped when mici is not installed (it is not a dependency of rczone);
* ``emcee``: the affine-invariant ensemble (no gradient: one likelihood per step and walker),
  ``8 d`` walkers; its effective samples from emcee's integrated autocorrelation time; skipped
  when emcee is not installed.

The effective sample size is the smallest bulk ESS over the parameters (ArviZ, rank-normalized;
Vehtari et al. 2021); "per gradient" counts log-density evaluations of any kind. Beside them, the
ML fit's own cost: one L-BFGS search (what places the chains) and the default global search.
Prints a table and writes ``{"sampling": {...}}`` to ``--out`` (default: a temporary file, so
``bench/results.json`` is not rewritten).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import problems  # noqa: E402
from rczone.estimation import Objective, fit, make_spec  # noqa: E402
from rczone.estimation.methods.mcmc import McmcOptions  # noqa: E402
from rczone.estimation.optimize import minimize_from  # noqa: E402
from rczone.estimation.sampling import over_dispersed_starts, posterior_of, sample  # noqa: E402
from rczone.files.atomic import write_json_atomic  # noqa: E402

FREE = ["Ro", "Ri", "Cw", "Ci", "sigma_w_Tw", "sigma_v"]
FIXED = {"sigma_w_Ti": 0.0, "sigma_x0_Tw": 0.1, "sigma_x0_Ti": 0.1, "x0_Tw": 26.6, "x0_Ti": 26.7}


def task():
    net, data = problems.peer_network(), problems.peer_data()
    spec = make_spec(net, FREE, fixed=FIXED)
    return net, data, posterior_of(Objective(net, data, spec, "mcmc", "foh"))


def ess_bulk(theta: np.ndarray) -> np.ndarray:
    """Bulk ESS per parameter of draws shaped (chains, draws, d)."""
    import arviz as az

    return np.array([float(az.ess(theta[..., i], method="bulk")) for i in range(theta.shape[-1])])


def run_nutpie(logp, settings, rng) -> dict:
    t0 = time.perf_counter()
    out = sample(logp, settings=settings, rng=rng)
    wall = time.perf_counter() - t0
    post = out.posterior
    return {
        "seconds": wall,
        "draws": post.flat.shape[0],
        "evaluations": post.n_gradients + out.mode.n_evals,
        "ess": float(min(post.ess_bulk)),
        "rhat_max": float(post.rhat.max()),
        "divergences": post.divergences,
    }


def diverging(stats) -> int:
    """Divergent transitions in mici's statistics (nested dictionaries of arrays)."""
    if isinstance(stats, dict):
        return sum(int(np.sum(v)) if k == "diverging" else diverging(v) for k, v in stats.items())
    if isinstance(stats, (list, tuple)):
        return sum(diverging(v) for v in stats)
    return 0


def run_mici(logp, settings, rng, starts) -> dict | None:
    try:
        import mici
    except ImportError:
        return None
    calls = [0]

    def neg(z):
        calls[0] += 1
        return -logp(z)[0]

    def grad_neg(z):
        calls[0] += 1
        v, g = logp(z)
        return -g, -v

    system = mici.systems.EuclideanMetricSystem(neg, grad_neg_log_dens=grad_neg)
    integrator = mici.integrators.LeapfrogIntegrator(system)
    sampler = mici.samplers.DynamicMultinomialHMC(system, integrator, rng)
    adapters = [mici.adapters.DualAveragingStepSizeAdapter(0.8), mici.adapters.OnlineVarianceMetricAdapter()]
    t0 = time.perf_counter()
    _, traces, stats = sampler.sample_chains(
        settings.tune,
        settings.draws,
        list(starts),
        adapters=adapters,
        n_process=1,
        display_progress=False,
        trace_funcs=[lambda state: {"z": state.pos}],
    )
    wall = time.perf_counter() - t0
    theta = logp.to_theta(np.stack(traces["z"]))
    return {
        "seconds": wall,
        "draws": int(theta.shape[0] * theta.shape[1]),
        "evaluations": calls[0],
        "ess": float(min(ess_bulk(theta))),
        "rhat_max": None,
        "divergences": diverging(stats),
    }


def run_emcee(logp, settings, rng, center) -> dict | None:
    try:
        import emcee
    except ImportError:
        return None
    d = center.size
    walkers = 8 * d
    steps = settings.tune + settings.draws
    start = center + 1e-3 * rng.standard_normal((walkers, d))
    ens = emcee.EnsembleSampler(walkers, d, logp.value)
    t0 = time.perf_counter()
    ens.run_mcmc(start, steps, progress=False)
    wall = time.perf_counter() - t0
    tau = ens.get_autocorr_time(discard=settings.tune, tol=0)
    ess = settings.draws * walkers / float(np.max(tau))
    return {
        "seconds": wall,
        "draws": settings.draws * walkers,
        "evaluations": steps * walkers,
        "ess": ess,
        "rhat_max": None,
        "divergences": None,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--tune", type=int, default=1000)
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "rczone-bench-sampling.json")
    args = ap.parse_args(argv)
    settings = McmcOptions(draws=args.draws, tune=args.tune, chains=args.chains)
    net, data, logp = task()
    spec = logp.objective.spec
    logp(logp.to_z(spec.start))  # compile the kernels before any clock runs
    t0 = time.perf_counter()
    mode = minimize_from(logp.objective, spec, spec.start, "lbfgs")
    ml_local = time.perf_counter() - t0
    t0 = time.perf_counter()
    fit(net, data, FREE, method="ml", fixed=FIXED, hold="foh")
    ml_global = time.perf_counter() - t0
    starts = over_dispersed_starts(logp, mode.end, args.chains, np.random.default_rng(1))
    rows = {"nutpie": run_nutpie(logp, settings, np.random.default_rng(1))}
    rows["mici"] = run_mici(logp, settings, np.random.default_rng(1), starts)
    rows["emcee"] = run_emcee(logp, settings, np.random.default_rng(1), logp.to_z(mode.end))
    print(
        f"2-state task, {data.n_samples} samples, {len(FREE)} free; load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    print(
        f"ML: one L-BFGS search {ml_local:.2f} s ({mode.n_evals} evaluations); global search {ml_global:.2f} s"
    )
    print(
        f"{'sampler':8s} {'seconds':>8s} {'draws/s':>8s} {'min ESS':>8s} {'ESS/s':>8s} {'evals':>8s} {'ESS/eval':>9s} {'R-hat':>6s} {'div':>4s}"
    )
    out = {"ml_lbfgs_s": ml_local, "ml_global_s": ml_global, "load": os.getloadavg()[0], "samplers": {}}
    for name, r in rows.items():
        if r is None:
            print(f"{name:8s} not installed")
            continue
        r["draws_per_s"] = r["draws"] / r["seconds"]
        r["ess_per_s"] = r["ess"] / r["seconds"]
        per_eval = r["ess"] / r["evaluations"] if r["evaluations"] else float("nan")
        rhat = f"{r['rhat_max']:.3f}" if r["rhat_max"] is not None else "-"
        div = str(r["divergences"]) if r["divergences"] is not None else "-"
        ev = str(r["evaluations"]) if r["evaluations"] else "-"
        print(
            f"{name:8s} {r['seconds']:8.1f} {r['draws_per_s']:8.0f} {r['ess']:8.0f} {r['ess_per_s']:8.1f} {ev:>8s} {per_eval:9.3f} {rhat:>6s} {div:>4s}"
        )
        out["samplers"][name] = r
    write_json_atomic(args.out, {"sampling": out})
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
