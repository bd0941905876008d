"""Posterior sampling: the No-U-Turn sampler on the Kalman likelihood and the declared priors.

The method ``"mcmc"`` of :mod:`rczone.estimation.methods` ends here instead of in the global
search. The log posterior of the free parameters is

    log p(z | y) = log L(theta) + log p_eta(eta) + log |d eta / d z| + const,

with ``log L`` the Kalman-filter likelihood of the ML objective (untempered), ``p_eta`` the prior
on the optimizer's variable ``eta`` (:mod:`rczone.estimation.priors`: the declared priors; for the
other parameters flat in ``eta`` within the bounds, log-uniform for R and C, uniform in sigma for a
noise level) and ``z = logit((eta - lo) / (hi - lo))``
the unbounded variable the sampler moves in (log for positive parameters, then logit of the box:
:meth:`~rczone.estimation.parameters.ParameterSpec.to_z`). The gradient is exact: the
Objective's forward sensitivities, times the two Jacobians.

The sampler is nutpie's NUTS (Hoffman & Gelman 2014, with nutpie's mass-matrix adaptation from
gradients and draws), called back into Python for each log density and gradient; the draws and
sample statistics come back as ArviZ ``InferenceData``, whose rank-normalized R-hat and effective
sample sizes (Vehtari et al. 2021) decide convergence (:mod:`rczone.estimation.posterior`).
docs/posterior.md compares it with other samplers on the 2-state task.

The chains start around the maximum of the likelihood found by one L-BFGS search from the start
values, spread by twice the standard deviation its Fisher information gives (over-dispersed
starts make R-hat meaningful; Gelman et al. 2013, sec. 11.4).

References
----------
Hoffman, M. D. & Gelman, A. (2014). The No-U-Turn sampler: adaptively setting path lengths in
Hamiltonian Monte Carlo. *Journal of Machine Learning Research* 15, 1593-1623.
Vehtari, A., Gelman, A., Simpson, D., Carpenter, B. & Bürkner, P.-C. (2021). Rank-normalization,
folding, and localization: an improved R-hat for assessing convergence of MCMC. *Bayesian
Analysis* 16(2), 667-718.
Gelman, A., Carlin, J. B., Stern, H. S., Dunson, D. B., Vehtari, A. & Rubin, D. B. (2013).
*Bayesian Data Analysis*, 3rd ed. CRC Press.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from rczone.errors import ParameterError, RczoneError
from rczone.estimation.costs import Objective
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.optimize import StartOutcome, minimize_from
from rczone.estimation.posterior import Posterior
from rczone.estimation.priors import LogPrior, log_prior
from rczone.estimation.result import FitResult
from rczone.results import Estimate


@dataclass(frozen=True, eq=False)
class LogPosterior:
    """``log p(z | y)`` and its gradient in the sampler's variable ``z`` (see the module notes).

    Attributes
    ----------
    objective : Objective
        ``-log L`` (an ML objective: untempered, no prior of its own).
    prior : LogPrior
        ``-log p_eta`` of the free parameters.
    """

    objective: Objective
    prior: LogPrior

    def __call__(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """``(log p, d log p / d z)``; ``(-inf, zeros)`` where the model is invalid."""
        spec = self.objective.spec
        z = np.asarray(z, dtype=float)
        lo, hi = spec.eta_lower, spec.eta_upper
        f = 0.5 * (1.0 + np.tanh(0.5 * z))
        eta = lo + (hi - lo) * f
        theta = spec.to_theta(eta)
        j, g, _ = self.objective.theta_value_and_gradient(theta)
        pen, dpen, _ = self.prior.terms(theta)
        one_minus = 0.5 * (1.0 - np.tanh(0.5 * z))
        # log f and log (1 - f) without underflow far out in the tails
        log_jac = float(np.sum(np.log(hi - lo) - np.logaddexp(0.0, -z) - np.logaddexp(0.0, z)))
        value = -(j + pen) + log_jac
        if not math.isfinite(value):
            return -math.inf, np.zeros(z.size)
        deta_dz = (hi - lo) * f * one_minus
        grad = -(g + dpen) * spec.jacobian(eta) * deta_dz + (1.0 - 2.0 * f)
        return value, grad

    def value(self, z: np.ndarray) -> float:
        """``log p`` alone (one likelihood evaluation, no sensitivities: for samplers without gradients)."""
        spec = self.objective.spec
        z = np.asarray(z, dtype=float)
        theta = self.to_theta(z)
        j = self.objective.theta_cost(theta)
        pen = self.prior.terms(theta)[0]
        log_jac = float(
            np.sum(np.log(spec.eta_upper - spec.eta_lower) - np.logaddexp(0.0, -z) - np.logaddexp(0.0, z))
        )
        value = -(j + pen) + log_jac
        return value if math.isfinite(value) else -math.inf

    def to_z(self, theta: np.ndarray) -> np.ndarray:
        """The sampler's variable of physical values ``theta``."""
        spec = self.objective.spec
        return spec.to_z(spec.to_eta(theta))

    def to_theta(self, z: np.ndarray) -> np.ndarray:
        """Physical values of the sampler's variable ``z`` (last axis: the parameters)."""
        spec = self.objective.spec
        return spec.to_theta(spec.from_z(z))


