"""Diagnose, then fit, many seeded virtual nights; summarize per regime (used by the acceptance tests).

Run ``python -m tests.acceptance.survey [n_seeds]`` from the repository root to print the
verdicts-vs-fits table of ``docs/identifiability.md``.

Each night is diagnosed as a user would (:func:`rczone.diagnostics.diagnose` with its defaults: at
the model's values if they reproduce the night, else at a quick fit's estimates), then fitted by LS
twice: with the paper's reduced free set ``Cr, Rw`` (the wall starting in equilibrium with the data,
:data:`FITS` ``"reduced"``), and with rczone's default free set, which also estimates the wall's
initial temperature (``"default"``).

Definitions (the structural-error allowance, see ``docs/identifiability.md``):

* ``u`` (predicted uncertainty of ``ln theta`` on one night) = ``sqrt(se^2 + b^2)``, with ``se`` the
  expected relative standard error and ``b`` the worst-case relative bias from a 0.2 K model error,
  both from diagnose *before* the fit.
* A parameter is **recovered** in a regime when (1) no fit sits at a bound and every fit converged,
  (2) the night-to-night scatter (sample std of ``ln theta_hat``) is at most ``min(2 u_rms, ln 2)``,
  (3) every night lies within ``3 u`` of the regime's geometric mean, and (4) that geometric mean is
  within a factor :data:`STRUCTURAL_FACTOR` of the steady-state true equivalent.
* It is **not recovered** when any of these fails.
* The regime's **consensus** is ``"identifiable"`` when no night says "not identifiable" and most
  say "identifiable" ("weak" is the verdict's own in-between: it claims neither), ``"not
  identifiable"`` when no night says "identifiable", and ``"mixed"`` otherwise.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from rczone.calibration import calibrate
from rczone.diagnostics import diagnose
from rczone.virtual.scenarios import generate_night

FREE = ("Cr", "Rw")
#: The LS fits of each night: the paper's reduced free set, and rczone's default (with the wall's
#: initial temperature).
FITS = {"reduced": list(FREE), "default": None}
#: (season, mode) of each regime.
REGIMES = {
    "summer closed-loop": ("summer", "closed-loop"),
    "winter closed-loop": ("winter", "closed-loop"),
    "autumn forced": ("autumn", "forced"),
}
#: Allowed ratio between the forced-test value and the steady-state true equivalent: the reduced
#: model's structural error (hour-scale vs steady-state wall response, tests/acceptance/truth.py).
STRUCTURAL_FACTOR = 2.0


@dataclass(frozen=True)
class NightOutcome:
    """Verdicts and predictions of diagnose, and the LS fits (:data:`FITS`), on one night."""

    regime: str
    seed: int
    verdict: dict[str, str]
    expected_se: dict[str, float]
    worst_bias: dict[str, float]
    operating_point: str
    estimate: dict[str, dict[str, float]]
    fit_rel_se: dict[str, dict[str, float]]
    at_bound: dict[str, dict[str, bool]]
    converged: dict[str, bool]
    rmse_K: dict[str, float]

    def u(self, name: str) -> float:
        """Predicted uncertainty of ``ln theta`` (statistical and model-error), before the fit."""
        return float(np.hypot(self.expected_se[name], self.worst_bias[name]))


def night_outcome(regime: str, seed: int, fits: Iterable[str] = tuple(FITS)) -> NightOutcome:
    """Generate one night of ``regime``, diagnose it, then fit the reduced model by LS (the ``fits``)."""
    season, mode = REGIMES[regime]
    frame = generate_night(season, mode, seed)
    rep = diagnose("second-order-paper", frame, free=list(FREE))
    res = {k: calibrate("second-order-paper", frame, method="ls", free=FITS[k]).result for k in fits}
    return NightOutcome(
        regime=regime,
        seed=seed,
        verdict={k: rep.parameters[k].verdict for k in FREE},
        expected_se={k: rep.parameters[k].expected_rel_se for k in FREE},
        worst_bias={k: rep.parameters[k].worst_case_bias for k in FREE},
        operating_point=rep.operating_point.source,
        estimate={f: {k: float(r.estimates[k]) for k in FREE} for f, r in res.items()},
        fit_rel_se={f: {k: float(r.std_errors[k] / r.estimates[k]) for k in FREE} for f, r in res.items()},
        at_bound={f: {k: bool(r.parameters[k].at_bound) for k in FREE} for f, r in res.items()},
        converged={f: bool(r.converged) for f, r in res.items()},
        rmse_K={f: float(r.rmse_K) for f, r in res.items()},
    )


@dataclass(frozen=True)
class RegimeSummary:
    """What the fits of one parameter did over the nights of one regime."""

    regime: str
    name: str
    fit: str
    n: int
    verdicts: dict[str, int]
    gmean: float
    ratio_to_truth: float
    scatter_ln: float
    u_rms: float
    se_rms: float
    bias_rms: float
    fit_se_median: float
    max_dev_in_u: float
    n_at_bound: int
    all_converged: bool
    min_estimate: float
    max_estimate: float
    max_inside: float = float("nan")  # largest estimate of the nights not at a bound

    @property
    def recovered(self) -> bool:
        """The criteria of the module docstring."""
        return (
            self.n_at_bound == 0
            and self.all_converged
            and self.scatter_ln <= min(2 * self.u_rms, np.log(2.0))
            and self.max_dev_in_u <= 3.0
            and abs(np.log(self.ratio_to_truth)) <= np.log(STRUCTURAL_FACTOR)
        )

    @property
    def consensus(self) -> str:
        """The regime's verdict (module notes): identifiable, not identifiable, or mixed."""
        ident, never = self.verdicts.get("identifiable", 0), self.verdicts.get("not identifiable", 0)
        if ident == 0:
            return "not identifiable"
        return "identifiable" if never == 0 and ident > self.n / 2 else "mixed"


