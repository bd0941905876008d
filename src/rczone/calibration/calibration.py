"""The calibration: a fit from the model's values, its fitted model and its checks.

This is the path shared by ``rczone fit``, the demo and batch calibration: fit from the model's
values and validate the fitted model open loop. The network is never modified; the fitted values
live in a new :class:`~rczone.models.zone.ZoneModel`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rczone.calibration.bands import calibrate_band
from rczone.calibration.dataset import (
    ModelLike,
    as_model,
    dataset,
    frame_from,
    ignored_channels,
)
from rczone.estimation import Dataset, FitResult, fit
from rczone.estimation.fit import default_free
from rczone.estimation.innovations import (
    ResidualAnalysis,
    innovation_analysis,
    ljung_box_lags,
    open_loop_analysis,
)
from rczone.estimation.methods import DEFAULT_METHOD, method_of
from rczone.estimation.openloop import (
    INITIAL_STATE_PRIOR_K,
    OpenLoopError,
    ResidualTest,
    estimate_initial_state,
    ljung_box,
    open_loop_error,
    per_output_errors,
)
from rczone.estimation.sampling import SamplerSettings
from rczone.models import ZoneModel
from rczone.models.plausibility import Plausibility, operating_flow, plausibility
from rczone.network.stochastic import (
    INITIAL_STATE,
    initial_spread_name,
    is_noise_name,
    kind_of,
    measurement_noise_names,
)
from rczone.results import Result
from rczone.results.accessors import FitAccessors
from rczone.results.verdict import EXIT_UNTRUSTED, Verdict, verdict_of


@dataclass(frozen=True, eq=False, repr=False)
class Calibration(FitAccessors, Result):
    """A fit, its open-loop check on the calibration data, the checks after it and one verdict.

    statsmodels' accessors are at the top (:class:`rczone.results.accessors.FitAccessors`):
    ``params``, ``bse``, ``cov_params()``, ``conf_int(alpha)``, ``tvalues``, ``llf``, ``aic``,
    ``bic``, ``nobs``, a labelled ``correlation``, and :meth:`get_prediction` / :meth:`forecast`.

    Attributes
    ----------
    result : FitResult
        The fit.
    model : ZoneModel
        The fitted model (structure and conventions of the input model, the estimates as values;
        its provenance names the data and the model fitted).
    open_loop : OpenLoopError
        Open-loop simulation of the fitted model on the calibration data. The unmeasured nodes
        start where the data say: at the initial state an LS fit estimates with the parameters, and
        for ML and MAP at :func:`~rczone.estimation.openloop.estimate_initial_state` (the
        filter itself needs no estimate).
    residuals : ResidualTest
        Whiteness of the open-loop error of the first output (not expected to be white; see the
        innovations for ML, and :attr:`open_loop_residuals` for every output).
    innovations : ResidualAnalysis or None
        Whiteness of the one-step innovations (ML and MAP fits; None for LS or too few samples).
    open_loop_residuals : ResidualAnalysis or None
        The same statistics on the open-loop error, labelled as such.
    checks : dict or None
        JSON-ready post-fit checks (profiles, estimates at bounds or far from construction, fits to
        other data and their disagreements, predictions of other data;
        :func:`rczone.workflow.checks.check_fit`); None when not made.
    identifiability : IdentifiabilityReport or None
        The identifiability analysis at the estimates; None when not made.
    plausibility : Plausibility or None
        UA, time constants and solar aperture of the fitted model against the model's values
        before the fit, with warnings (:mod:`rczone.models.plausibility`); None when not made.
    data_warnings : tuple of str
        The data's signals outside their plausible range (``Dataset.warnings``: degF read as
        degC, ...); each flags the fit.
    verdict : Verdict
        The one verdict (:func:`rczone.results.verdict.verdict_of`), computed at construction.
    """

    result: FitResult
    model: ZoneModel
    open_loop: OpenLoopError
    residuals: ResidualTest
    innovations: ResidualAnalysis | None = None
    open_loop_residuals: ResidualAnalysis | None = None
    checks: dict | None = None
    identifiability: Any = None
    plausibility: Plausibility | None = None
    data_warnings: tuple[str, ...] = ()
    verdict: Verdict = field(init=False)

    def __post_init__(self) -> None:
        verdict = verdict_of(self.result, self.identifiability, self.checks, data=self.data_warnings)
        object.__setattr__(self, "verdict", verdict)

    @property
    def data_label(self) -> str:
        """The data's name, as the provenance records it."""
        return str(self.model.provenance.get("data", "data"))

    @property
    def model_label(self) -> str:
        """The model's name, as the provenance records it."""
        return str(self.model.provenance.get("model", self.model.label))

    @property
    def exit_code(self) -> int:
        """0 for a trustworthy fit, :data:`~rczone.results.verdict.EXIT_UNTRUSTED` for a flagged one."""
        return 0 if self.verdict.trustworthy else EXIT_UNTRUSTED

    def get_prediction(self, data: pd.DataFrame, *, steps: int | None = None, **options):
        """The fitted model's prediction of ``data`` (:func:`rczone.calibration.prediction`).

        Parameters
        ----------
        data : DataFrame
            The inputs (and measurements, to score) of the period to predict, in SI units.
        steps : int, optional
            Steps ahead from the Kalman filter's state; default open loop.
        **options
            The keywords of :func:`rczone.calibration.prediction` (``constants``, ``hold`` ...).

        Returns
        -------
        Prediction
            With ``summary_frame(alpha)`` (statsmodels' columns, a band at any level).
        """
        from rczone.calibration.prediction import prediction

        return prediction(self.model, data, steps=steps, label=options.pop("label", "data"), **options)

    def forecast(self, steps: int, data: pd.DataFrame) -> pd.DataFrame:
        """Each sample of ``data`` predicted ``steps`` ahead, one column per output.

        statsmodels' ``forecast(steps)`` continues a series past its end; a zone's temperature
        depends on inputs that must be given, so ``data`` holds them (and the measurements the
        Kalman filter runs on up to ``steps`` samples before each prediction).

        Parameters
        ----------
        steps : int
            Steps ahead (a model fitted by ML or MAP, which has noise levels).
        data : DataFrame
            Inputs and measurements, SI units.

        Returns
        -------
        DataFrame
            One column per output, indexed by the data's time stamps.
        """
        return self.get_prediction(data, steps=steps).predicted_mean

    def to_frame(self) -> pd.DataFrame:
        """The parameter table (:meth:`FitResult.to_frame`)."""
        return self.result.to_frame()

    def output_errors(self) -> list[tuple[str, float, float]]:
        """``(output, open-loop RMSE, largest error)`` of every measured output, K (missing samples skipped)."""
        rmse, worst = per_output_errors(self.open_loop.error)
        return [
            (o, float(r), float(w)) for o, r, w in zip(self.model.network.outputs, rmse, worst, strict=True)
        ]

    def _repr_line(self) -> str:
        state = "trustworthy" if self.verdict.trustworthy else "flagged"
        return (
            f"{self.model_label} fitted to {self.data_label} by {self.result.method.upper()},"
            f" {self.result.n_params} parameters, {state}"
        )

    def summary_lines(self) -> list:
        """What ``rczone fit`` prints, in order (rich markup)."""
        from rczone.results.fit_text import esc, parameter_table, residual_lines, search_line

        r = self.result
        title = f"{esc(self.model_label)} fitted to {esc(self.data_label)} by {r.method.upper()}"
        from rczone.models.library import is_family_name

        generic = is_family_name(self.model_label)  # generic starting values, not construction data
        lines: list = [*self.header_lines(), parameter_table(r, title, generic=generic), search_line(r)]
        # an LS fit's own RMSE is the open-loop one: said once (issue 22, defect 8)
        own = "" if r.rmse_kind == "open-loop" else f" {r.rmse_kind} RMSE {r.rmse_K:.3f} K;"
        lines.append(
            f"open-loop RMSE {self.open_loop.rmse_K:.3f} K, max {self.open_loop.max_abs_K:.3f} K;{own}"
            f" {r.n_evals} evaluations"
        )
        if self.plausibility is not None:
            lines.append(esc(self.plausibility.line()))
            lines += [f"[yellow]implausible:[/] {esc(w)}" for w in self.plausibility.warnings]
        stretch = self.model.provenance.get("stretch") or {}
        if stretch.get("samples", 0) < stretch.get("of", 0):
            lines.append(
                f"[yellow]note:[/] fitted on {stretch['samples']} of {stretch['of']} samples"
                f" ({stretch['fraction']:.0%}), the longest stretch where every input is known"
            )
        per_output = self.output_errors()
        if len(per_output) > 1:
            lines.append(
                "open loop per output: "
                + "; ".join(f"{esc(o)} RMSE {rmse:.3f} K, max {worst:.3f} K" for o, rmse, worst in per_output)
            )
        lines += residual_lines(self.innovations or self.open_loop_residuals)
        used = self.model.provenance.get("constants") or {}
        if used:
            lines.append("held constant: " + ", ".join(f"{esc(k)} = {v:g}" for k, v in used.items()))
        lines += [f"note: {esc(note)}" for note in (*r.notes, *self.verdict.notes)]
        lines += [f"[yellow]warning:[/] {esc(reason)}" for reason in self.verdict.reasons]
        if not self.verdict.trustworthy:
            lines.append(
                f"[red]result flagged[/] (exit code {EXIT_UNTRUSTED}): do not use these estimates without"
                " checking the warnings above"
            )
        return lines

    def to_dict(self) -> dict:
        """What ``rczone fit --json`` writes: the fit, its errors, residuals, checks and verdict."""
        r = self.result
        payload = r.to_dict()
        net = self.model.network
        payload.update(
            data=self.data_label,
            model=self.model_label,
            data_used=dict(self.model.provenance.get("stretch") or {}),
            open_loop_rmse_K=self.open_loop.rmse_K,
            open_loop_max_error_K=self.open_loop.max_abs_K,
            outputs={
                o: {
                    "open_loop_rmse_K": rmse,
                    "open_loop_max_error_K": worst,
                    "sigma_v_K": r.estimates.get(noise),
                }
                for (o, rmse, worst), noise in zip(
                    self.output_errors(), measurement_noise_names(net.outputs), strict=True
                )
            },
            ljung_box_p=self.residuals.p_value,
            innovations=self.innovations.to_dict() if self.innovations is not None else None,
            open_loop_residuals=self.open_loop_residuals.to_dict() if self.open_loop_residuals else None,
            constants=self.model.provenance.get("constants") or {},
            ignored_channels=list(self.model.provenance.get("ignored_channels") or []),
            identifiability={
                k: {"verdict": v.verdict, "reason": v.reason}
                for k, v in self.identifiability.parameters.items()
            }
            if self.identifiability
            else {},
            checks=self.checks,
            plausibility=self.plausibility.to_dict() if self.plausibility is not None else None,
            trustworthy=self.verdict.trustworthy,
            verdict=self.verdict.to_dict(),
            exit_code=self.exit_code,
        )
        return payload