def posterior_of(objective: Objective) -> LogPosterior:
    """The log posterior of an ML ``objective`` with the network's declared priors (the ``"flat"`` default otherwise).

    Parameters
    ----------
    objective : Objective
        Of a method whose kernel is the Kalman likelihood and that adds no prior of its own.

    Returns
    -------
    LogPosterior
    """
    if objective.map_prior is not None or objective.likelihood_weight != 1.0:
        raise ParameterError("posterior sampling needs the untempered likelihood (an ML objective)")
    return LogPosterior(objective, log_prior(objective.spec, objective.network.priors, default="flat"))


class _Run(NamedTuple):
    """What one sampler run returns to :func:`sample`."""

    z: np.ndarray  #: (chains, draws, d)
    stats: Any  #: ArviZ InferenceData
    seconds: float
    sampler: str


def _nutpie() -> Any:
    """The nutpie module, or a one-line error saying how to install it."""
    try:
        import nutpie
        from nutpie.compiled_pyfunc import from_pyfunc
    except ImportError:
        raise RczoneError(
            "posterior sampling needs nutpie and ArviZ; install the extra: pip install 'rczone[mcmc]'"
        ) from None
    return nutpie, from_pyfunc


def _run_nuts(
    logp: LogPosterior, starts: np.ndarray, settings: McmcOptions, seed: int, progress: Any = None
) -> _Run:
    """NUTS (nutpie) from ``starts`` (one row of ``z`` per chain).

    ``progress.advance(done, total)`` is told the draws of all chains, warm-up included, as they come:
    nutpie hands each stored draw to the ``expand`` function once, and its own bar (a terminal's
    indicatif bar, or HTML in a notebook) is off, as it would ignore ``--quiet`` and redirection.
    """
    nutpie, from_pyfunc = _nutpie()
    d = starts.shape[1]
    names = ["z"]
    chain_of_seed: dict[int, int] = {}

    def make_logp():
        return logp

    total = settings.chains * (settings.draws + settings.tune)
    drawn = [0]

    def expand(z):
        drawn[0] += 1
        if progress is not None and drawn[0] % 10 == 0:
            progress.advance(drawn[0], total)
        return {"z": np.asarray(z, dtype=float).copy()}

    def make_expand(_seed1, _seed2, _chain):
        return expand

    def initial_point(s: int) -> np.ndarray:
        # nutpie asks once per chain with a seed of its own; hand the starts out in turn
        k = chain_of_seed.setdefault(int(s), len(chain_of_seed))
        return starts[k % starts.shape[0]].copy()

    model = from_pyfunc(
        d, make_logp, make_expand, [np.dtype("float64")], [(d,)], names, make_initial_point_fn=initial_point
    )
    t0 = time.perf_counter()
    try:
        idata = nutpie.sample(
            model,
            draws=settings.draws,
            tune=settings.tune,
            chains=settings.chains,
            cores=1,  # the log density holds the GIL: more threads only contend for it
            seed=int(seed),
            progress_bar=False,
            save_warmup=True,
        )
    except (KeyboardInterrupt, SystemExit, MemoryError):
        raise
    except BaseException as exc:  # nutpie's Rust panics derive from BaseException
        raise RczoneError(
            f"the sampler (nutpie {nutpie.__version__}) failed: {' '.join(str(exc).split())[:200]}; try"
            " more warm-up draws (--tune) or fit by ML first"
        ) from None
    seconds = time.perf_counter() - t0
    z = np.asarray(idata.posterior["z"].values, dtype=float)
    return _Run(z, idata, seconds, f"nutpie {nutpie.__version__} (NUTS)")


