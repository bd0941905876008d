"""Local and global identifiability of RC parameters from a data set, before any fit.

Three pieces of evidence are combined into a verdict per free parameter:

1. **Fisher information** from exact output sensitivities (:mod:`rczone.simulation.sensitivity`)
   with respect to ``log(theta)``, at the prior operating point (construction values). The
   nuisance directions a real fit must also absorb are included and marginalized out: the
   unknown initial state of every node and an unknown constant heat gain (the paper had to guess
   Q = 50 W). Output errors in buildings are dominated by model error that is correlated over
   tens of minutes, so the information of ``N`` samples is counted as that of
   ``N * dt / correlation_time`` independent ones (documented, configurable).
2. **Robustness to model error**: a low-order model never matches a real room exactly (rczone's
   own model-order study finds 0.2--0.5 K between the 2nd-order and the full-scale model on
   ordinary nights). Least squares turns a model error ``e(t)`` into a parameter bias
   ``(S'S)^{-1} S' e``; its worst case over errors of RMS ``model_error_K`` is
   ``model_error_K * sqrt(N [(S'S)^{-1}]_jj)`` (Cauchy--Schwarz), i.e. the expected standard
   error rescaled from ``sigma_K`` over ``n_eff`` samples to ``model_error_K`` over one. A
   parameter the data see only through a signal comparable with that error is not identifiable in
   practice even when its statistical standard error is small -- the paper's closed-loop nights.
3. **Distinguishability** (global): the output change when a parameter is divided or multiplied
   by 10, after the nuisances are re-fitted by linear least squares (they enter linearly). If
   the remaining change is below the noise level, the data cannot tell the value from one ten
   times smaller (or larger) -- the paper's failure mode.
4. **Data indicators** (:mod:`rczone.diagnostics.indicators`) to explain the cause in plain words.

References
----------
.. [1] Lin, Middelkoop, Barooah, IEEE CDC 2012, section IV.
.. [2] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (local identifiability, Fisher information, experiment design).
.. [3] A. Raue et al., "Structural and practical identifiability analysis of partially observed
   dynamical models by exploiting the profile likelihood", Bioinformatics 25(15), 2009.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rczone.comparison import model_arrays
from rczone.diagnostics.indicators import DataIndicators, data_indicators
from rczone.errors import ParameterError, did_you_mean
from rczone.network import RCNetwork
from rczone.network.parameters import expression_names
from rczone.simulation import simulate
from rczone.simulation.initial import output_consistent_state
from rczone.simulation.sensitivity import output_sensitivities

IDENTIFIABLE, WEAK, NOT_IDENTIFIABLE = "identifiable", "weak", "not identifiable"
#: Expected relative standard error (in log space) below which a parameter is identifiable.
SE_IDENTIFIABLE = 0.25
#: ... and above which it is not identifiable at all.
SE_NOT_IDENTIFIABLE = 1.0
#: Worst-case relative bias (log space) from a model error of ``model_error_K`` below which a
#: parameter can be identifiable ...
BIAS_IDENTIFIABLE = 0.5
#: ... and above which it is not identifiable.
BIAS_NOT_IDENTIFIABLE = 1.0
#: |correlation| above which two parameters are reported as confounded.
CORR_CONFOUNDED = 0.95


@dataclass(frozen=True)
class ParameterVerdict:
    """The verdict on one free parameter, with the evidence and a plain-words reason."""

    name: str
    verdict: str
    reason: str
    advice: str
    construction: float
    expected_rel_se: float
    most_correlated_with: str | None
    max_abs_correlation: float
    rms_change_tenth_K: float
    rms_change_tenfold_K: float
    worst_case_bias: float = 0.0

    def to_dict(self) -> dict:
        return {k: v for k, v in vars(self).items() if k != "name"}


@dataclass(frozen=True)
class IdentifiabilityReport:
    """Everything :func:`diagnose` found.

    Attributes
    ----------
    parameters : dict of name to ParameterVerdict
    names : tuple of str
        Free parameters, the order of the matrices below.
    fisher : ndarray, shape (P, P)
        Fisher information of the free log-parameters with the nuisances marginalized.
    expected_se : ndarray, shape (P,)
        Expected standard errors of ``log(theta)`` (relative standard errors).
    correlation : ndarray, shape (P, P)
    condition_number : float
        Of the column-scaled sensitivity matrix including nuisances.
    """

    parameters: dict[str, ParameterVerdict]
    names: tuple[str, ...]
    fisher: np.ndarray
    expected_se: np.ndarray
    correlation: np.ndarray
    condition_number: float
    sigma_K: float
    n_effective: float
    indicators: DataIndicators
    settings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "parameters": {k: v.to_dict() for k, v in self.parameters.items()},
            "free": list(self.names),
            "fisher_log": self.fisher.tolist(),
            "expected_rel_se": dict(zip(self.names, self.expected_se.tolist(), strict=True)),
            "correlation": self.correlation.tolist(),
            "condition_number": self.condition_number,
            "sigma_K": self.sigma_K,
            "n_effective": self.n_effective,
            "indicators": self.indicators.to_dict(),
            "settings": self.settings,
        }


def parameter_boundaries(network: RCNetwork, name: str) -> tuple[str, ...]:
    """Boundary inputs reached through the resistors that use ``name`` (directly or via ties)."""
    users = {name} | {
        p.name for p in network.parameters.values() if p.expr is not None and name in expression_names(p.expr)
    }
    out = []
    for r in network.resistors:
        if isinstance(r.resistance, str) and r.resistance in users:
            out += [e for e in (r.a, r.b) if e in network.boundaries]
    # a resistor chain (wall) reaches its boundary through capacitive nodes: follow it
    if not out:
        for r in network.resistors:
            if isinstance(r.resistance, str) and r.resistance in users:
                for r2 in network.resistors:
                    if {r2.a, r2.b} & {r.a, r.b} and (
                        r2.a in network.boundaries or r2.b in network.boundaries
                    ):
                        out += [e for e in (r2.a, r2.b) if e in network.boundaries]
    return tuple(dict.fromkeys(out))


def _nuisance_columns(
    ss, t, u, m, heat_input: str | None, initial_state: bool = True
) -> tuple[np.ndarray, list[str]]:
    """Output responses to each initial state (zero input) and to a unit constant heat gain."""
    cols, names = [np.zeros(t.size)], ["none"]  # a zero column keeps shapes valid with no nuisance
    zero = np.zeros_like(u)
    mm = m if m.shape[1] else None
    for i, s in enumerate(ss.state_names if initial_state else ()):
        e = np.zeros(ss.n_states)
        e[i] = 1.0
        cols.append(simulate(ss, t, zero, mm, x0=e).y[:, 0])
        names.append(f"x0[{s}]")
    if heat_input is not None and heat_input in ss.input_names:
        uq = zero.copy()
        uq[:, ss.input_names.index(heat_input)] = 1.0
        cols.append(simulate(ss, t, uq, mm, x0=np.zeros(ss.n_states)).y[:, 0])
        names.append(f"offset[{heat_input}]")
    return np.column_stack(cols), names


def _refit_residual(delta: np.ndarray, nuis: np.ndarray) -> float:
    """RMS of ``delta`` after removing its least-squares projection on the nuisance columns."""
    coef, *_ = np.linalg.lstsq(nuis, delta, rcond=None)
    return float(np.sqrt(np.mean((delta - nuis @ coef) ** 2)))


def diagnose(
    network: RCNetwork,
    frame: pd.DataFrame,
    free: Sequence[str] | None = None,
    theta: Mapping[str, float] | None = None,
    sigma_K: float = 0.1,
    correlation_time_s: float = 1800.0,
    model_error_K: float = 0.2,
    constants: Mapping[str, float] | None = None,
    heat_input: str | None = "Q",
    initial_state_nuisance: bool = True,
) -> IdentifiabilityReport:
    """Tell whether ``frame`` can identify the ``free`` parameters of ``network``.

    Parameters
    ----------
    network : RCNetwork
    frame : DataFrame
        ``time`` (s), ``Ti`` and the model's inputs (``Tsd`` may be derived from the five
        surroundings).
    free : sequence of str, optional
        Free base parameters; default every base resistance and capacitance.
    theta : mapping, optional
        Prior operating point; default the construction (declared) values.
    sigma_K : float
        Output error level the fit must see through (sensor noise plus model error), K.
    correlation_time_s : float
        Correlation time of that error; information is counted per this many seconds.
    model_error_K : float
        RMS structural error the model may have on these data, K; the verdict requires the
        worst-case bias it can cause to be small (see the module notes). 0 disables the check.
    constants : mapping, optional
        Inputs held constant instead of read from the frame (e.g. ``{"Q": 50.0}``).
    heat_input : str or None
        Heat input whose unknown constant offset is a nuisance (None to disable).
    initial_state_nuisance : bool
        Treat the initial state as unknown (a fit that estimates it, or starts from a guess).

    Returns
    -------
    IdentifiabilityReport
    """
    if not sigma_K > 0 or not correlation_time_s > 0 or not model_error_K >= 0:
        raise ParameterError(
            f"sigma_K and correlation_time_s must be > 0 and model_error_K >= 0, got {sigma_K},"
            f" {correlation_time_s}, {model_error_K}"
        )
    if free is None:
        free = [
            n
            for n, p in network.parameters.items()
            if not p.is_tied and p.kind in ("resistance", "capacitance")
        ]
    for n in free:
        if n not in network.parameters:
            raise ParameterError(f"unknown free parameter {n!r}; " + did_you_mean(n, network.parameters))
    free = list(free)
    vals = network.values(theta)
    t, u, m = model_arrays(network, frame, constants)
    y = frame["Ti"].to_numpy(float)
    ok = np.isfinite(y)
    ss = network.state_space(theta)
    mm = m if m.shape[1] else None
    x0 = output_consistent_state(ss, u[0], m[0] if m.shape[1] else 0.0, float(y[ok][0]))
    sens = output_sensitivities(network, theta, free, t, u, mm, x0=x0)
    S = sens.dy[ok, 0, :]
    nuis, _ = _nuisance_columns(ss, t, u, m, heat_input, initial_state_nuisance)
    nuis = nuis[ok]
    dt = float(np.median(np.diff(t)))
    n_eff = ok.sum() * min(1.0, dt / correlation_time_s)
    w = n_eff / ok.sum() / sigma_K**2
    J = np.column_stack([S, nuis])
    scale = np.linalg.norm(J, axis=0)
    used = scale > 0  # a nuisance column that is identically zero carries no information
    sv = np.linalg.svd(J[:, used] / scale[used], compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    F_all = w * (J.T @ J)
    P = len(free)
    Fff, Ffn, Fnn = F_all[:P, :P], F_all[:P, P:], F_all[P:, P:]
    F = Fff - Ffn @ np.linalg.pinv(Fnn, rcond=1e-13) @ Ffn.T
    cov = np.linalg.pinv(F, rcond=1e-14, hermitian=True)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    se[np.diag(F) <= 0] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, 1.0)
    bias = se * (model_error_K / sigma_K) * np.sqrt(n_eff)

    y0 = sens.y[ok, 0]
    ind = data_indicators(frame)
    verdicts = {}
    for j, name in enumerate(free):
        changes = []
        for factor in (0.1, 10.0):
            alt = simulate(
                network.state_space({**_base(network, theta), name: vals[name] * factor}), t, u, mm, x0=x0
            )
            changes.append(_refit_residual(alt.y[ok, 0] - y0, nuis))
        others = [(abs(corr[j, k]), free[k]) for k in range(P) if k != j]
        rho, partner = max(others) if others else (0.0, None)
        verdicts[name] = _verdict(
            network,
            name,
            float(se[j]),
            rho,
            partner,
            changes,
            sigma_K,
            ind,
            vals[name],
            float(bias[j]),
            model_error_K,
        )
    return IdentifiabilityReport(
        verdicts,
        tuple(free),
        F,
        se,
        corr,
        cond,
        sigma_K,
        float(n_eff),
        ind,
        {
            "correlation_time_s": correlation_time_s,
            "model_error_K": model_error_K,
            "heat_offset_nuisance": heat_input,
            "constants": dict(constants or {}),
        },
    )


def _base(network: RCNetwork, theta: Mapping[str, float] | None) -> dict[str, float]:
    return {k: v for k, v in network.values(theta).items() if not network.parameters[k].is_tied}


def _verdict(
    network: RCNetwork,
    name: str,
    se: float,
    rho: float,
    partner: str | None,
    changes: list[float],
    sigma: float,
    ind: DataIndicators,
    value: float,
    bias: float = 0.0,
    model_error: float = 0.0,
) -> ParameterVerdict:
    tenth, tenfold = changes
    indistinct = min(tenth, tenfold) < sigma
    if se < SE_IDENTIFIABLE and bias < BIAS_IDENTIFIABLE and not indistinct:
        verdict = IDENTIFIABLE
    elif (
        se >= SE_NOT_IDENTIFIABLE
        or bias >= BIAS_NOT_IDENTIFIABLE
        or (indistinct and se >= SE_IDENTIFIABLE)
        or max(tenth, tenfold) < sigma
    ):
        verdict = NOT_IDENTIFIABLE
    else:
        verdict = WEAK
    kind = network.parameters[name].kind
    reasons, advice = [], []
    bounds = parameter_boundaries(network, name)
    sur = [s for s in ind.surroundings if s.name in bounds]
    if verdict != IDENTIFIABLE:
        if kind == "resistance" and sur:
            s = max(sur, key=lambda s: s.max_abs_diff_K)
            moved = f" and moved with it (correlation {s.correlation:.2f})" if s.correlation > 0.7 else ""
            reasons.append(
                f"the room stayed within {s.max_abs_diff_K:.1f} K of {s.name} (typically {s.median_abs_diff_K:.1f} K)"
                f"{moved}, so the heat flow through {name} was too small to tell apart from an unknown heat gain"
            )
            advice.append(
                f"run a forced-response test that drives the room several K away from {s.name} for hours"
                " (see `rczone design`)"
            )
        if tenth < sigma:
            reasons.append(
                f"with {name} ten times smaller the room temperature changes by only {tenth:.2f} K RMS once the"
                f" initial state and heat gain are re-fitted, below the {sigma:.2f} K error level, so a fit can"
                f" return a value far below the true one and still match the data"
            )
        elif tenfold < sigma:
            reasons.append(
                f"with {name} ten times larger the room temperature changes by only {tenfold:.2f} K RMS once the"
                f" initial state and heat gain are re-fitted, below the {sigma:.2f} K error level"
            )
        if bias >= BIAS_IDENTIFIABLE and model_error > 0:
            reasons.append(
                f"a model error of {model_error:.1f} K, usual for a low-order model of a real room, could shift"
                f" the estimate by {_factor(bias)}, and the fit would still match"
                " the data"
            )
        if rho > CORR_CONFOUNDED and partner:
            reasons.append(
                f"its effect on the room temperature is almost the same as that of {partner} (correlation"
                f" {rho:.2f}), so the data fix only a combination of the two"
            )
            advice.append(
                f"fix {partner} or {name} at its construction value, or excite the room differently"
            )
        if kind == "capacitance" and not reasons:
            reasons.append(
                "the room temperature did not change fast or far enough to show the thermal inertia"
            )
            advice.append("step the supply-air temperature or flow and hold each step for at least an hour")
        if not reasons:
            reasons.append(f"the expected relative standard error is {se:.0%}")
        advice.append("or keep it at its construction value (fixed, or MAP with a prior)")
    else:
        reasons.append(
            f"the data determine it to about ±{_percent(se)} (expected relative standard error); even a model"
            f" error of {model_error:.1f} K could shift it by at most a factor {np.exp(bias):.2f}"
        )
    return ParameterVerdict(
        name=name,
        verdict=verdict,
        reason="; ".join(reasons),
        advice="; ".join(advice),
        construction=float(value),
        expected_rel_se=float(se),
        most_correlated_with=partner,
        max_abs_correlation=float(rho),
        rms_change_tenth_K=float(tenth),
        rms_change_tenfold_K=float(tenfold),
        worst_case_bias=float(bias),
    )


def _factor(log_shift: float) -> str:
    """A worst-case shift in words: 'up to a factor 2.7', or 'more than a factor 100'."""
    f = float(np.exp(min(log_shift, 50.0)))
    return f"up to a factor {f:.2g}" if f < 100 else "more than a factor 100"


def _percent(rel: float) -> str:
    return f"{rel:.0%}" if rel >= 0.01 else "1% or better"
