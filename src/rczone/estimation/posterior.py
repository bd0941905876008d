"""The draws of a posterior and the diagnostics that say whether they can be used.

A sampler's output is trusted only when the chains agree and explore: the rank-normalized split
R-hat below :data:`RHAT_MAX`, a bulk and tail effective sample size of at least
:data:`ESS_MIN_PER_CHAIN` per chain, and no divergent transition (Vehtari, Gelman, Simpson,
Carpenter & Bürkner 2021 recommend exactly these thresholds; a divergence means the sampler
missed part of the posterior: Betancourt 2017, sec. 6.2). :meth:`Posterior.issues` names each
failed check; :func:`rczone.estimation.sampling.sample_fit` turns them into the fit's flags.

References
----------
Vehtari, A., Gelman, A., Simpson, D., Carpenter, B. & Bürkner, P.-C. (2021). Rank-normalization,
folding, and localization: an improved R-hat for assessing convergence of MCMC. *Bayesian
Analysis* 16(2), 667-718.
Betancourt, M. (2017). A conceptual introduction to Hamiltonian Monte Carlo. arXiv:1701.02434.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rczone.errors import ParameterError
from rczone.results import json_number

#: Largest R-hat of a converged run (Vehtari et al. 2021).
RHAT_MAX = 1.01
#: Smallest bulk and tail effective sample size per chain of a converged run (Vehtari et al. 2021: 100).
ESS_MIN_PER_CHAIN = 100
#: Draws a fitted model keeps for posterior predictive bands (:func:`rczone.calibration.prediction`).
KEPT_DRAWS = 200

#: Codes of the posterior's issues (added to :data:`rczone.estimation.result.ISSUES`).
POSTERIOR_ISSUES = {
    "rhat": f"R-hat of an estimate is {RHAT_MAX:g} or more: the chains disagree",
    "ess": f"an effective sample size is below {ESS_MIN_PER_CHAIN} per chain",
    "divergences": "divergent transitions: the sampler missed part of the posterior",
}


@dataclass(frozen=True, eq=False)
class Posterior:
    """Draws of the free parameters and their convergence diagnostics.

    Attributes
    ----------
    names : tuple of str
        Free parameters, in order.
    draws : ndarray, shape (chains, draws, d)
        Physical values (SI units), warm-up excluded.
    rhat : ndarray, shape (d,)
        Rank-normalized split R-hat per parameter.
    ess_bulk, ess_tail : ndarray, shape (d,)
        Bulk and tail effective sample sizes per parameter (over all chains).
    divergences : int
        Divergent transitions after warm-up.
    tune : int
        Warm-up draws per chain (discarded).
    seconds : float
        Wall time of the sampler, warm-up included, s.
    n_gradients : int
        Log-density and gradient evaluations, warm-up included.
    sampler : str
        The sampler and its version.
    prior : dict
        The prior of each free parameter (:meth:`rczone.estimation.priors.LogPrior.to_dict`;
        None: flat in the optimizer's variable within the bounds).
    inference_data : object, optional
        ArviZ ``InferenceData`` of the run (posterior and sample statistics), for ArviZ's own
        plots and diagnostics; not serialized.
    mode_seconds : float
        Wall time of the L-BFGS search for the maximum of the likelihood that placed the chains,
        s: the cost of an ML fit's local search, to set the sampler's against.
    """

    names: tuple[str, ...]
    draws: np.ndarray
    rhat: np.ndarray
    ess_bulk: np.ndarray
    ess_tail: np.ndarray
    divergences: int
    tune: int
    seconds: float
    n_gradients: int
    sampler: str
    prior: dict
    inference_data: Any = None
    mode_seconds: float = math.nan

    @property
    def n_chains(self) -> int:
        """Chains run."""
        return int(self.draws.shape[0])

    @property
    def n_draws(self) -> int:
        """Draws kept per chain."""
        return int(self.draws.shape[1])

    @property
    def draws_per_second(self) -> float:
        """Kept draws (all chains) per second of sampling, warm-up included in the time."""
        return self.n_chains * self.n_draws / self.seconds if self.seconds > 0 else math.nan

    @property
    def flat(self) -> np.ndarray:
        """Every kept draw, chains concatenated, shape ``(chains * draws, d)``."""
        return self.draws.reshape(-1, len(self.names))

    @property
    def mean(self) -> np.ndarray:
        """Posterior mean per parameter (SI units)."""
        return self.flat.mean(axis=0)

    @property
    def sd(self) -> np.ndarray:
        """Posterior standard deviation per parameter (SI units)."""
        return self.flat.std(axis=0, ddof=1)

    def interval(self, level: float = 0.9) -> np.ndarray:
        """Equal-tailed credible intervals: the ``(1 - level) / 2`` and ``(1 + level) / 2`` quantiles.

        Parameters
        ----------
        level : float
            Posterior probability inside the interval, in (0, 1).

        Returns
        -------
        ndarray, shape (d, 2)
            Lower and upper end per parameter, SI units.
        """
        if not 0 < level < 1:
            raise ParameterError(f"level must be in (0, 1), got {level!r}")
        q = np.quantile(self.flat, [(1 - level) / 2, (1 + level) / 2], axis=0)
        return q.T

    def issues(self) -> list[tuple[str, str]]:
        """``(code, sentence)`` for each failed convergence check (empty for a usable run)."""
        out = []
        bad = [n for n, r in zip(self.names, self.rhat) if not r < RHAT_MAX]
        if bad:
            worst = float(np.nanmax(np.where(np.isfinite(self.rhat), self.rhat, np.inf)))
            out.append(
                ("rhat", f"R-hat {worst:.3f} >= {RHAT_MAX:g} for {', '.join(bad)}: the chains disagree")
            )
        floor = ESS_MIN_PER_CHAIN * self.n_chains
        ess = np.minimum(self.ess_bulk, self.ess_tail)
        low = [n for n, e in zip(self.names, ess) if not e >= floor]
        if low:
            out.append(
                (
                    "ess",
                    f"effective sample size {float(np.nanmin(ess)):.0f} < {floor} ({ESS_MIN_PER_CHAIN} per"
                    f" chain) for {', '.join(low)}: run more draws (--draws)",
                )
            )
        if self.divergences > 0:
            out.append(
                (
                    "divergences",
                    f"{self.divergences} divergent transitions: the sampler missed part of the posterior"
                    " (more warm-up, --tune, or tighter priors)",
                )
            )
        return out

    def to_frame(self):
        """Every kept draw as a row: ``chain``, ``draw`` and one column per parameter (SI units)."""
        import pandas as pd

        chains, draws, _ = self.draws.shape
        frame = pd.DataFrame(self.flat, columns=list(self.names))
        frame.insert(0, "draw", np.tile(np.arange(draws), chains))
        frame.insert(0, "chain", np.repeat(np.arange(chains), draws))
        return frame

    def kept(self, n: int = KEPT_DRAWS) -> np.ndarray:
        """``n`` draws evenly spaced through all chains (fewer if there are fewer), shape ``(n, d)``."""
        flat = self.flat
        idx = np.unique(np.linspace(0, flat.shape[0] - 1, min(n, flat.shape[0])).round().astype(int))
        return flat[idx]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready diagnostics, per-parameter summaries and :meth:`kept` draws (NaN becomes ``None``)."""
        q90, q95 = self.interval(0.9), self.interval(0.95)
        mean, sd = self.mean, self.sd
        return {
            "sampler": self.sampler,
            "chains": self.n_chains,
            "draws": self.n_draws,
            "tune": self.tune,
            "divergences": int(self.divergences),
            "seconds": json_number(self.seconds),
            "draws_per_second": json_number(self.draws_per_second),
            "n_gradients": int(self.n_gradients),
            "ml_search_seconds": json_number(self.mode_seconds),
            "rhat_max": RHAT_MAX,
            "ess_min": ESS_MIN_PER_CHAIN * self.n_chains,
            "converged": not self.issues(),
            "prior": self.prior,
            "parameters": {
                n: {
                    "mean": json_number(mean[i]),
                    "sd": json_number(sd[i]),
                    "interval_90": [json_number(q90[i, 0]), json_number(q90[i, 1])],
                    "interval_95": [json_number(q95[i, 0]), json_number(q95[i, 1])],
                    "rhat": json_number(self.rhat[i]),
                    "ess_bulk": json_number(self.ess_bulk[i]),
                    "ess_tail": json_number(self.ess_tail[i]),
                }
                for i, n in enumerate(self.names)
            },
            "kept_draws": {"names": list(self.names), "values": self.kept().tolist()},
        }
