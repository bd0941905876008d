"""The calibration workflow: data frame in, fitted model and its checks out.

This is the path shared by ``rczone fit``, ``rczone predict``, the demo and batch
calibration: pick the model's signals from a frame by name (with the model's own conventions
for inputs the data lack, :class:`~rczone.models.zone.ModelInputs`), fit from the model's values,
and validate the fitted model open loop. The network is never modified; the fitted values live
in a new :class:`~rczone.models.zone.ZoneModel`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rczone.errors import DataError
from rczone.estimation import Dataset, FitResult, fit
from rczone.estimation.fit import default_free
from rczone.estimation.innovations import (
    ResidualAnalysis,
    innovation_analysis,
    ljung_box_lags,
    open_loop_analysis,
)
from rczone.estimation.methods import DEFAULT_METHOD, REGISTRY, method_of
from rczone.estimation.sampling import SamplerSettings
from rczone.estimation.validation import (
    INITIAL_STATE_PRIOR_K,
    InitialStateEstimate,
    OpenLoopError,
    ResidualTest,
    estimate_initial_state,
    ljung_box,
    open_loop_error,
    per_output_errors,
)
from rczone.models import ZoneModel, load_model
from rczone.network import RCNetwork
from rczone.network.stochastic import (
    INITIAL_SPREAD,
    INITIAL_STATE,
    KINDS,
    initial_spread_name,
    is_noise_name,
    kind_of,
    measurement_noise_names,
    target_of,
)
from rczone.results import Result
from rczone.results.verdict import EXIT_UNTRUSTED, Verdict, verdict_of

ModelLike = ZoneModel | RCNetwork | str | os.PathLike


def as_model(model: ModelLike) -> ZoneModel:
    """A :class:`ZoneModel` from a model, a bare network, a built-in name or a model file."""
    return load_model(model)


def frame_from(data: pd.DataFrame) -> pd.DataFrame:
    """A frame with a ``time`` column in seconds; a DatetimeIndex (or datetime ``time``) is converted.

    Every API entry point accepts a frame indexed by time stamps: the time becomes seconds since
    the first sample (only differences of time enter the models).
    """
    if not isinstance(data, pd.DataFrame):
        raise DataError(f"data must be a pandas DataFrame, got {type(data).__name__}")
    if "time" in data:
        t = data["time"]
        if pd.api.types.is_datetime64_any_dtype(t):
            out = data.copy()
            out["time"] = (t - t.iloc[0]).dt.total_seconds()
            return out
        return data
    if isinstance(data.index, pd.DatetimeIndex):
        out = data.reset_index(drop=True)
        out.insert(0, "time", (data.index - data.index[0]).total_seconds().to_numpy())
        return out
    raise DataError(
        "the data have no 'time' column and no DatetimeIndex; give time in seconds or index the"
        " frame by time stamps"
    )


def time_index(frame: pd.DataFrame, t: np.ndarray) -> pd.DatetimeIndex | None:
    """The time stamps of the samples at ``t`` (as :func:`frame_from` made them), in the data's time zone.

    A frame indexed by time stamps (or with a datetime ``time`` column) gives them from its first
    stamp; UTC epoch seconds (a loaded trend log) give UTC stamps, converted to the zone of the
    frame's DatetimeIndex when it has one. None when the data have no clock time.
    """
    index = frame.index if isinstance(frame.index, pd.DatetimeIndex) else None
    t = np.asarray(t, dtype=float)
    if "time" in frame and pd.api.types.is_datetime64_any_dtype(frame["time"]):
        return pd.DatetimeIndex(frame["time"].iloc[0] + pd.to_timedelta(t, unit="s"), name="timestamp")
    if "time" in frame:
        if not (t.size and t[0] > EPOCH_SECONDS):
            return None
        stamps = pd.to_datetime(t, unit="s", utc=True)
        if index is not None and index.tz is not None:
            stamps = stamps.tz_convert(index.tz)
        return pd.DatetimeIndex(stamps, name="timestamp")
    if index is not None and len(index):
        return pd.DatetimeIndex(index[0] + pd.to_timedelta(t, unit="s"), name="timestamp")
    return None


#: Times above this (s) are UTC epoch seconds (after 1973), not seconds from the start of the data.
EPOCH_SECONDS = 1e8


def complete_stretch(u: np.ndarray, m: np.ndarray, y: np.ndarray) -> slice:
    """The longest run of samples where every input and flow is known and some output is measured.

    The model needs its inputs at every sample (an unknown input is not a missing measurement);
    outputs may be missing inside the run. Returns ``slice(start, stop)``.
    """
    ok = np.isfinite(u).all(axis=1) & np.isfinite(m).all(axis=1)
    best, start = (0, 0), None
    for i, good in enumerate(np.r_[ok, False]):
        if good and start is None:
            start = i
        elif not good and start is not None:
            if i - start > best[1] - best[0] and np.isfinite(y[start:i]).any():
                best = (start, i)
            start = None
    return slice(*best)


MIN_USED_FRACTION = 0.5
"""Where inputs have gaps, the longest complete stretch is used only if it holds at least this
fraction of the samples; below, the data are refused (exit code 2) rather than silently cut to a
small part. The fraction used is in the fitted model's provenance (``stretch``) and in fit's JSON."""


def dataset(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    stretch: str = "longest",
) -> Dataset:
    """The model's signals from a frame (see :meth:`ZoneModel.signals`) as an estimation data set.

    Parameters
    ----------
    stretch : {"longest", "all"}
        ``"longest"``: where an input has gaps, the longest stretch without any
        (:func:`complete_stretch`; :func:`dataset_note` says which was used); ``"all"``: every
        sample (an input gap is then an error naming the sample).
    """
    zm = as_model(model)
    t, u, m, y = zm.signals(frame_from(frame), constants)
    if stretch == "longest":
        sl = complete_stretch(u, m, y)
        if sl.stop - sl.start < 2:
            bad = [
                n
                for j, n in enumerate((*zm.network.input_names, *zm.network.flow_names))
                if not np.isfinite(np.column_stack([u, m])[:, j]).any()
            ]
            raise DataError(
                "no stretch of at least 2 samples where every input is known"
                + (f" ({', '.join(bad)} never are)" if bad else "")
                + "; check the column map and the data's gaps"
            )
        if (sl.stop - sl.start) < MIN_USED_FRACTION * len(t):
            raise DataError(
                f"only {sl.stop - sl.start} of {len(t)} samples ({(sl.stop - sl.start) / len(t):.0%}) form the"
                " longest stretch where every input is known, less than the"
                f" {MIN_USED_FRACTION:.0%} rczone uses without asking (rczone.calibrate.MIN_USED_FRACTION):"
                " fill the inputs' gaps, hold a missing input constant (--const), or select the stretch"
                " with the column map's [time] start and end"
            )
        t, u, m, y = t[sl], u[sl], m[sl], y[sl]
    elif stretch != "all":
        raise DataError(f"stretch must be 'longest' or 'all', got {stretch!r}")
    net = zm.network
    return Dataset(t, u, m if m.shape[1] else None, y, net.input_names, net.flow_names, net.outputs)


@dataclass(frozen=True, eq=False, repr=False)
class Calibration(Result):
    """A fit, its open-loop check on the calibration data, the checks after it and one verdict.

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
        for ML and MAP at :func:`~rczone.estimation.validation.estimate_initial_state` (the
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
    verdict: Verdict = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "verdict", verdict_of(self.result, self.identifiability, self.checks))

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
        lines: list = [parameter_table(r, title), search_line(r)]
        lines.append(
            f"open-loop RMSE {self.open_loop.rmse_K:.3f} K, max {self.open_loop.max_abs_K:.3f} K;"
            f" {r.rmse_kind} RMSE {r.rmse_K:.3f} K; {r.n_evals} evaluations"
        )
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
            identifiability={
                k: {"verdict": v.verdict, "reason": v.reason}
                for k, v in self.identifiability.parameters.items()
            }
            if self.identifiability
            else {},
            checks=self.checks,
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
    """
    zm = as_model(model)
    net = zm.network
    frame = frame_from(frame)
    used = zm.constants_used(frame, constants)
    data = dataset(zm, frame, constants)
    stretch = {
        "samples": int(data.n_samples),
        "of": len(frame),
        "fraction": data.n_samples / max(len(frame), 1),
        "start_s": float(data.t[0]),
        "end_s": float(data.t[-1]),
    }
    free = tuple(free) if free else default_free(net, method, noise=noise)
    start = {k: v for k, v in {**zm.theta, **zm.noise}.items() if k in free}
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
        fixed={k: v for k, v in zm.theta.items() if k not in free},
        bounds=bounds,
        sampler=sampler,
    )
    values = {**res.fixed, **res.estimates}
    theta = {k: v for k, v in values.items() if k in net.parameters and not net.parameters[k].is_tied}
    kind = method_of(method)
    noise = {k: v for k, v in values.items() if is_noise_name(k)} if kind.stochastic else {}
    initial = {k: v for k, v in values.items() if kind_of(k) == INITIAL_STATE}
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
        **({"posterior_draws": posterior_draws(res)} if res.posterior is not None else {}),
        **dict(provenance or {}),
    )
    if kind.stochastic:  # as LS estimates them: the unmeasured nodes start where the data say
        initial = _estimated_start(fitted, values, data, has_noise=True).values
    ol = open_loop_error(net, {**theta, **initial}, data)
    n_lags = ljung_box_lags(int(np.isfinite(ol.error[:, 0]).sum()))  # lags of what is measured
    inn = olr = None
    if np.isfinite(data.y).sum(axis=0).min() >= MIN_ANALYSIS_SAMPLES:
        olr = open_loop_analysis(ol.error, data)
        if kind.stochastic:
            inn = innovation_analysis(net, values, data, res.hold)
    return Calibration(res, fitted, ol, ljung_box(ol.error[:, 0], n_lags=n_lags), inn, olr)


#: Fewest measured samples (of every output) the residual analysis is made on (fewer: the statistics mean nothing).
MIN_ANALYSIS_SAMPLES = 10


def parameter_covariance(res: FitResult) -> dict[str, object]:
    """The estimates' covariance in physical units, ``{"names": [...], "matrix": [[...]]}``.

    ``cov_ij = corr_ij se_i se_j`` (the correlation is the same in eta and theta to first order);
    NaN where a standard error is missing (an estimate held at a bound).
    """
    se = np.array([res.std_errors[n] for n in res.names], dtype=float)
    return {"names": list(res.names), "matrix": (res.correlation * np.outer(se, se)).tolist()}


def predict(
    model: ModelLike, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
) -> OpenLoopError:
    """Open-loop simulation of a model on data (the measured states start at their first measurement)."""
    zm = as_model(model)
    data = dataset(zm, frame, constants)
    return open_loop_error(zm.network, dict(zm.theta), data)


@dataclass(frozen=True, eq=False, repr=False)
class Prediction(Result):
    """An open-loop or k-step-ahead prediction with a band of plus or minus two standard deviations.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time, s (as in the data: UTC epoch seconds for a loaded trend log).
    measured, predicted, sd : ndarray, shape (N, ny)
        ``sd`` is the total: ``sqrt(sd_noise^2 + sd_parameters^2)``.
    outputs : tuple of str
    band_source : str
        Where the standard deviation comes from, in words.
    sd_noise, sd_parameters : ndarray, shape (N, ny), optional
        The parts from the noise (or the fit's RMSE) and from the estimates' covariance (NaN: none).
    steps : int, optional
        Steps ahead; None for open loop.
    initial_state : InitialStateEstimate, optional
        Open loop: the unmeasured nodes' initial temperatures estimated from the data (None when
        they start at the steady state).
    index : DatetimeIndex, optional
        The samples' time stamps in the data's time zone (None when the data have no clock time).
    model_label, data_label : str
        Names of the model and the data, for titles.
    lower, upper : ndarray, shape (N, ny), optional
        A posterior predictive band (a model fitted by sampling:
        :func:`~rczone.estimation.forecast.posterior_band`), of the probability of plus or minus two
        standard deviations; None: the band is ``predicted -+ 2 sd``.
    """

    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    sd: np.ndarray
    outputs: tuple[str, ...]
    band_source: str
    sd_noise: np.ndarray | None = None
    sd_parameters: np.ndarray | None = None
    steps: int | None = None
    initial_state: InitialStateEstimate | None = None
    index: pd.DatetimeIndex | None = None
    model_label: str = "model"
    data_label: str = "data"
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None

    @property
    def band(self) -> tuple[np.ndarray, np.ndarray]:
        """The band's lower and upper ends, shape (N, ny) each."""
        if self.lower is not None and self.upper is not None:
            return self.lower, self.upper
        return self.predicted - 2 * self.sd, self.predicted + 2 * self.sd

    @property
    def horizon(self) -> str:
        """``"open loop"`` or ``"k steps ahead"``, in words."""
        return "open loop" if self.steps is None else f"{self.steps} step{'s' * (self.steps != 1)} ahead"

    @property
    def error(self) -> np.ndarray:
        return self.measured - self.predicted

    @property
    def rmse_K(self) -> np.ndarray:
        """Per output, K (NaN where nothing is measured)."""
        return per_output_errors(self.error)[0]

    @property
    def max_abs_K(self) -> np.ndarray:
        """Per output, K (NaN where nothing is measured)."""
        return per_output_errors(self.error)[1]

    @property
    def coverage(self) -> np.ndarray:
        """Fraction of measured samples inside the band, per output (NaN without a band)."""
        lo, hi = self.band
        ok = np.isfinite(self.measured) & np.isfinite(lo) & np.isfinite(hi)
        inside = (self.measured >= lo) & (self.measured <= hi) & ok
        return np.where(ok.sum(axis=0) > 0, inside.sum(axis=0) / np.maximum(ok.sum(axis=0), 1), np.nan)

    def _columns(self) -> dict[str, np.ndarray]:
        cols: dict[str, np.ndarray] = {}
        lo, hi = self.band
        for j, o in enumerate(self.outputs):
            cols[f"{o}_measured"] = self.measured[:, j]
            cols[f"{o}_predicted"] = self.predicted[:, j]
            cols[f"{o}_lower"] = lo[:, j]
            cols[f"{o}_upper"] = hi[:, j]
            if self.sd_noise is not None:
                cols[f"{o}_sd_noise"] = self.sd_noise[:, j]
            if self.sd_parameters is not None:
                cols[f"{o}_sd_parameters"] = self.sd_parameters[:, j]
        return cols

    def to_frame(self) -> pd.DataFrame:
        """Per output measured, predicted, lower and upper (2 sigma), indexed by the data's time stamps.

        Without clock time (seconds from the start), a ``time`` column in seconds instead.
        """
        if self.index is not None:
            return pd.DataFrame(self._columns(), index=self.index)
        return pd.DataFrame({"time": self.t, **self._columns()})

    def series_frame(self) -> pd.DataFrame:
        """The layout of the series file: ``time`` (s), ``timestamp_utc`` for epoch times, then the columns."""
        cols: dict[str, np.ndarray] = {"time": self.t}
        if self.t.size and self.t[0] > EPOCH_SECONDS:  # epoch seconds: also a readable UTC time stamp
            cols["timestamp_utc"] = pd.to_datetime(self.t, unit="s", utc=True).strftime("%Y-%m-%dT%H:%M:%SZ")
        return pd.DataFrame({**cols, **self._columns()})

    def _repr_line(self) -> str:
        rmse = ", ".join(f"{o} RMSE {v:.3f} K" for o, v in zip(self.outputs, self.rmse_K))
        return f"{self.model_label} on {self.data_label}, {self.horizon}, {len(self.t)} samples, {rmse}"

    def summary_lines(self) -> list:
        """What ``rczone predict`` prints (before the files it writes)."""
        from rczone.results.fit_text import esc

        lines = []
        start = self.initial_state
        if start is not None and start.sd:
            lines.append(
                "initial temperatures of the unmeasured nodes, estimated from the data (steady state for the"
                " first sample in brackets): "
                + ", ".join(
                    f"{esc(target_of(k))} {start.values[k]:.2f} ({start.steady[k]:.2f}) ± {sd:.2f} K"
                    for k, sd in start.sd.items()
                )
            )
        for j, o in enumerate(self.outputs):
            lines.append(
                f"{esc(self.data_label)}: {esc(o)} {self.horizon} RMSE {self.rmse_K[j]:.3f} K, max error"
                f" {self.max_abs_K[j]:.3f} K; {self.coverage[j]:.0%} of the measurements inside the 2-sigma band"
                f" ({esc(self.band_source)})"
            )
        return lines

    def to_dict(self) -> dict:
        """What ``rczone predict --json`` writes."""
        start = self.initial_state
        one = len(self.outputs) == 1
        return {
            "model": self.model_label,
            "data": self.data_label,
            "rmse_K": float(self.rmse_K[0]) if one else dict(zip(self.outputs, map(float, self.rmse_K))),
            "max_error_K": float(self.max_abs_K[0])
            if one
            else dict(zip(self.outputs, map(float, self.max_abs_K))),
            "band": self.band_source,
            "horizon": self.horizon,
            "steps": self.steps,
            "initial_state": {
                target_of(k): {
                    "estimate_degC": v,
                    "steady_degC": start.steady[k],
                    "sd_K": start.sd[k],
                }
                for k, v in start.values.items()
                if k in start.sd
            }
            if start is not None
            else None,
            "coverage_2sigma": dict(zip(self.outputs, map(float, self.coverage))),
            "mean_sd_K": {
                part: {o: float(np.nanmean(a[:, j])) for j, o in enumerate(self.outputs)}
                for part, a in (("noise", self.sd_noise), ("estimates", self.sd_parameters))
                if a is not None and np.isfinite(a).any()
            },
        }

    def write(self, path: str | os.PathLike) -> None:
        """Write :meth:`series_frame` as ``.csv`` or ``.parquet`` (atomically)."""
        import io

        from rczone.atomic import write_bytes_atomic, write_text_atomic

        p = os.fspath(path)
        low = p.lower()
        if low.endswith(".csv"):
            write_text_atomic(p, self.series_frame().to_csv(index=False))
        elif low.endswith((".parquet", ".pq")):
            buf = io.BytesIO()
            self.series_frame().to_parquet(buf, index=False)
            write_bytes_atomic(p, buf.getvalue())
        else:
            raise DataError(f"the series file must end in .csv or .parquet, got {p!r}")