def over_dispersed_starts(
    logp: LogPosterior, mode: np.ndarray, chains: int, rng: np.random.Generator
) -> np.ndarray:
    """Over-dispersed starts around ``mode``: two Fisher standard deviations in eta, at most 0.5.

    Parameters
    ----------
    logp : LogPosterior
        The log posterior (its objective gives the Fisher information).
    mode : ndarray, shape (d,)
        Physical values the starts scatter around (the ML estimate).
    chains : int
        Starts wanted.
    rng : numpy.random.Generator
        Draws the scatter.

    Returns
    -------
    ndarray, shape (chains, d)
        Starts in the sampler's variable ``z``, inside the bounds.
    """
    spec = logp.objective.spec
    eta = spec.to_eta(mode)
    curv = logp.objective.curvature(eta)
    sd = np.where(curv > 0, 2.0 / np.sqrt(np.where(curv > 0, curv, 1.0)), 0.5)
    sd = np.minimum(sd, 0.5 * np.ones_like(sd))
    width = spec.eta_upper - spec.eta_lower
    out = np.empty((chains, spec.n_free))
    for k in range(chains):
        e = eta + sd * rng.standard_normal(spec.n_free)
        e = np.clip(e, spec.eta_lower + 1e-3 * width, spec.eta_upper - 1e-3 * width)
        out[k] = spec.to_z(e)
    return out


class Sampled(NamedTuple):
    """The posterior and the search that placed its chains."""

    posterior: Posterior
    mode: StartOutcome


def sample(
    logp: LogPosterior, *, settings: McmcOptions, rng: np.random.Generator, progress: Any = None
) -> Sampled:
    """Draw from ``logp``: one L-BFGS search for the mode, then NUTS chains around it.

    Parameters
    ----------
    logp : LogPosterior
        The log posterior (:func:`posterior_of`).
    settings : McmcOptions
        Draws, warm-up and chains.
    rng : numpy.random.Generator
        Draws the starts and the sampler's seed.
    progress : object, optional
        Told ``progress.advance(done, total)`` as the chains' draws come in; None: nothing.

    Returns
    -------
    Sampled
    """
    import arviz as az

    spec = logp.objective.spec
    t0 = time.perf_counter()
    mode = minimize_from(logp.objective, spec, spec.start, "lbfgs")
    mode_seconds = time.perf_counter() - t0
    starts = over_dispersed_starts(logp, mode.end, settings.chains, rng)
    run = _run_nuts(logp, starts, settings, int(rng.integers(2**31 - 1)), progress)
    theta = logp.to_theta(run.z)
    post = az.convert_to_inference_data(
        {n: theta[..., i] for i, n in enumerate(spec.names)}
    )  # physical values, for ArviZ's diagnostics and plots
    post.extend(run.stats, join="left")
    stats = run.stats.sample_stats
    diverging = stats["diverging"].values
    steps = [
        g["n_steps"].values.sum() for g in (stats, run.stats.get("warmup_sample_stats")) if g is not None
    ]
    rhat = az.rhat(post, method="rank")
    ess_bulk = az.ess(post, method="bulk")
    ess_tail = az.ess(post, method="tail")
    posterior = Posterior(
        names=spec.names,
        draws=theta,
        rhat=np.array([float(rhat[n]) for n in spec.names]),
        ess_bulk=np.array([float(ess_bulk[n]) for n in spec.names]),
        ess_tail=np.array([float(ess_tail[n]) for n in spec.names]),
        divergences=int(np.sum(diverging)),
        tune=settings.tune,
        seconds=run.seconds,
        n_gradients=int(sum(steps)),
        sampler=run.sampler,
        prior=logp.prior.to_dict(),
        inference_data=post,
        mode_seconds=mode_seconds,
    )
    return Sampled(posterior, mode)


