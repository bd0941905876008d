"""Local and global identifiability of RC parameters from a data set, before relying on a fit.

Four pieces of evidence are combined into a verdict per free parameter:

1. **Fisher information** from exact output sensitivities (:mod:`rczone.simulation.sensitivity`)
   with respect to ``log(theta)``, every output of the model stacked
   (:mod:`rczone.diagnostics.fisher`). The nuisance directions a real fit must also absorb are
   marginalized out: the unknown initial state of every node and the unknown constant offset of
   every heat input that is only guessed (a constant in the data, such as the paper's Q = 50 W).
   Output errors in buildings are dominated by model error that is correlated over tens of
   minutes, so the information of ``N`` samples is counted as that of ``N * dt / correlation_time``
   independent ones (documented, configurable).
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

**Operating point.** Sensitivities are local: they are taken where the parameters are. The model's
own values are used when they *reproduce the data*: an open-loop simulation at them, with the
nuisances re-fitted (as a fit would), leaves a residual of at most :data:`CONSISTENT_FACTOR` times
the error level ``sqrt(sigma_K^2 + model_error_K^2)``. Otherwise a quick least-squares fit
(:func:`rczone.calibration.calibrate` without standard errors) is run first and the analysis is done
at its estimates. The report says which was used, and the residual of each.

References
----------
.. [1] Lin, Middelkoop, Barooah, IEEE CDC 2012, section IV.
.. [2] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (local identifiability, Fisher information, experiment design).
.. [3] A. Raue et al., "Structural and practical identifiability analysis of partially observed
   dynamical models by exploiting the profile likelihood", Bioinformatics 25(15), 2009.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rczone.data.excitation import Excitation, input_excitation
from rczone.diagnostics.fisher import (
    check_free,
    marginal_fisher,
    nuisance_responses,
    project_out,
    rms,
    sample_weight,
)
from rczone.diagnostics.indicators import DataIndicators, data_indicators
from rczone.errors import ParameterError, did_you_mean
from rczone.estimation import Dataset
from rczone.estimation.costs import initial_state
from rczone.estimation.settings import FitSettings
from rczone.models import ZoneModel
from rczone.network import RCNetwork
from rczone.network.parameters import expression_names
from rczone.results import Result
from rczone.simulation import simulate
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
#: Relative margin around every threshold. A verdict whose deciding quantity lies within it of a
#: threshold is *borderline*: another data set of the same kind, or another machine's rounding in the
#: operating point, could tip it. "Identifiable" is never given on a borderline: each of ``se``, ``b``
#: and the two changes must clear its threshold by this factor, otherwise the verdict is "weak".
VERDICT_MARGIN = 0.1
#: A zone whose difference to a surrounding temperature is typically below this (or varies by less)
#: sends a heat flow through the resistance between them that an unknown gain can mimic, K.
STEADY_DIFFERENCE_K = 1.0
#: |correlation| above which two parameters are reported as confounded.
CORR_CONFOUNDED = 0.95
#: The model's values reproduce the data when the residual of an open-loop simulation at them,
#: after re-fitting the nuisances, is at most this many times ``sqrt(sigma_K^2 + model_error_K^2)``.
CONSISTENT_FACTOR = 2.0
#: Ways of choosing the operating point (see :func:`diagnose`).
OPERATING_POINTS = ("auto", "model", "fit")
#: Parameter kinds diagnose looks at by default (analysed in log space, so their value must be > 0).
DIAGNOSED_KINDS = ("resistance", "capacitance", "gain")


@dataclass(frozen=True)
class ParameterVerdict:
    """The verdict on one free parameter, with the evidence and a plain-words reason.

    ``value`` is the parameter at the operating point, ``construction`` the model's declared
    (construction) value. ``borderline`` is true when moving any of the deciding quantities by
    :data:`VERDICT_MARGIN` could change the verdict; "identifiable" is never borderline.
    ``at_bound`` ("lower" or "upper") when the value sits at a bound of its search box: the verdict
    is then "not identifiable", whatever the local quantities say.
    """

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
    value: float = math.nan
    borderline: bool = False
    at_bound: str | None = None

    def to_dict(self) -> dict:
        return {k: v for k, v in vars(self).items() if k != "name"}


@dataclass(frozen=True)
class OperatingPoint:
    """Where the sensitivities were taken, and why.

    Attributes
    ----------
    source : {"model", "fit"}
        The model's own values, or the estimates of a quick least-squares fit.
    theta : dict of str to float
        Base parameter values used.
    initial_state : dict of str to float
        Initial state of the simulation the analysis linearizes (degC).
    residual_K : float
        RMS of the data minus the open-loop simulation at the model's values, after re-fitting
        the nuisances (initial state, guessed heat-gain offsets), K.
    threshold_K : float
        The largest residual for which the model's values count as reproducing the data.
    fit_residual_K : float
        The same residual at the quick fit's estimates (NaN without a fit).
    reason : str
        The choice in words.
    fit_free : tuple of str
        Parameters the quick fit estimated (empty without a fit).
    at_bound : dict of str to {"lower", "upper"}
        Parameters (diagnosed or fitted) whose value sits at a bound of its search box
        (:meth:`rczone.estimation.parameters.ParameterSpec.near_bound`): the data push them beyond
        it, so the point is degenerate and every verdict is read at an arbitrary place.
    """

    source: str
    theta: dict[str, float]
    initial_state: dict[str, float]
    residual_K: float
    threshold_K: float
    fit_residual_K: float = math.nan
    reason: str = ""
    fit_free: tuple[str, ...] = ()
    at_bound: dict[str, str] = field(default_factory=dict)

    @property
    def residual_used_K(self) -> float:
        """Residual at the values the analysis used."""
        return self.fit_residual_K if self.source == "fit" else self.residual_K

    @property
    def reproduces_data(self) -> bool:
        """Whether the values used reproduce the data within the threshold."""
        return bool(self.residual_used_K <= self.threshold_K)

    def to_dict(self) -> dict:
        return {
            "source": self.source,
            "theta": dict(self.theta),
            "initial_state": dict(self.initial_state),
            "residual_K": self.residual_K,
            "threshold_K": self.threshold_K,
            "fit_residual_K": None if math.isnan(self.fit_residual_K) else self.fit_residual_K,
            "reproduces_data": self.reproduces_data,
            "reason": self.reason,
            "fit_free": list(self.fit_free),
            "at_bound": dict(self.at_bound),
        }


#: Colour of each verdict in the console.
VERDICT_STYLE = {"identifiable": "green", "weak": "yellow", "not identifiable": "red"}


@dataclass(frozen=True, repr=False)
class IdentifiabilityReport(Result):
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
    sigma_K : float
    n_effective : float
        Independent samples the information is counted for, over all outputs.
    indicators : DataIndicators
    operating_point : OperatingPoint
    outputs : tuple of str
        The model's outputs, all of which entered the analysis.
    signals : DataFrame
        ``time`` and the model's signals over the samples analysed (SI units), for reports.
    settings : dict
        The analysis' settings and what it held constant.
    units : dict of str to str
        SI unit of each free parameter.
    model_label, data_label : str
        Names of the model and the data, for titles (``rczone diagnose`` sets them).
    excitation : Excitation or None
        Whether the inputs are excited apart (:mod:`rczone.diagnostics.excitation`).
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
    operating_point: OperatingPoint | None = None
    outputs: tuple[str, ...] = ()
    signals: pd.DataFrame | None = field(default=None, repr=False)
    settings: dict = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    model_label: str = "model"
    data_label: str = "data"
    excitation: Excitation | None = None

    def to_frame(self) -> pd.DataFrame:
        """One row per free parameter: verdict, value and its unit, expected relative standard error and bias, reason."""
        rows = [
            {
                "parameter": n,
                "verdict": v.verdict,
                "value": v.value,
                "unit": self.units.get(n, ""),
                **v.to_dict(),
            }
            for n, v in self.parameters.items()
        ]
        return pd.DataFrame(rows).set_index("parameter")

    def _repr_line(self) -> str:
        counts = {}
        for v in self.parameters.values():
            counts[v.verdict] = counts.get(v.verdict, 0) + 1
        return f"{self.data_label} for {self.model_label}: " + ", ".join(
            f"{k} {c}" for k, c in counts.items()
        )

    def summary_lines(self) -> list:
        """What ``rczone diagnose`` prints (before the files it writes)."""
        from rich.table import Table

        from rczone.results.fit_text import esc

        table = Table(title=f"Can {esc(self.data_label)} identify {esc(self.model_label)}?")
        for c in ("parameter", "value", "unit", "expected ± (rel.)", "verdict", "reason"):
            table.add_column(c, overflow="fold")
        for name, v in self.parameters.items():
            table.add_row(
                esc(name),
                f"{v.value:.4g}",
                esc(self.units.get(name, "")),
                f"{v.expected_rel_se:.0%}" if v.expected_rel_se < 10 else "> 1000%",
                f"[{VERDICT_STYLE[v.verdict]}]{v.verdict}[/]",
                esc(v.reason),
            )
        lines: list = [table]
        op = self.operating_point
        if op is not None:
            style = "" if op.reproduces_data else "[yellow]"
            lines.append(f"{style}operating point:{'[/]' if style else ''} {esc(op.reason)}")
        if len(self.outputs) > 1:
            lines.append("outputs analysed together: " + ", ".join(esc(o) for o in self.outputs))
        if self.settings.get("hold") == "foh":
            lines.append("inputs between samples: linear (foh)")
        held = self.settings.get("constants") or {}
        if held:
            lines.append("held constant: " + ", ".join(f"{esc(k)} = {v:g}" for k, v in held.items()))
        if self.excitation is not None:
            lines += self.excitation.summary_lines()
        lines += [f"[bold]{esc(name)}[/]: {esc(v.advice)}" for name, v in self.parameters.items() if v.advice]
        return lines

    def to_dict(self) -> dict:
        """What ``rczone diagnose --json`` writes."""
        return {
            "data": self.data_label,
            "model": self.model_label,
            "parameters": {k: v.to_dict() for k, v in self.parameters.items()},
            "free": list(self.names),
            "outputs": list(self.outputs),
            "operating_point": self.operating_point.to_dict() if self.operating_point else None,
            "fisher_log": self.fisher.tolist(),
            "expected_rel_se": dict(zip(self.names, self.expected_se.tolist(), strict=True)),
            "correlation": self.correlation.tolist(),
            "condition_number": self.condition_number,
            "sigma_K": self.sigma_K,
            "n_effective": self.n_effective,
            "indicators": self.indicators.to_dict(),
            "settings": self.settings,
            "excitation": self.excitation.to_dict() if self.excitation is not None else None,
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


def guessed_heat_inputs(network: RCNetwork, data: Dataset) -> tuple[str, ...]:
    """Heat inputs (W) that are constant over the data: a guess (a default, a constant), not a measurement."""
    out = []
    for h in network.heat_inputs:
        if h.unit != "W":
            continue
        col = data.u[:, network.input_names.index(h.name)]
        col = col[np.isfinite(col)]
        if col.size and np.all(col == col[0]):
            out.append(h.name)
    return tuple(out)


def default_diagnosed(network: RCNetwork, theta: Mapping[str, float]) -> list[str]:
    """The model's free resistances, capacitances and (positive) gains: what a fit estimates."""
    return [n for n in network.default_free if network.parameters[n].kind in DIAGNOSED_KINDS and theta[n] > 0]