def prediction(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    steps: int | None = None,
    parameters: bool = True,
    initial_state: str = "estimated",
    label: str = "data",
) -> Prediction:
    """Open-loop (or ``steps``-ahead) prediction of ``model`` on data with a two-sigma band.

    The band has two parts (:mod:`rczone.estimation.forecast`):

    * the noise: from the model's noise levels when it has them (a likelihood fit: process noise
      accumulated along the prediction plus measurement noise), else, open loop, from the
      open-loop RMSE of the least-squares fit that produced the model (constant), else none;
    * the estimates: their covariance saved with a fitted model (``provenance["covariance"]``),
      carried to the prediction by the delta method (``parameters=False`` leaves it out).

    Parameters
    ----------
    steps : int, optional
        Predict ``y[j]`` from the measurements up to ``j - steps`` (Kalman filter; needs the
        model's noise levels). Default: open loop from the first measurement.
    initial_state : {"estimated", "steady"}
        Open loop: where the unmeasured nodes start. ``"estimated"`` (default): their initial
        temperatures estimated from these data around the conditional steady state
        (:func:`~rczone.estimation.validation.estimate_initial_state`, prior standard deviation
        the model's ``sigma_x0`` or 1 K), and the band starts from the estimate's uncertainty;
        ``"steady"``: at the steady state for the first sample's inputs, which shows a slow node's
        unknown start as a bias lasting its time constant.
    label : str
        The data's name, for titles.
    """
    from rczone.estimation.forecast import noise_band, parameter_sd

    zm = as_model(model)
    data = dataset(zm, frame, constants)
    net = zm.network
    values = {**zm.theta, **noise_values(zm)}
    has_noise = any(is_noise_name(k) for k in zm.noise)
    if steps is not None and not has_noise:
        raise DataError(
            f"a {steps}-step prediction needs the model's noise levels; fit the model by ML"
            " (rczone fit --method ml --save-model ...) or predict open loop"
        )
    if initial_state not in INITIAL_STATES:
        raise DataError(f"initial_state must be one of {', '.join(INITIAL_STATES)}, got {initial_state!r}")
    start = None
    if steps is None and initial_state == "estimated":
        start = _estimated_start(zm, values, data, has_noise)
        values.update(start.values)
        if has_noise:
            values.update({initial_spread_name(target_of(k)): v for k, v in start.sd.items()})
    sources = []
    if has_noise:
        y_hat, sd = noise_band(net, values, data, steps)
        sources.append("the model's noise levels")
    else:
        y_hat = open_loop_error(net, {**zm.theta, **values}, data).y_hat
        fitted_by = REGISTRY.get(str(zm.provenance.get("method")))
        rmse = zm.provenance.get("rmse_K") if fitted_by is not None and not fitted_by.stochastic else None
        if isinstance(rmse, (int, float)) and np.isfinite(rmse):
            sd = np.full_like(y_hat, float(rmse))
            sources.append("the open-loop RMSE of the least-squares fit")
        else:
            sd = np.full_like(y_hat, np.nan)
    if not np.all(np.isfinite(y_hat[steps or 0 :])):
        raise DataError("the model's prediction is not finite; its values are not usable on these data")
    sd_par = lower = upper = None
    kept = saved_draws(zm) if parameters else None
    cov = saved_covariance(zm) if parameters and kept is None else None
    if kept is not None:
        from rczone.estimation.forecast import posterior_band

        def band(v: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
            if has_noise:
                return noise_band(net, v, data, steps)
            return open_loop_error(net, v, data).y_hat, sd

        lower, upper, sd_par = posterior_band(band, values, *kept, np.random.default_rng(0))
        sources.append(f"{kept[1].shape[0]} posterior draws")
    if cov is not None:
        names, matrix = cov
        if has_noise:

            def predictor(v: Mapping[str, float]) -> np.ndarray:
                return noise_band(net, v, data, steps)[0]
        else:

            def predictor(v: Mapping[str, float]) -> np.ndarray:
                return open_loop_error(net, v, data).y_hat

        sd_par = parameter_sd(predictor, values, names, matrix)
        sources.append("the estimates' covariance")
    total = sd if sd_par is None else np.sqrt(np.where(np.isfinite(sd), sd**2, 0.0) + sd_par**2)
    source = (
        " and ".join(sources) if sources else "none: the model has no noise levels (fit it by ML for a band)"
    )
    return Prediction(
        data.t,
        data.y,
        y_hat,
        total,
        net.outputs,
        source,
        sd,
        sd_par,
        steps,
        start,
        index=time_index(frame, data.t),
        model_label=zm.label,
        data_label=label,
        lower=lower,
        upper=upper,
    )


#: Where an open-loop prediction starts its unmeasured nodes (:func:`prediction`).
INITIAL_STATES = ("estimated", "steady")


def _estimated_start(zm: ZoneModel, values: Mapping[str, float], data: Dataset, has_noise: bool):
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


def noise_values(zm: ZoneModel) -> dict[str, float]:
    """The model's noise levels completed with the defaults for those it has none of (empty without any)."""
    if not any(is_noise_name(k) for k in zm.noise):
        return {}
    from rczone.estimation.parameters import noise_parameter_names

    values = dict(zm.noise)
    for n in noise_parameter_names(zm.network):
        kind = kind_of(n)
        if n in values or kind == INITIAL_STATE:
            continue
        values[n] = KINDS[INITIAL_SPREAD].default if kind == INITIAL_SPREAD else 0.0
    return values


def posterior_draws(res: FitResult) -> dict[str, object]:
    """A sampled fit's kept draws, ``{"names": [...], "values": [[...], ...]}`` (physical units)."""
    kept = res.posterior.kept()
    return {"names": list(res.posterior.names), "values": kept.tolist()}


def saved_draws(zm: ZoneModel) -> tuple[list[str], np.ndarray] | None:
    """The posterior draws a sampled fit saved with the model, restricted to what moves a prediction.

    As :func:`saved_covariance`: only base parameters and noise levels are kept. None when the
    model has none. A malformed entry (a model file is untrusted) is an error.
    """
    kept = zm.provenance.get("posterior_draws")
    if kept is None:
        return None
    try:
        names = [str(n) for n in kept["names"]]
        matrix = np.array(kept["values"], dtype=float)
        if matrix.ndim != 2 or matrix.shape[1] != len(names) or matrix.shape[0] < 2:
            raise ValueError
        if not np.isfinite(matrix).all():
            raise ValueError
    except (KeyError, TypeError, ValueError):
        raise DataError(
            f"model {zm.label!r}: its saved posterior draws are malformed (expected names and a table of"
            " at least two finite rows, one column per name)"
        ) from None
    known = {*zm.theta, *noise_values(zm)}
    keep = [i for i, n in enumerate(names) if n in known]
    if not keep:
        return None
    return [names[i] for i in keep], matrix[:, keep]


def saved_covariance(zm: ZoneModel) -> tuple[list[str], np.ndarray] | None:
    """The estimates' covariance a fit saved with the model, restricted to what moves a prediction.

    Only the model's base parameters and noise levels are kept (the initial state of the
    calibration data says nothing about other data). None when the model has none, or none of
    its entries is usable. A malformed entry (a model file is untrusted) is an error.
    """
    cov = zm.provenance.get("covariance")
    if cov is None:
        return None
    try:
        names = [str(n) for n in cov["names"]]
        matrix = np.array(
            [[np.nan if v is None else float(v) for v in row] for row in cov["matrix"]], dtype=float
        )
        if matrix.shape != (len(names), len(names)):
            raise ValueError
    except (KeyError, TypeError, ValueError):
        raise DataError(
            f"model {zm.label!r}: its saved covariance is malformed (expected names and a square matrix)"
        ) from None
    known = {*zm.theta, *noise_values(zm)}
    keep = [i for i, n in enumerate(names) if n in known and np.isfinite(matrix[i, i])]
    if not keep:
        return None
    return [names[i] for i in keep], matrix[np.ix_(keep, keep)]