def sample_fit(
    objective: Objective, *, settings: McmcOptions, rng: np.random.Generator, progress: Any = None
) -> FitResult:
    """A :class:`~rczone.estimation.result.FitResult` of posterior means and standard deviations.

    Each :class:`~rczone.results.Estimate` holds the posterior mean (``value``) and standard
    deviation (``std_error``); ``correlation`` is that of the draws in ``eta``; the objective,
    the log-likelihood and the RMSE are those at the posterior mean; the flags are the
    posterior's failed convergence checks (:meth:`~rczone.estimation.posterior.Posterior.issues`)
    and estimates at a bound.

    Parameters
    ----------
    objective : Objective
        The ML objective of the problem (:func:`posterior_of`).
    settings : McmcOptions
        Draws, warm-up and chains.
    rng : numpy.random.Generator
        Draws the starts and the sampler's seed.
    progress : object, optional
        Told how far the chains are (:func:`sample`); None: nothing.

    Returns
    -------
    FitResult
    """
    from rczone.estimation.methods import method_of
    from rczone.estimation.minimize import log_likelihood, rmse_of, unit_of

    logp = posterior_of(objective)
    run = sample(logp, settings=settings, rng=rng, progress=progress)
    post = run.posterior
    spec, net, data = objective.spec, objective.network, objective.data
    mean, sd = post.mean, post.sd
    eta = np.where(spec.log, np.log(np.where(spec.log, post.flat, 1.0)), post.flat)
    corr = np.corrcoef(eta, rowvar=False) if spec.n_free > 1 else np.ones((1, 1))
    near = spec.near_bound(mean)
    issues = [code for code, _ in post.issues()]
    flags = [text for _, text in post.issues()]
    for n, b in zip(spec.names, near):
        if b:
            issues.append("at_bound")
            flags.append(f"the posterior of {n} piles up at a bound")
    cost = objective.theta_cost(mean)
    values = spec.values(mean)
    meth = method_of(objective.method)
    parameters = {
        n: Estimate(
            n, float(v), float(e), float(lo), float(hi), float(c), bool(b), unit_of(net, n), k, bool(lg)
        )
        for n, v, e, lo, hi, c, b, k, lg in zip(
            spec.names, mean, sd, spec.lower, spec.upper, spec.construction, near, spec.kinds, spec.log
        )
    }
    return FitResult(
        parameters=parameters,
        correlation=corr,
        objective_value=cost,
        method=objective.method,
        engine=objective.engine,
        optimizer=post.sampler,
        hold=objective.hold,
        converged=not post.issues(),
        n_evals=run.mode.n_evals + post.n_gradients,
        starts=(run.mode,),
        best_start=0,
        rmse_K=rmse_of(net, values, data, objective.method, objective.hold),
        rmse_kind=meth.rmse_kind,
        llf=log_likelihood(net, values, data, meth, objective.hold, cost),
        nobs=int(np.isfinite(data.y).sum()),
        fixed={k: v for k, v in values.items() if k not in spec.names},
        flags=tuple(flags),
        issues=tuple(dict.fromkeys(issues)),
        posterior=post,
    )
