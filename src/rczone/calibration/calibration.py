"""The calibration: a fit from the model's values, its fitted model and its checks.

This is the path shared by ``rczone fit``, the demo and batch calibration: fit from the model's
values and validate the fitted model open loop. The network is never modified; the fitted values
live in a new :class:`~rczone.models.zone.ZoneModel`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rczone.calibration.bands import calibrate_band
from rczone.calibration.dataset import ModelLike, PreparedData, as_model, prepare
from rczone.data.excitation import input_excitation
from rczone.estimation import Dataset, FitResult, fit
from rczone.estimation.initial import INITIAL_STATE_PRIOR_K, estimate_initial_state
from rczone.estimation.methods import method_of
from rczone.estimation.settings import FitSettings
from rczone.models import ZoneModel
from rczone.models.plausibility import Plausibility, operating_flow, plausibility
from rczone.network.stochastic import (
    INITIAL_STATE,
    initial_spread_name,
    is_noise_name,
    kind_of,
    measurement_noise_names,
)
from rczone.postfit.evidence import HorizonScores, held_out_evidence
from rczone.postfit.innovations import (
    ResidualAnalysis,
    innovation_analysis,
    ljung_box_lags,
    open_loop_analysis,
)
from rczone.postfit.openloop import OpenLoopError, ResidualTest, ljung_box, open_loop_error, per_output_errors
from rczone.postfit.robust import robust_errors, robust_lines
from rczone.results import Result
from rczone.results.accessors import FitAccessors
from rczone.results.verdict import EXIT_UNTRUSTED, Verdict, dropped_samples, verdict_of

#: What a calibration with pending checks makes on their first read (:attr:`Calibration.pending`).
_DEFERRED = ("checks", "identifiability", "verdict")


def stamped(model: ZoneModel, verdict: Verdict) -> ZoneModel:
    """``model`` whose provenance records ``verdict`` (trustworthy, and the reasons if not)."""
    import dataclasses

    provenance = {**model.provenance, "trustworthy": verdict.trustworthy, "flags": list(verdict.reasons)}
    return dataclasses.replace(model, provenance=provenance)


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
        for ML and MAP at :func:`~rczone.estimation.initial.estimate_initial_state` (the
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
    holdout : HorizonScores or None
        The scores on data held out of the fit (``--holdout``,
        :func:`rczone.workflow.holdout.score_held_out`); None without a held-out part.
    data_warnings : tuple of str
        The data's signals outside their plausible range (``Dataset.warnings``: degF read as
        degC, ...); each flags the fit.
    robust : RobustErrors or None
        Sandwich standard errors of an ML fit (:mod:`rczone.postfit.robust`); the verdict
        reads them when the innovations are not white.
    evidence : HeldOutEvidence or None
        The held-out checks of ``--holdout`` (:mod:`rczone.postfit.evidence`), set by
        :func:`rczone.calibration.calibration.with_holdout`; they enter the verdict.
    excitation : Excitation or None
        Whether the inputs were excited apart (:mod:`rczone.data.excitation`); collinear inputs
        are named in the verdict's notes.
    verdict : Verdict
        The one verdict (:func:`rczone.results.verdict.verdict_of`), computed at construction, or
        with the checks when they are pending.
    pending : callable, optional
        The post-fit checks still to make: called once with the calibration, it returns
        ``(checks, identifiability)``. Until then ``checks``, ``identifiability`` and ``verdict``
        are not computed; the first read of any of them (``summary()``, ``to_dict()`` and the
        report read them) makes all three, as statsmodels computes ``bse`` on first access, and
        the fitted model's provenance then records the verdict (:func:`rczone.fit`; issue 34).
    data : PreparedData or None
        The data the fit was made on (:func:`~rczone.calibration.dataset.prepare`: the frame and
        its data set, the longest complete stretch in SI units), which the checks after the fit
        are handed instead of the frame, so that they do not build it again.
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
    holdout: Any = None
    data_warnings: tuple[str, ...] = ()
    robust: Any = None
    evidence: Any = None
    excitation: Any = None
    verdict: Verdict = field(init=False)
    pending: Any = field(default=None, compare=False)
    data: PreparedData | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.pending is None:
            self._judge()

    def __getattribute__(self, name: str) -> Any:
        """A deferred attribute (:data:`_DEFERRED`) with the pending checks made first, once."""
        if name in _DEFERRED and object.__getattribute__(self, "__dict__").get("pending") is not None:
            object.__getattribute__(self, "_make_pending")()
        return object.__getattribute__(self, name)

    def _make_pending(self) -> None:
        """Make the pending checks, the verdict from them, and record it in the model's provenance."""
        checks, diag = self.pending(self)
        object.__setattr__(self, "checks", checks)
        object.__setattr__(self, "identifiability", diag)
        object.__setattr__(self, "pending", None)
        self._judge()
        object.__setattr__(self, "model", stamped(self.model, self.verdict))

    def _judge(self) -> None:
        """Set :attr:`verdict` from the fit and the checks made."""
        white = self.innovations.white if self.innovations is not None else None
        verdict = verdict_of(
            self.result,
            self.identifiability,
            self.checks,
            data=self.data_warnings,
            data_used=self.model.provenance.get("stretch"),
            notes=self._evaluation_note(),
            robust=self.robust,
            white=white,
            evidence=self.evidence,
            excitation=self.excitation,
        )
        object.__setattr__(self, "verdict", verdict)

    def _evaluation_note(self) -> tuple[str, ...]:
        """A note when every R, C and gain was held: the fit estimated noise levels only (issue 39)."""
        if any(n in self.model.network.parameters for n in self.result.parameters):
            return ()
        return (
            "every R, C and gain was held (fixed): this is an evaluation of the model at its values, with"
            " only its noise levels and initial states estimated",
        )

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
        if stretch.get("samples", 0) < stretch.get("of", 0) and not dropped_samples(stretch):
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
        lines += robust_lines(self.robust, self.result)
        lines += self.excitation.summary_lines() if self.excitation is not None else []
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
        if self.holdout is not None:
            lines += self.holdout.summary_lines()
        if self.evidence is not None:
            lines.append(verdict_line(self))
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
            robust_std_errors=self.robust.to_dict() if self.robust is not None else None,
            excitation=self.excitation.to_dict() if self.excitation is not None else None,
            trustworthy=self.verdict.trustworthy,
            verdict=self.verdict.to_dict(),
            exit_code=self.exit_code,
        )
        if self.holdout is not None:
            payload["holdout"] = self.holdout.to_dict()
        return payload