def calibrate(
    model: ModelLike,
    frame: pd.DataFrame,
    method: str = DEFAULT_METHOD,
    free: Sequence[str] | None = None,
    optimizer: str = "auto",
    n_starts: int | None = None,
    seed: int = 0,
    constants: Mapping[str, float] | None = None,
    provenance: Mapping[str, object] | None = None,
    uncertainty: bool = True,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    noise: str = "measured",
    sampler: SamplerSettings | None = None,
    hold: str = "zoh",
    fixed: Mapping[str, float | None] | None = None,
    *,
    analyses: bool = True,
    data: Dataset | None = None,
) -> Calibration:
    """Fit ``model`` to ``frame`` and check the fitted model open loop.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
        A built-in name, a model file, a saved model (its values are the start) or a network.
    frame : DataFrame
        ``time`` (s) or a DatetimeIndex, and a column per model input and output (by name; the
        model's conventions fill inputs the data lack).
    method : {"ml", "ls", "map"}
        A method of :data:`rczone.estimation.methods.REGISTRY`; default ML, as ``rczone fit``.
    free : sequence of str, optional
        Default :func:`rczone.estimation.fit.default_free`.
    optimizer : {"auto", "nelder-mead", "powell", "lbfgs"}
    n_starts : int, optional
        Default: the global search (see :func:`rczone.estimation.fit`); 1: one local search.
    seed : int
        Seed of the global search.
    constants : mapping, optional
        Inputs held constant instead of read from the frame.
    provenance : mapping, optional
        Added to the fitted model's provenance.
    uncertainty : bool
        Standard errors from the Hessian.
    bounds : mapping, optional
        Search bounds overriding the declared ones.
    noise : {"measured", "all"}
        ML and MAP without ``free``: process noise on the measured states or on every state
        (:func:`rczone.estimation.fit.default_free` says why the first is the default).
    sampler : SamplerSettings, optional
        Draws, warm-up and chains of a sampling method (``"mcmc"``); the fitted model keeps
        :data:`~rczone.estimation.posterior.KEPT_DRAWS` posterior draws for :func:`prediction`.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the inputs (:func:`rczone.estimation.fit`); recorded in the
        fitted model's provenance.
    fixed : mapping, optional
        Values of parameters that are not free (a noise level, an initial state, an R or C),
        physical units; None keeps the model's value.
    analyses : bool
        Make the analyses a reader of the fit looks at: the whiteness of the innovations and of the
        open-loop error (:attr:`Calibration.innovations`, :attr:`Calibration.open_loop_residuals`),
        the band's calibration and the ARX baselines saved with the fitted model, and the
        plausibility of the estimates. False (batch calibration, which stores the estimates and the
        open-loop errors only) skips them: the fit, its standard errors and the open-loop check
        are the same, the calibration's analyses are None.
    data : Dataset, optional
        ``dataset(model, frame, constants)`` when the caller has built it already (the methods of
        one zone in a batch share one); default built here.
    """
    zm = as_model(model)
    net = zm.network
    ignored = ignored_channels(frame)
    frame = frame_from(frame)
    used = zm.constants_used(frame, constants)
    data = dataset(zm, frame, constants) if data is None else data
    stretch = {
        "samples": int(data.n_samples),
        "of": len(frame),
        "fraction": data.n_samples / max(len(frame), 1),
        "start_s": float(data.t[0]),
        "end_s": float(data.t[-1]),
    }
    free = tuple(free) if free else default_free(net, method, noise=noise)
    start = {k: v for k, v in {**zm.theta, **zm.noise}.items() if k in free}
    held = {k: v for k, v in zm.theta.items() if k not in free}
    known = {**zm.theta, **zm.noise}
    held.update({k: (known.get(k) if v is None else v) for k, v in (fixed or {}).items()})
    res = fit(
        net,
        data,
        free,
        method=method,
        optimizer=optimizer,
        n_starts=n_starts,
        rng=np.random.default_rng(seed),
        uncertainty=uncertainty,
        start=start,
        fixed={k: v for k, v in held.items() if v is not None},
        bounds=bounds,
        sampler=sampler,
        hold=hold,
    )
    values = {**res.fixed, **res.estimates}
    theta = {k: v for k, v in values.items() if k in net.parameters and not net.parameters[k].is_tied}
    kind = method_of(method)
    noise = {k: v for k, v in values.items() if is_noise_name(k)} if kind.stochastic else {}
    initial = {k: v for k, v in values.items() if kind_of(k) == INITIAL_STATE}
    band = calibrate_band(net, values, data, res.hold) if kind.stochastic and analyses else None
    fitted = zm.with_values(
        theta,
        noise,
        method=method,
        optimizer=optimizer,
        free=list(free),
        objective_value=res.objective_value,
        engine=res.engine,
        rmse_K=res.rmse_K,
        std_errors={k: float(v) for k, v in res.std_errors.items()},
        initial_state=initial,
        constants=used,
        trustworthy=res.trustworthy,
        flags=list(res.flags),
        stretch=stretch,
        covariance=parameter_covariance(res),
        band_scale=band.to_dict() if band is not None else None,
        baselines=baseline_models(data) if analyses else None,
        **({"posterior_draws": posterior_draws(res)} if res.posterior is not None else {}),
        hold=hold,
        **({"ignored_channels": list(ignored)} if ignored else {}),
        **dict(provenance or {}),
    )
    if kind.stochastic:  # as LS estimates them: the unmeasured nodes start where the data say
        initial = estimated_start(fitted, values, data, has_noise=True).values
    ol = open_loop_error(net, {**theta, **initial}, data, hold)
    n_lags = ljung_box_lags(int(np.isfinite(ol.error[:, 0]).sum()))  # lags of what is measured
    inn = olr = plaus = None
    if analyses and np.isfinite(data.y).sum(axis=0).min() >= MIN_ANALYSIS_SAMPLES:
        olr = open_loop_analysis(ol.error, data)
        if kind.stochastic:
            inn = innovation_analysis(net, values, data, res.hold)
    if analyses:
        plaus = plausibility(fitted, zm, flow=operating_flow(data.m, net.flow_names))
    return Calibration(
        res,
        fitted,
        ol,
        ljung_box(ol.error[:, 0], n_lags=n_lags),
        inn,
        olr,
        plausibility=plaus,
        data_warnings=data.warnings,
    )