def _stack(a: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Measured samples of every output, stacked: ``a`` (N, ny, ...) -> (n_measured, ...)."""
    return a[ok]


def _residual(
    network: RCNetwork,
    theta: Mapping[str, float],
    values: Mapping[str, float],
    data: Dataset,
    offsets: Sequence[str],
    hold: str = "zoh",
) -> tuple[float, np.ndarray]:
    """RMS of data minus simulation after re-fitting initial state and offsets; and the initial state."""
    ss = network.state_space(theta)
    x0 = initial_state(ss, values, data)
    mm = data.m if data.m.shape[1] else None
    y = simulate(ss, data.t, data.u, mm, x0=x0, hold=hold).y
    ok = np.isfinite(data.y)
    nuis, _ = nuisance_responses(ss, data.t, data.u, data.m, offsets, hold=hold)
    return rms(project_out(_stack(data.y - y, ok), _stack(nuis, ok))), x0


def choose_operating_point(
    zm: ZoneModel,
    frame: pd.DataFrame,
    data: Dataset,
    free: Sequence[str],
    sigma_K: float,
    model_error_K: float,
    offsets: Sequence[str],
    mode: str = "auto",
    *,
    settings: FitSettings,
) -> OperatingPoint:
    """The model's values if they reproduce the data, else a quick fit's estimates (see the module notes).

    Parameters
    ----------
    zm : ZoneModel
        Its ``theta`` is the candidate.
    frame : DataFrame
        The data (for the fit).
    data : Dataset
        The model's signals taken from ``frame``.
    free : sequence of str
        Parameters diagnosed; the quick fit estimates these and the model's default free ones.
    mode : {"auto", "model", "fit"}
        ``"model"`` always uses the model's values, ``"fit"`` always fits first.
    settings : FitSettings
        The quick fit's settings (least squares): its inputs held constant (SI units), the seed of
        its global search, and its hold (inputs between samples), which the residuals use too.
    """
    hold = settings.hold
    net = zm.network
    theta = dict(zm.theta)
    threshold = CONSISTENT_FACTOR * math.hypot(sigma_K, model_error_K)
    r_model, x0 = _residual(net, theta, {}, data, offsets, hold)
    states = dict(zip(net.state_names, map(float, x0), strict=True))
    what = "after re-fitting the initial state" + (" and the heat-gain offset" if offsets else "")
    if mode == "model" or (mode == "auto" and r_model <= threshold):
        how = "as asked" if mode == "model" else f"they reproduce the data within {threshold:.2f} K"
        reason = f"the model's values ({how}: residual {r_model:.2f} K RMS {what})"
        pinned = parameters_at_bound(net, free, theta)
        return OperatingPoint(
            "model", theta, states, r_model, threshold, reason=reason + _pinned_words(pinned), at_bound=pinned
        )
    from rczone.calibration import calibrate
    from rczone.estimation.fit import default_free

    fit_free = tuple(dict.fromkeys((*default_free(net, "ls"), *free)))
    cal = calibrate(zm, frame, settings, free=fit_free, uncertainty=False)
    fitted = dict(cal.model.theta)
    x0_values = dict(cal.model.provenance.get("initial_state") or {})
    r_fit, x0 = _residual(net, fitted, x0_values, data, offsets, hold)
    if mode == "fit":
        why = "as asked"
    else:
        why = f"the model's values miss the data by {r_model:.2f} K RMS {what}, more than {threshold:.2f} K"
    reason = f"a quick least-squares fit ({why}; residual {r_fit:.2f} K RMS at the fit)"
    if r_fit > threshold:
        reason += (
            f"; even the fit misses the data by more than {threshold:.2f} K, so the model error is larger"
            " than assumed: read the verdicts with caution, or raise the model error"
        )
    states = dict(zip(net.state_names, map(float, x0), strict=True))
    # the fit's own at-bound flags (Estimate records): diagnose and the fit agree by construction
    pinned = {n: e.bound_side for n, e in cal.result.parameters.items() if n in net.parameters and e.at_bound}
    reason += _pinned_words(pinned)
    return OperatingPoint("fit", fitted, states, r_model, threshold, r_fit, reason, fit_free, pinned)


def parameters_at_bound(
    network: RCNetwork, names: Sequence[str], theta: Mapping[str, float]
) -> dict[str, str]:
    """Which of ``names`` sit at a bound of the search box a fit would use, and which bound.

    For the model's own values, where no fit ran; a quick fit's estimates carry the same flags in
    their :class:`~rczone.results.estimate.Estimate` records.

    The box is the one :func:`rczone.estimation.parameters.make_spec` gives (declared bounds, else
    a factor 1000 around the declared value); "at" is within 0.1 % of its width in the optimizer's
    variable (:meth:`~rczone.estimation.parameters.ParameterSpec.near_bound`).
    """
    spec = _search_box(network, names)
    if spec is None:
        return {}
    values = network.values(theta)
    th = np.array([values[n] for n in spec.names], dtype=float)
    near = spec.near_bound(th)
    eta = spec.to_eta(th)
    mid = 0.5 * (spec.eta_lower + spec.eta_upper)
    return {n: ("upper" if e > c else "lower") for n, e, c, hit in zip(spec.names, eta, mid, near) if hit}


def _search_box(network: RCNetwork, names: Sequence[str]):
    """The parameter spec (search box) of the untied ``names`` a fit would use; None when there is none."""
    from rczone.estimation.parameters import make_spec

    names = [n for n in names if n in network.parameters and network.parameters[n].expr is None]
    if not names:
        return None
    try:
        return make_spec(network, names)
    except ParameterError:
        return None


def parameters_near_bound(
    network: RCNetwork, names: Sequence[str], theta: Mapping[str, float], margin: float = VERDICT_MARGIN
) -> dict[str, str]:
    """Which of ``names`` lie within ``margin`` (relative) of a positive bound of the search box, and which bound.

    A value 2.972 under an upper bound of 3 is 1 % from it: the data may well want it beyond, so
    it is not "identifiable" whatever the local quantities say (issue 38). The box is the one of
    :func:`parameters_at_bound`.
    """
    spec = _search_box(network, names)
    if spec is None:
        return {}
    values = network.values(theta)
    out = {}
    for n, lo, hi in zip(spec.names, spec.lower, spec.upper, strict=True):
        v = values[n]
        if hi > 0 and v > 0 and v * (1 + margin) >= hi:
            out[n] = "upper"
        elif lo > 0 and v <= lo * (1 + margin):
            out[n] = "lower"
    return out


def _with_excitation(
    verdicts: dict[str, ParameterVerdict], network: RCNetwork, exc: Excitation, near: Mapping[str, str]
) -> dict[str, ParameterVerdict]:
    """The verdicts with the collinear inputs and the near-bound values: never "identifiable", and the cause named."""
    from rczone.diagnostics.excitation import parameters_of

    owners = parameters_of(network, [n for g in exc.groups for n in g])
    out = {}
    for name, v in verdicts.items():
        group = next((g for g in exc.groups if set(owners.get(name, ())) & set(g)), None)
        reasons, advice, verdict = [v.reason], v.advice, v.verdict
        if group is not None:
            reasons.insert(0, exc.finding(group))
            advice = exc.finding(group).split("; ", 1)[1]
            if _degenerate(group, exc, owners, verdicts, near):
                verdict = WEAK if verdict == IDENTIFIABLE else verdict
        side = near.get(name)
        if side and not v.at_bound:
            reasons.insert(0, f"its value {v.value:.4g} lies within {VERDICT_MARGIN:.0%} of its {side} bound")
            verdict = WEAK if verdict == IDENTIFIABLE else verdict
        changed = dict(reason="; ".join(r for r in reasons if r), advice=advice, verdict=verdict)
        out[name] = dataclasses.replace(v, **changed) if (group is not None or side) else v
    return out


#: Inputs correlated at least this closely are treated as one: the Fisher information of their
#: separate effects rests on the last percent of their difference, which any model error swamps.
EXACT_COLLINEAR = 0.99


def _degenerate(group, exc: Excitation, owners, verdicts, near: Mapping[str, str]) -> bool:
    """Whether a collinear group makes the Fisher analysis of its parameters unreliable.

    When the inputs move together almost exactly (``|r| >=`` :data:`EXACT_COLLINEAR`), or when a
    parameter through which one of them acts sits at or near a bound (the analysis is then read at a
    degenerate point), the expected standard errors say nothing about the separate effects. Otherwise
    (two boundary temperatures that drift together at 0.95 over a night, say) the Fisher information
    already carries the collinearity, and its verdict stands with the finding as a note.
    """
    inside = [abs(r) for a, b, r in exc.pairs if a in group and b in group]
    if inside and max(inside) >= EXACT_COLLINEAR:
        return True
    members = [p for p, ins in owners.items() if set(ins) & set(group)]
    return any(near.get(p) or (p in verdicts and verdicts[p].at_bound) for p in members)


def _pinned_words(pinned: Mapping[str, str]) -> str:
    if not pinned:
        return ""
    which = ", ".join(f"{n} at its {b} bound" for n, b in pinned.items())
    them = "them" if len(pinned) > 1 else "it"
    return (
        f"; at this point {which}: the data push {them} beyond the search box, so every verdict is read"
        f" at a degenerate point (widen the bounds or fix {them}, and diagnose again)"
    )


def _indicator_frame(zm: ZoneModel, frame: pd.DataFrame, data: Dataset) -> pd.DataFrame:
    """``time`` and the model's signals (and the columns averaged into an input) over ``data``'s samples."""
    out = pd.DataFrame({"time": data.t})
    for names, arr in ((data.input_names, data.u), (data.flow_names, data.m), (data.output_names, data.y)):
        for j, n in enumerate(names):
            out[n] = arr[:, j]
    t = frame["time"].to_numpy(float)
    rows = (t >= data.t[0]) & (t <= data.t[-1])
    if rows.sum() == data.n_samples:
        for cols in zm.inputs.mean_of.values():
            for c in cols:
                if c in frame and c not in out:
                    out[c] = frame[c].to_numpy(float)[rows]
    return out


SIGMA_RANGE_K = (1e-6, 100.0)
"""Error levels (``sigma_K``, and ``model_error_K`` when not 0) accepted, K: from a microkelvin
(far below any sensor's resolution) to 100 K (far above any room's range). Outside, the weights
``1/sigma^2`` overflow or vanish and the verdicts mean nothing."""


def _check_settings(sigma_K: float, correlation_time_s: float, model_error_K: float, mode: str) -> None:
    if not (sigma_K > 0 and correlation_time_s > 0 and model_error_K >= 0) or not all(
        map(math.isfinite, (sigma_K, correlation_time_s, model_error_K))
    ):
        raise ParameterError(
            f"sigma_K and correlation_time_s must be > 0 and model_error_K >= 0 (finite), got {sigma_K},"
            f" {correlation_time_s}, {model_error_K}"
        )
    lo, hi = SIGMA_RANGE_K
    for name, v in (("sigma", sigma_K), ("model error", model_error_K)):
        if v != 0 and not lo <= v <= hi:
            raise ParameterError(
                f"the {name} must be from {lo:g} to {hi:g} K (rczone.diagnostics.identifiability.SIGMA_RANGE_K),"
                f" got {v:g} K"
            )
    if not 1.0 <= correlation_time_s <= 1e7:
        raise ParameterError(f"correlation_time_s must be from 1 s to 1e7 s, got {correlation_time_s:g}")
    if mode not in OPERATING_POINTS:
        raise ParameterError(
            f"operating_point must be one of {', '.join(OPERATING_POINTS)}, got {mode!r}; "
            + did_you_mean(str(mode), OPERATING_POINTS)
        )


def diagnose(
    model: ZoneModel | RCNetwork | str,
    frame: pd.DataFrame,
    free: Sequence[str] | None = None,
    theta: Mapping[str, float] | None = None,
    sigma_K: float = 0.1,
    correlation_time_s: float = 1800.0,
    model_error_K: float = 0.2,
    constants: Mapping[str, float] | None = None,
    heat_input: str | Sequence[str] | None = "auto",
    initial_state_nuisance: bool = True,
    operating_point: str = "auto",
    seed: int = 0,
    hold: str | None = None,
) -> IdentifiabilityReport:
    """Tell whether ``frame`` can identify the ``free`` parameters of ``model``.

    Parameters
    ----------
    model : ZoneModel, RCNetwork or str
        A model (its values and input conventions are used), a bare network or a built-in name /
        model file (:func:`rczone.models.load_model`).
    frame : DataFrame
        ``time`` (s) or a DatetimeIndex, and the model's signals by name (the model's conventions
        fill inputs the data lack, e.g. a default heat gain or a mean of surrounding rooms). Every
        output of the model is used; missing output samples are skipped.
        Or data prepared for the model (:func:`rczone.calibration.dataset.prepare`; a fit's
        :attr:`rczone.calibration.Calibration.data`), read as they are.
    free : sequence of str, optional
        Parameters to diagnose; default the model's free resistances, capacitances and gains.
    theta : mapping, optional
        Values replacing the model's own (the candidate operating point).
    sigma_K : float
        Output error level a fit must see through (sensor noise plus model error), K.
    correlation_time_s : float
        Correlation time of that error; information is counted per this many seconds.
    model_error_K : float
        RMS structural error the model may have on these data, K; the verdict requires the
        worst-case bias it can cause to be small (see the module notes). 0 disables the check.
    constants : mapping, optional
        Inputs held constant instead of read from the frame (SI units).
    heat_input : "auto", str, sequence of str or None
        Heat inputs whose unknown constant offset is a nuisance: ``"auto"`` every heat input (W)
        that is constant over the data (a guess, such as a default gain), or the names, or None.
    initial_state_nuisance : bool
        Treat the initial state as unknown (a fit that estimates it, or starts from a guess).
    operating_point : {"auto", "model", "fit"}
        Where the analysis is done: ``"auto"`` the model's values if they reproduce the data
        (module notes), else a quick least-squares fit's estimates; ``"model"`` the model's values
        regardless; ``"fit"`` always the quick fit's.
    seed : int
        Seed of the quick fit's global search.
    hold : {"zoh", "foh"}, optional
        Inputs between samples, in the sensitivities, the responses and the quick fit (held or
        linear, as in :func:`rczone.simulation.simulate`; on coarse data the choice moves the
        optimum); default the one a fitted model was fitted with (its provenance), else ``"zoh"``.

    Returns
    -------
    IdentifiabilityReport
    """
    from rczone.calibration import frame_from, prepare
    from rczone.calibration.prediction import model_hold
    from rczone.models import load_model
    from rczone.simulation.simulate import HOLDS

    _check_settings(sigma_K, correlation_time_s, model_error_K, operating_point)
    zm = load_model(model)
    if theta:
        zm = zm.with_values(theta)
    hold = model_hold(zm) if hold is None else str(hold).strip().lower()
    if hold not in HOLDS:
        raise ParameterError(
            f"hold must be one of {', '.join(HOLDS)}, got {hold!r}; " + did_you_mean(hold, HOLDS)
        )
    net = zm.network
    if free is None:
        free = default_diagnosed(net, zm.theta)
    free = list(free)
    if not free:
        raise ParameterError(f"model {zm.label!r} has no free parameter to diagnose; name some with free")
    check_free(net, free)
    prepared = prepare(zm, frame, constants)
    frame, data, constants = frame_from(prepared.frame), prepared.dataset, prepared.constants
    if heat_input == "auto":
        offsets = guessed_heat_inputs(net, data)
    else:
        offsets = (heat_input,) if isinstance(heat_input, str) else tuple(heat_input or ())
        for h in offsets:
            if h not in net.input_names:
                raise ParameterError(
                    f"heat_input {h!r} is not an input of the model; " + did_you_mean(h, net.input_names)
                )
    quick = FitSettings(method="ls", seed=seed, hold=hold, constants=dict(constants or {}))
    op = choose_operating_point(
        zm, frame, data, free, sigma_K, model_error_K, offsets, operating_point, settings=quick
    )
    check_free(net, free, op.theta)
    theta = op.theta
    vals = net.values(theta)
    declared = net.values()
    ss = net.state_space(theta)
    t, u = data.t, data.u
    mm = data.m if data.m.shape[1] else None
    x0 = np.array([op.initial_state[s] for s in net.state_names])
    ok = np.isfinite(data.y)
    sens = output_sensitivities(net, theta, free, t, u, mm, x0=x0, hold=hold)
    S = _stack(sens.dy, ok)
    nuis_t, _ = nuisance_responses(ss, t, u, data.m, offsets, initial_state_nuisance, hold=hold)
    nuis = _stack(nuis_t, ok)
    dt = float(np.median(np.diff(t)))
    w = sample_weight(dt, sigma_K, correlation_time_s)
    n_eff = int(ok.sum()) * min(1.0, dt / correlation_time_s)
    J = np.column_stack([S, nuis])
    scale = np.linalg.norm(J, axis=0)
    used = scale > 0  # a nuisance that never shows in the outputs carries no information
    sv = np.linalg.svd(J[:, used] / scale[used], compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    F = marginal_fisher(S, nuis, w)
    cov = np.linalg.pinv(F, rcond=1e-14, hermitian=True)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    se[np.diag(F) <= 0] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, 1.0)
    bias = se * (model_error_K / sigma_K) * np.sqrt(n_eff)

    y0 = _stack(sens.y, ok)
    signals = _indicator_frame(zm, frame, data)
    ind = data_indicators(
        signals,
        output=net.outputs[0],
        surroundings=[c for c in signals if c in net.boundaries or _averaged(zm, c)],
        inputs=(*net.input_names, *net.flow_names),
        flow=net.flow_names[0] if net.flow_names else None,
    )
    words = _Words(net, offsets, declared, vals)
    verdicts = {}
    for j, name in enumerate(free):
        changes = []
        for factor in (0.1, 10.0):
            alt = simulate(net.state_space({**theta, name: vals[name] * factor}), t, u, mm, x0=x0, hold=hold)
            changes.append(rms(project_out(_stack(alt.y, ok) - y0, nuis)))
        others = [(abs(corr[j, k]), free[k]) for k in range(len(free)) if k != j]
        rho, partner = max(others) if others else (0.0, None)
        verdicts[name] = _verdict(
            words,
            name,
            float(se[j]),
            rho,
            partner,
            changes,
            sigma_K,
            ind,
            float(bias[j]),
            model_error_K,
            at_bound=op.at_bound.get(name),
        )
    exc = input_excitation(np.column_stack([u, data.m]), (*data.input_names, *data.flow_names))
    verdicts = _with_excitation(verdicts, net, exc, parameters_near_bound(net, free, theta))
    if exc.collinear and op.at_bound:  # wider bounds cannot separate inputs that move together
        op = dataclasses.replace(op, reason=op.reason + "; " + "; ".join(exc.findings()))
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
        op,
        tuple(net.outputs),
        signals,
        {
            "correlation_time_s": correlation_time_s,
            "model_error_K": model_error_K,
            "heat_offset_nuisance": list(offsets),
            "initial_state_nuisance": initial_state_nuisance,
            "hold": hold,
            "constants": zm.constants_used(frame, constants),
            "samples": data.n_samples,
            "model": zm.label,
        },
        units={n: net.parameters[n].unit or "" for n in free},
        model_label=zm.label,
        excitation=exc,
    )


def _averaged(zm: ZoneModel, column: str) -> bool:
    """Whether ``column`` is one of the columns averaged into a boundary input (a surrounding space)."""
    return any(column in cols for b, cols in zm.inputs.mean_of.items() if b in zm.network.boundaries)


@dataclass(frozen=True)
class _Words:
    """What the verdicts say about the model: its signals in words, its construction and operating values."""

    network: RCNetwork
    offsets: tuple[str, ...]
    construction: Mapping[str, float]
    value: Mapping[str, float]

    @property
    def measured(self) -> str:
        outs = self.network.outputs
        return "the room temperature" if len(outs) == 1 else f"the measured temperatures ({', '.join(outs)})"

    @property
    def changes(self) -> str:
        """``measured`` with the verb: "the room temperature changes", "the measured ... change"."""
        return self.measured + (" changes" if len(self.network.outputs) == 1 else " change")

    @property
    def refitted(self) -> str:
        return (
            "the initial state and heat gain are re-fitted"
            if self.offsets
            else "the initial state is re-fitted"
        )

    @property
    def actuators(self) -> str:
        net = self.network
        names = [
            *dict.fromkeys(s.temperature for s in net.supply_air if s.temperature not in net.boundaries),
            *net.flow_names,
            *(h.name for h in net.heat_inputs if h.unit == "W"),
        ]
        return ", ".join(names) if names else "an input the building controls"


def _verdict(
    words: _Words,
    name: str,
    se: float,
    rho: float,
    partner: str | None,
    changes: list[float],
    sigma: float,
    ind: DataIndicators,
    bias: float = 0.0,
    model_error: float = 0.0,
    *,
    at_bound: str | None = None,
) -> ParameterVerdict:
    network = words.network
    tenth, tenfold = changes
    verdict = _rule(se, bias, tenth, tenfold, sigma)
    # the verdicts of every combination of the quantities moved by the margin either way
    m = 1.0 + VERDICT_MARGIN
    nearby = {
        _rule(se * a, bias * b, tenth * c, tenfold * d, sigma)
        for a, b, c, d in itertools.product((1 / m, m), repeat=4)
    }
    borderline = nearby != {verdict} and not at_bound
    demoted = verdict == IDENTIFIABLE and borderline
    if demoted:
        verdict = WEAK
    if at_bound:
        # the sensitivities at a bound say nothing about where the data want the parameter
        verdict = NOT_IDENTIFIABLE
    kind = network.parameters[name].kind
    reasons, advice = [], []
    bounds = parameter_boundaries(network, name)
    sur = [s for s in ind.surroundings if s.name in bounds]
    measured = words.measured
    if at_bound:
        unit = network.parameters[name].unit
        reasons.append(
            f"its value {words.value[name]:.4g}{' ' + unit if unit else ''} sits at the {at_bound} bound of its"
            " search box: the data push it beyond, so the analysis there cannot tell its value"
        )
        advice.append(f"widen the bounds of {name} (or fix it) and diagnose again")
    elif demoted:
        reasons.append(
            f"it meets the rules for identifiable by less than the {VERDICT_MARGIN:.0%} margin"
            f" (±{_percent(se)}, worst-case shift {_factor(bias)}), so another data set of the same"
            " kind could fail them"
        )
        advice.append("a longer or more strongly forced test would make it clear")
    elif verdict != IDENTIFIABLE:
        if kind == "resistance" and sur:
            s = max(sur, key=lambda s: s.max_abs_diff_K)
            moved = f" and moved with it (correlation {s.correlation:.2f})" if s.correlation > 0.7 else ""
            if s.median_abs_diff_K < STEADY_DIFFERENCE_K:
                reasons.append(
                    f"the room stayed within {s.max_abs_diff_K:.1f} K of {s.name} (typically"
                    f" {s.median_abs_diff_K:.1f} K){moved}, so the heat flow through {name} was too small to"
                    " tell apart from an unknown heat gain"
                )
            elif s.std_diff_K < STEADY_DIFFERENCE_K:
                reasons.append(
                    f"the difference between the room and {s.name} hardly changed (standard deviation"
                    f" {s.std_diff_K:.1f} K), so the heat flow through {name} was almost constant and cannot be"
                    " told apart from an unknown heat gain"
                )
            advice.append(
                f"run a forced-response test that drives the room several K away from {s.name} for hours"
                " (see `rczone design`)"
            )
        if tenth < sigma:
            reasons.append(
                f"with {name} ten times smaller {words.changes} by only {tenth:.2f} K RMS once"
                f" {words.refitted}, below the {sigma:.2f} K error level, so a fit can"
                f" return a value far below the true one and still match the data"
            )
        elif tenfold < sigma:
            reasons.append(
                f"with {name} ten times larger {words.changes} by only {tenfold:.2f} K RMS once"
                f" {words.refitted}, below the {sigma:.2f} K error level"
            )
        if bias >= BIAS_IDENTIFIABLE and model_error > 0:
            reasons.append(
                f"a model error of {model_error:.1f} K, usual for a low-order model of a real room, could shift"
                f" the estimate by {_factor(bias)}, and the fit would still match"
                " the data"
            )
        if rho > CORR_CONFOUNDED and partner:
            reasons.append(
                f"its effect on {measured} is almost the same as that of {partner} (correlation"
                f" {rho:.2f}), so the data fix only a combination of the two"
            )
            advice.append(
                f"fix {partner} or {name} at its construction value, or excite the room differently"
            )
        if kind == "capacitance" and not reasons:
            reasons.append(f"{measured} did not change fast or far enough to show the thermal inertia")
            advice.append(f"step {words.actuators} and hold each step for at least an hour")
        if not reasons:
            reasons.append(f"the expected relative standard error is {se:.0%}")
        advice.append(
            ("or " if advice else "") + "keep it at its construction value (fixed, or MAP with a prior)"
        )
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
        construction=float(words.construction[name]),
        expected_rel_se=float(se),
        most_correlated_with=partner,
        max_abs_correlation=float(rho),
        rms_change_tenth_K=float(tenth),
        rms_change_tenfold_K=float(tenfold),
        worst_case_bias=float(bias),
        value=float(words.value[name]),
        borderline=borderline,
        at_bound=at_bound,
    )


def _rule(se: float, bias: float, tenth: float, tenfold: float, sigma: float) -> str:
    """The verdict from the four quantities (table in the module notes and docs/identifiability.md)."""
    indistinct = min(tenth, tenfold) < sigma
    if se < SE_IDENTIFIABLE and bias < BIAS_IDENTIFIABLE and not indistinct:
        return IDENTIFIABLE
    if (
        se >= SE_NOT_IDENTIFIABLE
        or bias >= BIAS_NOT_IDENTIFIABLE
        or (indistinct and se >= SE_IDENTIFIABLE)
        or max(tenth, tenfold) < sigma
    ):
        return NOT_IDENTIFIABLE
    return WEAK


def _factor(log_shift: float) -> str:
    """A worst-case shift in words: 'up to a factor 2.7', or 'more than a factor 100'."""
    f = float(np.exp(min(log_shift, 50.0)))
    return f"up to a factor {f:.2g}" if f < 100 else "more than a factor 100"


def _percent(rel: float) -> str:
    return f"{rel:.0%}" if rel >= 0.01 else "1% or better"