def calibrate(
    model: ModelLike,
    frame: pd.DataFrame,
    settings: FitSettings | None = None,
    *,
    provenance: Mapping[str, object] | None = None,
    uncertainty: bool = True,
    analyses: bool = True,
    progress: Any = None,
    **overrides: Any,
) -> Calibration:
    """Fit ``model`` to ``frame`` with ``settings`` and check the fitted model open loop.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
        A built-in name, a model file, a saved model (its values are the start) or a network.
    frame : DataFrame or PreparedData
        ``time`` (s) or a DatetimeIndex, and a column per model input and output (by name; the
        model's conventions fill inputs the data lack); or the data set an entry point prepared
        (:func:`~rczone.calibration.dataset.prepare`), fitted as it is.
    settings : FitSettings, optional
        How to fit (:class:`~rczone.estimation.settings.FitSettings`), carried whole to the method;
        default ``FitSettings()`` (ML, the global search), as ``rczone fit``. Its ``constants`` are
        the inputs held constant instead of read from the frame, its ``fixed`` values with None
        keep the model's value.
    provenance : mapping, optional
        Added to the fitted model's provenance.
    uncertainty : bool
        Standard errors from the Hessian.
    analyses : bool
        Make the analyses a reader of the fit looks at: the whiteness of the innovations and of the
        open-loop error (:attr:`Calibration.innovations`, :attr:`Calibration.open_loop_residuals`),
        the band's calibration and the ARX baselines saved with the fitted model, and the
        plausibility of the estimates. False (batch calibration, which stores the estimates and the
        open-loop errors only) skips them: the fit, its standard errors and the open-loop check
        are the same, the calibration's analyses are None.
    progress : object, optional
        Told how far the fit is (:func:`rczone.estimation.fit.fit`); None: nothing.
    **overrides
        Fields of :class:`~rczone.estimation.settings.FitSettings` replacing those of ``settings``
        (``method="ls"``, ``free=[...]``, ``n_starts=3``, ...).

    Returns
    -------
    Calibration
    """
    settings = FitSettings.of(settings, **overrides)
    constants = settings.constants or None
    zm = as_model(model)
    net = zm.network
    prepared = prepare(zm, frame, constants)
    data, ignored, stretch = prepared.dataset, prepared.ignored, prepared.stretch
    used = zm.constants_used(prepared.frame, prepared.constants)
    free = settings.free_for(net)
    start = {k: v for k, v in {**zm.theta, **zm.noise}.items() if k in free}
    held = {k: v for k, v in zm.theta.items() if k not in free}
    known = {**zm.theta, **zm.noise}
    held.update({k: (known.get(k) if v is None else v) for k, v in settings.fixed.items()})
    res = fit(
        net,
        data,
        free,
        settings=settings,
        uncertainty=uncertainty,
        start=start,
        fixed={k: v for k, v in held.items() if v is not None},
        progress=progress,
    )
    values = {**res.fixed, **res.estimates}
    theta = {k: v for k, v in values.items() if k in net.parameters and not net.parameters[k].is_tied}
    kind = method_of(settings.method)
    noise = {k: v for k, v in values.items() if is_noise_name(k)} if kind.stochastic else {}
    initial = {k: v for k, v in values.items() if kind_of(k) == INITIAL_STATE}
    band = calibrate_band(net, values, data, res.hold) if kind.stochastic and analyses else None
    fitted = zm.with_values(
        theta,
        noise,
        method=settings.method,
        optimizer=settings.optimizer,
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
        hold=settings.hold,
        **({"method_options": res.options} if res.options else {}),
        **({"ignored_channels": list(ignored)} if ignored else {}),
        **dict(provenance or {}),
    )
    if kind.stochastic:  # as LS estimates them: the unmeasured nodes start where the data say
        initial = estimated_start(fitted, values, data, has_noise=True).values
    ol = open_loop_error(net, {**theta, **initial}, data, settings.hold)
    n_lags = ljung_box_lags(int(np.isfinite(ol.error[:, 0]).sum()))  # lags of what is measured
    inn = olr = plaus = None
    if analyses and np.isfinite(data.y).sum(axis=0).min() >= MIN_ANALYSIS_SAMPLES:
        olr = open_loop_analysis(ol.error, data)
        if kind.stochastic:
            inn = innovation_analysis(net, values, data, res.hold)
    if analyses:
        plaus = plausibility(fitted, zm, flow=operating_flow(data.m, net.flow_names))
    robust = robust_errors(net, res, data) if analyses and kind.stochastic else None  # issue 38
    signals = (np.column_stack([data.u, data.m]), (*data.input_names, *data.flow_names))
    excitation = input_excitation(*signals) if analyses else None  # issue 38
    return Calibration(
        res,
        fitted,
        ol,
        ljung_box(ol.error[:, 0], n_lags=n_lags),
        inn,
        olr,
        plausibility=plaus,
        data_warnings=data.warnings,
        robust=robust,
        excitation=excitation,
        data=prepared,
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


def with_holdout(cal: Calibration, scores: HorizonScores) -> Calibration:
    """``cal`` with the held-out evidence of ``scores`` in its verdict (and its fitted model's provenance).

    Parameters
    ----------
    cal : Calibration
        The fit on the calibration part.
    scores : HorizonScores
        Its scores on the held-out part.

    Returns
    -------
    Calibration
        A new calibration; :attr:`~rczone.calibration.Calibration.verdict` weighs the evidence.
    """
    checked = dataclasses.replace(cal, evidence=held_out_evidence(scores, cal.innovations))
    return dataclasses.replace(checked, model=stamped(checked.model, checked.verdict))


def verdict_fit(cal: Calibration) -> FitResult:
    """The fit whose standard errors the verdict reads: the robust ones when the innovations are not white.

    Fits to other data are compared by their standard errors
    (:func:`rczone.postfit.profiles.compare_fits`); with a misspecified model the Hessian's are
    too small and identical houses "disagree" (issue 38).

    Parameters
    ----------
    cal : Calibration

    Returns
    -------
    FitResult
    """
    if cal.robust is None or cal.innovations is None or cal.innovations.white:
        return cal.result
    params = {
        n: e._replace(std_error=cal.robust.std_errors.get(n, e.std_error))
        for n, e in cal.result.parameters.items()
    }
    return dataclasses.replace(cal.result, parameters=params)


def verdict_line(cal: Calibration) -> str:
    """The last line of ``rczone fit --holdout``: the verdict with the held-out evidence, naming what failed."""
    v = cal.verdict
    if v.trustworthy:
        return "[green]verdict:[/] trustworthy on " + ", ".join(v.checked)
    failed = list((v.held_out or {}).get("failed") or [])
    what = f"; held out, failed: {', '.join(failed)}" if failed else ""
    return f"[red]verdict: flagged[/] (exit code {cal.exit_code}), {len(v.reasons)} reason(s){what}"