#: Fewest measured samples (of every output) the residual analysis is made on (fewer: the statistics mean nothing).
MIN_ANALYSIS_SAMPLES = 10


def posterior_draws(res: FitResult) -> dict[str, object]:
    """A sampled fit's kept draws, ``{"names": [...], "values": [[...], ...]}`` (physical units)."""
    kept = res.posterior.kept()
    return {"names": list(res.posterior.names), "values": kept.tolist()}


def parameter_covariance(res: FitResult) -> dict[str, object]:
    """The estimates' covariance in physical units, ``{"names": [...], "matrix": [[...]]}``.

    ``cov_ij = corr_ij se_i se_j`` (the correlation is the same in eta and theta to first order);
    NaN where a standard error is missing (an estimate held at a bound).
    """
    se = np.array([res.std_errors[n] for n in res.names], dtype=float)
    return {"names": list(res.names), "matrix": (res.correlation * np.outer(se, se)).tolist()}


def baseline_models(data: Dataset) -> dict | None:
    """The baselines fitted on the calibration data, saved with the model: ``{"arx": ...}`` (None: too few samples).

    Parameters
    ----------
    data : Dataset
        The calibration data.
    """
    from rczone.errors import DataError
    from rczone.estimation.baselines import fit_arx

    try:
        arx = fit_arx(data.y, data.u)
    except DataError:
        return None
    return {
        "arx": {**arx.to_dict(), "inputs": list(data.input_names), "dt_s": float(np.median(np.diff(data.t)))}
    }


def estimated_start(zm: ZoneModel, values: Mapping[str, float], data: Dataset, has_noise: bool):
    """The unmeasured nodes' initial temperatures for an open-loop prediction on ``data``."""
    net = zm.network
    if has_noise:
        noise = [values[n] for n in measurement_noise_names(net.outputs)]
    else:
        rmse = zm.provenance.get("rmse_K")
        level = float(rmse) if isinstance(rmse, (int, float)) and math.isfinite(rmse) and rmse > 0 else 0.1
        noise = [level] * len(net.outputs)
    noise = [max(float(v), 1e-3) for v in noise]
    prior = {
        s: float(values.get(initial_spread_name(s), INITIAL_STATE_PRIOR_K)) or INITIAL_STATE_PRIOR_K
        for s in net.state_names
    }
    return estimate_initial_state(net, values, data, noise, prior)