def summarize(outcomes: list[NightOutcome], name: str, truth: float, fit: str = "reduced") -> RegimeSummary:
    """Summary of parameter ``name`` fitted with the free set ``fit`` over ``outcomes`` (one regime)."""
    est = np.array([o.estimate[fit][name] for o in outcomes])
    ln = np.log(est)
    u = np.array([o.u(name) for o in outcomes])
    gm = float(np.exp(ln.mean()))
    verdicts: dict[str, int] = {}
    for o in outcomes:
        verdicts[o.verdict[name]] = verdicts.get(o.verdict[name], 0) + 1
    return RegimeSummary(
        regime=outcomes[0].regime,
        name=name,
        fit=fit,
        n=len(outcomes),
        verdicts=verdicts,
        gmean=gm,
        ratio_to_truth=gm / truth,
        scatter_ln=float(ln.std(ddof=1)),
        u_rms=float(np.sqrt(np.mean(u**2))),
        se_rms=float(np.sqrt(np.mean([o.expected_se[name] ** 2 for o in outcomes]))),
        bias_rms=float(np.sqrt(np.mean([o.worst_bias[name] ** 2 for o in outcomes]))),
        fit_se_median=float(np.median([o.fit_rel_se[fit][name] for o in outcomes])),
        max_dev_in_u=float(np.max(np.abs(ln - ln.mean()) / u)),
        n_at_bound=sum(o.at_bound[fit][name] for o in outcomes),
        all_converged=all(o.converged[fit] for o in outcomes),
        min_estimate=float(est.min()),
        max_estimate=float(est.max()),
        max_inside=float(
            max((o.estimate[fit][name] for o in outcomes if not o.at_bound[fit][name]), default=np.nan)
        ),
    )


def survey(seeds: Iterable[int], truth: dict[str, float]) -> list[RegimeSummary]:
    """Every fit x regime x parameter over ``seeds``."""
    seeds = list(seeds)
    outcomes = {regime: [night_outcome(regime, s) for s in seeds] for regime in REGIMES}
    return [summarize(outcomes[r], k, truth[k], f) for f in FITS for r in REGIMES for k in FREE]


def markdown(rows: list[RegimeSummary]) -> str:
    """The verdicts-vs-fits table."""
    head = (
        "| LS fit | regime | param | verdicts | estimates min..max | geo. mean / truth | scatter ln"
        " | predicted se | predicted u | LS se (median) | at bound | recovered |\n|" + "---|" * 12
    )
    lines = [head]
    for r in rows:
        v = ", ".join(f"{k} {n}" for k, n in sorted(r.verdicts.items()))
        lines.append(
            f"| {r.fit} | {r.regime} | {r.name} | {v} | {r.min_estimate:.3g}..{r.max_estimate:.3g} | {r.ratio_to_truth:.2f}"
            f" | {r.scatter_ln:.3f} | {r.se_rms:.3f} | {r.u_rms:.3f} | {r.fit_se_median:.3f} | {r.n_at_bound}"
            f" | {'yes' if r.recovered else 'no'} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - documentation helper
    from tests.acceptance.truth import steady_state_equivalent

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    print(markdown(survey(range(200, 200 + n), steady_state_equivalent())))
